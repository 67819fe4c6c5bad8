"""The common form of every input design: a dataclass with a ``kind`` and SI parameters.

A design knows which surfaces it moves and gives their time histories on any time vector
(s) as increments to the trim values (rad for surfaces, fraction for throttle). Optional
actuator rate limiting is applied after the ideal shape. Designs are built from plain
dicts (flight-card TOML tables) by ``flightid.scenarios.inputs.input_from_dict``; the
parsing helpers here turn ``amplitude_deg`` and ``rate_limit_deg`` into SI and name the
field that is wrong.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from flightid.channels import CONTROLS
from flightid.units import DEG

# switching times compare as t >= t_switch - _EDGE_TOL, so that a grid built as
# np.arange(n) * dt, whose points differ from k*dt by rounding, still switches on the
# sample that is nominally at t_switch
EDGE_TOL = 1e-9


def rate_limit(t: np.ndarray, u: np.ndarray, rate: float) -> np.ndarray:
    """Actuator rate limiting of a sampled signal ``u`` on times ``t`` (s) to ``rate`` (unit/s).

    The output moves towards the command by at most ``rate * dt`` per sample, so
    ``|diff(y)| / diff(t) <= rate`` holds at every sample (Morelli & Klein 2016, 9.2).
    ``rate <= 0`` means no limit.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s; shape (n,).
    u : numpy.ndarray
        Commanded signal; shape (n,).
    rate : float
        Rate limit, unit/s; <= 0 for none.

    Returns
    -------
    numpy.ndarray
        Rate-limited signal; shape (n,).
    """
    u = np.asarray(u, dtype=float)
    if rate <= 0 or u.size < 2:
        return u.copy()
    steps = np.diff(np.asarray(t, dtype=float)) * rate
    y = np.empty_like(u)
    y[0] = u[0]
    prev = u[0]
    for k in range(1, u.size):
        d = u[k] - prev
        s = steps[k - 1]
        prev = prev + (s if d > s else -s if d < -s else d)
        y[k] = prev
    return y


def check_time(t: np.ndarray) -> np.ndarray:
    """Validate a time vector (s): one-dimensional, finite, non-decreasing.

    Parameters
    ----------
    t : numpy.ndarray
        Time vector, s.

    Returns
    -------
    numpy.ndarray
        ``t`` as a float array.
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"time must be one-dimensional, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("time contains NaN or infinite values")
    if t.size > 1 and np.any(np.diff(t) < 0):
        raise ValueError("time must not decrease")
    return t


