"""Flight-test input designs: multi-steps (doublet, 2-1, 2-1-1, 3211, pulse), steps, sweeps.

Every design is a dataclass with a ``kind`` and SI parameters, returning surface increments
(rad, throttle fraction) on a given time vector (s). The registry ``INPUT_KINDS`` and
``input_from_dict`` build them from flight-card tables such as
``{kind = "3211", surface = "de", start = 10, base = 0.5, amplitude_deg = 3}``.
Multisines are in ``multisine``, the hand-flown maneuvers in ``maneuvers``.
``equal_energy`` scales and compares designs at equal energy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from flightid.scenarios.input_design import (
    EDGE_TOL,
    InputDesign,
    SingleInput,
    check_time,
    design_from_dict,
    rate_limit,
    require,
)
from flightid.scenarios.maneuvers import BankToBank, FigureEight, PullUpPushOver, ThrottleCut
from flightid.scenarios.multisine import Harmonics, Multisine, OrthogonalMultisine

__all__ = [
    "INPUT_KINDS",
    "Doublet",
    "InputDesign",
    "Maneuvers",
    "Multistep",
    "Pulse",
    "Step",
    "Sweep",
    "ThreeTwoOneOne",
    "TwoOne",
    "TwoOneOne",
    "input_from_dict",
    "inputs_from_list",
    "rate_limit",
    "total_signals",
]


# -- multi-step inputs -----------------------------------------------------------


@dataclass(kw_only=True)
class Multistep(SingleInput):
    """Pulses of ``widths`` x ``base`` (s) with ``signs``, back to zero after the last.

    Each level holds from the first sample with t >= t_switch (exact to the sample).
    """

    kind: ClassVar[str] = "multistep"
    base: float = 1.0
    widths: tuple[float, ...] = (1.0, 1.0)
    signs: tuple[float, ...] = (1.0, -1.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.base > 0, "base", f"pulse base time must be > 0 s, got {self.base}")
        require(len(self.widths) > 0, "widths", "needs at least one pulse")
        require(all(w > 0 for w in self.widths), "widths", f"must all be > 0, got {self.widths}")
        require(
            len(self.signs) == len(self.widths),
            "signs",
            f"{len(self.signs)} signs for {len(self.widths)} widths",
        )

    def switch_times(self) -> np.ndarray:
        """Times (s) at which the levels start, plus the final return to zero."""
        return self.start + self.base * np.concatenate([[0.0], np.cumsum(self.widths)])

    @property
    def end(self) -> float:
        return float(self.switch_times()[-1])

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        t = check_time(t)
        edges = self.switch_times()
        # index of the level each sample is on: number of edges with t >= edge - tol
        idx = np.searchsorted(edges - EDGE_TOL, t, side="right")
        levels = np.concatenate([[0.0], np.asarray(self.signs, float), [0.0]])
        return {self.surface: self.amplitude * levels[idx]}


@dataclass(kw_only=True)
class _Pattern(SingleInput):
    """Shared code of the fixed multi-step patterns (widths and signs are class constants)."""

    kind: ClassVar[str] = ""
    WIDTHS: ClassVar[tuple[float, ...]] = ()
    SIGNS: ClassVar[tuple[float, ...]] = ()
    base: float = 1.0

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.base > 0, "base", f"pulse base time must be > 0 s, got {self.base}")

    def _steps(self) -> Multistep:
        return Multistep(
            surface=self.surface,
            amplitude=self.amplitude,
            start=self.start,
            base=self.base,
            widths=self.WIDTHS,
            signs=self.SIGNS,
        )

    def switch_times(self) -> np.ndarray:
        """Times (s) at which the levels start, plus the final return to zero."""
        return self._steps().switch_times()

    @property
    def end(self) -> float:
        return self._steps().end

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        return self._steps().shapes(t)


@dataclass(kw_only=True)
class Doublet(_Pattern):
    """Doublet: +1, -1 pulses of ``base`` s each (Morelli & Klein 2016, 9.3)."""

    kind: ClassVar[str] = "doublet"
    WIDTHS: ClassVar[tuple[float, ...]] = (1.0, 1.0)
    SIGNS: ClassVar[tuple[float, ...]] = (1.0, -1.0)


@dataclass(kw_only=True)
class TwoOne(_Pattern):
    """2-1 doublet: +1 for 2 base, -1 for 1 base.

    The Twin Otter input of Batterson & O'Mara (NASA TM-4099, 1989).
    """

    kind: ClassVar[str] = "21"
    WIDTHS: ClassVar[tuple[float, ...]] = (2.0, 1.0)
    SIGNS: ClassVar[tuple[float, ...]] = (1.0, -1.0)


@dataclass(kw_only=True)
class TwoOneOne(_Pattern):
    """2-1-1: +1, -1, +1 for 2, 1, 1 base times (the Twin Otter rudder input, SIDPAC)."""

    kind: ClassVar[str] = "211"
    WIDTHS: ClassVar[tuple[float, ...]] = (2.0, 1.0, 1.0)
    SIGNS: ClassVar[tuple[float, ...]] = (1.0, -1.0, 1.0)


@dataclass(kw_only=True)
class ThreeTwoOneOne(_Pattern):
    """3211: +1, -1, +1, -1 for 3, 2, 1, 1 base times (Koehler; Jategaonkar 2006, 2.5)."""

    kind: ClassVar[str] = "3211"
    WIDTHS: ClassVar[tuple[float, ...]] = (3.0, 2.0, 1.0, 1.0)
    SIGNS: ClassVar[tuple[float, ...]] = (1.0, -1.0, 1.0, -1.0)


@dataclass(kw_only=True)
class Pulse(_Pattern):
    """Single pulse of ``base`` s."""

    kind: ClassVar[str] = "pulse"
    WIDTHS: ClassVar[tuple[float, ...]] = (1.0,)
    SIGNS: ClassVar[tuple[float, ...]] = (1.0,)


@dataclass(kw_only=True)
class Step(SingleInput):
    """Step of ``amplitude`` at ``start``, held for ``duration`` s (0: held to the end)."""

    kind: ClassVar[str] = "step"
    duration: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.duration >= 0, "duration", f"must be >= 0 s, got {self.duration}")

    @property
    def end(self) -> float:
        return self.start + self.duration

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        t = check_time(t)
        on = t >= self.start - EDGE_TOL
        if self.duration > 0:
            on &= t < self.start + self.duration - EDGE_TOL
        return {self.surface: np.where(on, self.amplitude, 0.0)}


# -- frequency sweeps ------------------------------------------------------------


@dataclass(kw_only=True)
class Sweep(SingleInput):
    """Frequency sweep from ``f_start`` to ``f_end`` (Hz) over ``duration`` (s).

    ``law`` "linear": f = f0 + (f1 - f0) tau / T; "log": f = f0 (f1 / f0)^(tau / T)
    (Tischler & Remple 2012, 5.7; Morelli & Klein 2016, 9.4). The phase is the exact
    integral of 2 pi f, so the instantaneous frequency follows the law; ``fade_in`` and
    ``fade_out`` (s) are raised-cosine amplitude envelopes that leave the phase alone.
    """

    kind: ClassVar[str] = "sweep"
    f_start: float = 0.1
    f_end: float = 2.0
    duration: float = 60.0
    law: str = "linear"
    fade_in: float = 0.0
    fade_out: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.f_start > 0, "f_start", f"must be > 0 Hz, got {self.f_start}")
        require(self.f_end > 0, "f_end", f"must be > 0 Hz, got {self.f_end}")
        require(self.duration > 0, "duration", f"must be > 0 s, got {self.duration}")
        require(self.law in ("linear", "log"), "law", f"'linear' or 'log', got {self.law!r}")
        require(self.fade_in >= 0, "fade_in", f"must be >= 0 s, got {self.fade_in}")
        require(self.fade_out >= 0, "fade_out", f"must be >= 0 s, got {self.fade_out}")
        require(
            self.fade_in + self.fade_out <= self.duration,
            "fade_in",
            f"fade_in + fade_out = {self.fade_in + self.fade_out} s exceeds duration "
            f"{self.duration} s",
        )
        if self.law == "log":
            require(self.f_start != self.f_end, "f_end", "a log sweep needs f_end != f_start")

    @property
    def end(self) -> float:
        return self.start + self.duration

    def frequency(self, t: np.ndarray) -> np.ndarray:
        """Instantaneous frequency (Hz) of the law at times ``t`` (s), clipped to the sweep."""
        tau = np.clip(np.asarray(t, float) - self.start, 0.0, self.duration) / self.duration
        if self.law == "linear":
            return self.f_start + (self.f_end - self.f_start) * tau
        return self.f_start * (self.f_end / self.f_start) ** tau

    def phase(self, t: np.ndarray) -> np.ndarray:
        """Phase (rad): 2 pi times the integral of the frequency from ``start``."""
        T = self.duration
        s = np.clip(np.asarray(t, float) - self.start, 0.0, T)
        f0, f1 = self.f_start, self.f_end
        if self.law == "linear":
            return 2 * np.pi * (f0 * s + (f1 - f0) * s**2 / (2 * T))
        k = np.log(f1 / f0)
        return 2 * np.pi * f0 * T / k * np.expm1(k * s / T)

    def envelope(self, t: np.ndarray) -> np.ndarray:
        """Amplitude envelope (0..1): raised-cosine fades, zero outside the sweep."""
        s = np.asarray(t, float) - self.start
        env = ((s >= 0) & (s <= self.duration)).astype(float)
        if self.fade_in > 0:
            m = (s >= 0) & (s < self.fade_in)
            env[m] = 0.5 * (1 - np.cos(np.pi * s[m] / self.fade_in))
        if self.fade_out > 0:
            r = self.duration - s
            m = (r >= 0) & (r < self.fade_out)
            env[m] = 0.5 * (1 - np.cos(np.pi * r[m] / self.fade_out))
        return env

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        t = check_time(t)
        return {self.surface: self.amplitude * self.envelope(t) * np.sin(self.phase(t))}


# -- registry and dicts ------------------------------------------------------------

INPUT_KINDS: dict[str, type[InputDesign]] = {
    c.kind: c
    for c in (
        Doublet,
        TwoOne,
        TwoOneOne,
        ThreeTwoOneOne,
        Pulse,
        Multistep,
        Step,
        Sweep,
        Multisine,
        OrthogonalMultisine,
        Harmonics,
        PullUpPushOver,
        ThrottleCut,
        BankToBank,
        FigureEight,
    )
}


def input_from_dict(d: dict[str, Any], context: str = "") -> InputDesign:
    """Build an input design from a flight-card table; errors name the bad field.

    ``kind`` selects the design (``INPUT_KINDS``); other keys are its parameters in SI,
    or in degrees with a ``_deg`` suffix (``amplitude_deg``, ``rate_limit_deg`` in deg/s).

    Parameters
    ----------
    d : dict[str, Any]
        The card's input table, with a ``kind`` key.
    context : str, optional
        Prefix for field names in error messages, e.g. ``"inputs[0]"``.

    Returns
    -------
    InputDesign
        The input design.
    """
    if not isinstance(d, dict):
        raise ValueError(f"{context or 'input'}: expected a table, got {type(d).__name__}")
    if "kind" not in d:
        raise ValueError(
            f"field {(context + '.' if context else '') + 'kind'!r} is missing; "
            f"one of {', '.join(INPUT_KINDS)}"
        )
    kind = d["kind"]
    if kind not in INPUT_KINDS:
        raise ValueError(
            f"field {(context + '.' if context else '') + 'kind'!r}: unknown input kind "
            f"{kind!r}; known: {', '.join(INPUT_KINDS)}"
        )
    return design_from_dict(INPUT_KINDS[kind], d, context)


def inputs_from_list(items: list[dict[str, Any]]) -> list[InputDesign]:
    """Build several designs (a card's ``[[inputs]]`` array); errors say which entry.

    Parameters
    ----------
    items : list[dict[str, Any]]
        The card's input tables.

    Returns
    -------
    list[InputDesign]
        One design per table, in order.
    """
    return [input_from_dict(d, f"inputs[{i}]") for i, d in enumerate(items)]


def total_signals(designs: list[InputDesign], t: np.ndarray) -> dict[str, np.ndarray]:
    """Sum of the increments of several designs per surface on times ``t`` (s).

    Parameters
    ----------
    designs : list[InputDesign]
        The input designs.
    t : numpy.ndarray
        Sample times, s; shape (n,).

    Returns
    -------
    dict[str, numpy.ndarray]
        Surface name -> summed increment (rad, or fraction for the throttle); shape (n,).
    """
    out: dict[str, np.ndarray] = {}
    for design in designs:
        for s, u in design.signals(t).items():
            out[s] = out[s] + u if s in out else u
    return out


@dataclass(kw_only=True)
class Maneuvers(InputDesign):
    """Several designs flown together as one (a card's ``[[maneuver]]`` list, e.g. aileron
    and rudder multisines at once): their increments summed per surface, each designs'
    own rate limit applied to it; it starts when the first one starts (``start`` is set
    from the parts) and ends when the last one ends; the whole's ``rate_limit`` is unused
    (each part has its own)."""

    kind: ClassVar[str] = "maneuvers"
    parts: tuple[InputDesign, ...] = ()

    def __post_init__(self) -> None:
        require(len(self.parts) >= 1, "maneuver", "needs at least one maneuver")
        self.start = min(d.start for d in self.parts)

    def surfaces(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(s for d in self.parts for s in d.surfaces()))

    def signals(self, t: np.ndarray) -> dict[str, np.ndarray]:
        return total_signals(list(self.parts), check_time(t))

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        return self.signals(t)

    @property
    def end(self) -> float:
        return max(d.end for d in self.parts)