@dataclass(kw_only=True)
class InputDesign:
    """Base of all input designs: start time (s) and optional rate limit (rad/s or 1/s)."""

    kind: ClassVar[str] = ""
    start: float = 0.0
    rate_limit: float = dataclasses.field(default=0.0, metadata={"unit": "rad/s"})

    # -- to be provided by each design -----------------------------------------
    def surfaces(self) -> tuple[str, ...]:
        """The control channels this design moves."""
        raise NotImplementedError

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """Ideal (not rate-limited) increments per surface on times ``t`` (s)."""
        raise NotImplementedError

    @property
    def end(self) -> float:
        """Time (s) at which the input is over (the signal is back to zero or held)."""
        raise NotImplementedError

    # -- common ----------------------------------------------------------------
    def signals(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """Increments per surface (rad, throttle fraction) on times ``t`` (s), rate-limited."""
        t = check_time(t)
        return {s: rate_limit(t, u, self.rate_limit) for s, u in self.shapes(t).items()}

    def to_dict(self) -> dict[str, Any]:
        """The design as a plain dict in SI units (inverse of ``input_from_dict``)."""
        d: dict[str, Any] = {"kind": self.kind}
        for f in dataclasses.fields(self):
            if not f.init:
                continue
            v = getattr(self, f.name)
            d[f.metadata.get("alias", f.name)] = list(v) if isinstance(v, tuple) else v
        return d


@dataclass(kw_only=True)
class SingleInput(InputDesign):
    """A design that moves one surface by ``amplitude`` (rad, or fraction for throttle)."""

    surface: str = "de"
    amplitude: float = dataclasses.field(default=0.0, metadata={"unit": "rad"})

    def surfaces(self) -> tuple[str, ...]:
        return (self.surface,)

    def signal(self, t: np.ndarray) -> np.ndarray:
        """The increment of ``surface`` (rad or fraction) on times ``t`` (s)."""
        return self.signals(t)[self.surface]

    def __post_init__(self) -> None:
        check_surface(self.surface, "surface")


def check_surface(name: str, field_name: str) -> None:
    """Raise naming ``field_name`` if ``name`` is not a control channel.

    Parameters
    ----------
    name : str
        Surface name to check.
    field_name : str
        Card field named in the error.
    """
    if name not in CONTROLS:
        raise ValueError(
            f"field {field_name!r}: unknown surface {name!r}; controls are {', '.join(CONTROLS)}"
        )


def require(condition: bool, field_name: str, message: str) -> None:
    """Raise ValueError naming the field if ``condition`` is false.

    Parameters
    ----------
    condition : bool
        The condition that must hold.
    field_name : str
        Card field named in the error.
    message : str
        What is wrong, for the error.
    """
    if not condition:
        raise ValueError(f"field {field_name!r}: {message}")


# -- building designs from dicts ---------------------------------------------------


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ValueError(f"field {where!r} must be a number, got {value!r}")
    if not np.isfinite(value):
        raise ValueError(f"field {where!r} must be finite, got {value!r}")
    return float(value)


def _convert(f: dataclasses.Field, value: Any, where: str, scale: float) -> Any:
    kind = str(f.type).replace(" ", "")
    if kind == "float":
        return _number(value, where) * scale
    if kind == "int":
        v = _number(value, where)
        if v != int(v):
            raise ValueError(f"field {where!r} must be a whole number, got {value!r}")
        return int(v)
    if kind == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"field {where!r} must be true or false, got {value!r}")
        return value
    if kind == "str":
        if not isinstance(value, str):
            raise ValueError(f"field {where!r} must be a string, got {value!r}")
        return value
    if kind.startswith("tuple[str"):
        if isinstance(value, str) or not isinstance(value, list | tuple):
            raise ValueError(f"field {where!r} must be a list of strings, got {value!r}")
        for i, v in enumerate(value):
            if not isinstance(v, str):
                raise ValueError(f"field {where!r}[{i}] must be a string, got {v!r}")
        return tuple(value)
    if kind.startswith("tuple[float"):
        if isinstance(value, str) or not isinstance(value, list | tuple):
            raise ValueError(f"field {where!r} must be a list of numbers, got {value!r}")
        return tuple(_number(v, f"{where}[{i}]") * scale for i, v in enumerate(value))
    raise TypeError(f"internal: field {where!r} has unsupported type {f.type}")


def design_from_dict(cls: type, d: dict[str, Any], context: str = "") -> Any:
    """Build dataclass ``cls`` from ``d``; ``<field>_deg`` gives an angle field in degrees.

    Every error names the offending field (prefixed by ``context``).

    Parameters
    ----------
    cls : type
        The input-design dataclass.
    d : dict[str, Any]
        The card's table; ``kind`` and ``effect`` keys are ignored.
    context : str, optional
        Prefix for field names in error messages.

    Returns
    -------
    Any
        An instance of ``cls``.
    """
    pre = f"{context}." if context else ""
    fields = {f.metadata.get("alias", f.name): f for f in dataclasses.fields(cls) if f.init}
    kwargs: dict[str, Any] = {}
    for key, value in d.items():
        if key in ("kind", "effect"):
            continue
        name, scale = key, 1.0
        if key.endswith("_deg") and key[:-4] in fields:
            name = key[:-4]
            if "rad" not in fields[name].metadata.get("unit", ""):
                raise ValueError(f"field {pre + key!r}: {name} is not an angle; give {name!r}")
            scale = DEG
        if name not in fields:
            what = getattr(cls, "kind", "") or cls.__name__
            raise ValueError(
                f"field {pre + key!r} is not a parameter of {what!r}; "
                f"allowed: {', '.join(sorted(fields))} (angles also as <name>_deg)"
            )
        if fields[name].name in kwargs:
            raise ValueError(
                f"field {pre + name!r} given twice (as {name!r} and {name + '_deg'!r})"
            )
        kwargs[fields[name].name] = _convert(fields[name], value, pre + key, scale)
        if scale != 1.0 and name == "amplitude" and d.get("surface") == "throttle":
            raise ValueError(f"field {pre + key!r}: throttle is a fraction 0..1, give 'amplitude'")
        if name == "amplitude" and d.get("surface") == "throttle" \
                and abs(kwargs["amplitude"]) > 1:
            raise ValueError(f"field {pre + key!r}: a throttle increment of "
                             f"{kwargs['amplitude']:g} cannot be flown: the throttle is a "
                             "fraction 0..1, so an increment lies within -1..1")
    try:
        return cls(**kwargs)
    except TypeError as exc:  # missing required field
        raise ValueError(f"{context or cls.__name__}: {exc}") from None
