"""Dispersions of a Monte Carlo study: parameters of catalogue effects drawn anew for each
realization, so that a study covers an aircraft known only to within its tolerances.

A dispersion is written ``EFFECT[OPTION=VALUE,...][.PARAMETER]:WIDTH[:DISTRIBUTION]``:

    mass_scale:0.05                           factor = 1 + N(0, 0.05)
    inertia_scale.iyy:0.1:uniform             iyy = 1 + U(-0.1, 0.1)
    cg_offset.x:0.02                          x = 0 + N(0, 0.02) m
    derivative_delta[derivative=Cm_alpha]:0.05  delta = N(0, 0.05) per rad
    bias[channel=q]:0.001                     a bias N(0, 0.001) rad/s on the q sensor
    scale[channel=alpha]:0.02                 a scale factor 1 + N(0, 0.02) on alpha

The drawn value is the parameter's neutral value (``flightid effects``: where the effect
does nothing) plus a draw: ``normal`` (the default; WIDTH is the standard deviation) or
``uniform`` (WIDTH is the half-width). PARAMETER may be left out when the effect has one
sizing parameter. Airframe effects (``derivative_delta``, ``mass_scale``,
``inertia_scale``, ``cg_offset``, any airframe or actuator entry) are flown in the
augmented aircraft, so the record's truth is the dispersed aircraft's; sensor effects are
put first in the named channel's chain (before noise, filters and quantization). The
draws of realization ``i`` come from their own stream of its seed, so they change neither
the noise nor the turbulence of the realization.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flightid.scenarios.cards import Card, sub_seed
from flightid.sim.effects.catalogue import CATALOGUE, ActsOn

DISTRIBUTIONS = ("normal", "uniform")
COLUMN_PREFIX = "disperse:"  # result-row column of each dispersion's drawn value
_SPEC = re.compile(r"^\s*(?P<effect>[a-z_]+)(\[(?P<options>[^\]]*)\])?"
                   r"(\.(?P<parameter>[a-z_]+))?\s*:\s*(?P<width>[^:]+?)\s*"
                   r"(:\s*(?P<dist>[a-z]+)\s*)?$")
_AUGMENTED = (ActsOn.AIRFRAME, ActsOn.ACTUATOR)


@dataclass(frozen=True)
class Dispersion:
    """One dispersed parameter: catalogue ``effect`` with ``options`` (sensor effects:
    ``channel``), its ``parameter``, drawn as neutral + ``distribution``(``width``)."""

    effect: str
    parameter: str
    width: float
    distribution: str = "normal"
    options: tuple[tuple[str, str], ...] = ()

    @property
    def group(self) -> str:
        """The effect with its options, e.g. ``derivative_delta[derivative=Cm_alpha]``."""
        opts = ",".join(f"{k}={v}" for k, v in self.options)
        return f"{self.effect}[{opts}]" if opts else self.effect

    @property
    def key(self) -> str:
        """The parameter's name in result rows, e.g. ``mass_scale.factor``."""
        return f"{self.group}.{self.parameter}"

    @property
    def neutral(self) -> float:
        """The parameter's value at which the effect does nothing."""
        return float(CATALOGUE[self.effect].parameter(self.parameter).zero)

    def draw(self, rng: np.random.Generator) -> float:
        """neutral + N(0, width) or neutral + U(-width, width)."""
        if self.distribution == "normal":
            return self.neutral + float(rng.normal(0.0, self.width))
        return self.neutral + float(rng.uniform(-self.width, self.width))

    def text(self) -> str:
        """The spec string (inverse of ``parse``)."""
        return f"{self.key}:{self.width!r}:{self.distribution}"


def parse(text: str) -> Dispersion:
    """A dispersion from its spec string; errors name what is wrong.

    Parameters
    ----------
    text : str
        ``EFFECT[OPTION=VALUE][.PARAMETER]:WIDTH[:normal|uniform]``, e.g.
        ``mass_scale:0.05``.

    Returns
    -------
    Dispersion
        The dispersion.
    """
    m = _SPEC.match(str(text))
    if not m:
        raise ValueError(f"dispersion {text!r}: expected EFFECT[OPTION=VALUE][.PARAMETER]:"
                         "WIDTH[:normal|uniform], e.g. mass_scale:0.05")
    name = m["effect"]
    if name not in CATALOGUE:
        raise ValueError(f"dispersion {text!r}: unknown effect {name!r}; see flightid effects")
    entry = CATALOGUE[name]
    if entry.acts_on not in (*_AUGMENTED, ActsOn.SENSOR):
        raise ValueError(f"dispersion {text!r}: {name} acts on the {entry.acts_on}; only "
                         "airframe, actuator and sensor effects can be dispersed")
    sizing = [p.name for p in entry.parameters if p.sizes]
    parameter = m["parameter"]
    if parameter is None:
        if len(sizing) != 1:
            raise ValueError(f"dispersion {text!r}: {name} has parameters "
                             f"{', '.join(sizing)}; name one ({name}.PARAMETER:WIDTH)")
        parameter = sizing[0]
    if parameter not in sizing:
        raise ValueError(f"dispersion {text!r}: {name} has no sizing parameter "
                         f"{parameter!r}; it has {', '.join(sizing)}")
    try:
        width = float(m["width"])
    except ValueError:
        raise ValueError(f"dispersion {text!r}: width {m['width']!r} is not a number") \
            from None
    if not (np.isfinite(width) and width > 0):
        raise ValueError(f"dispersion {text!r}: width must be > 0, got {m['width']}")
    dist = m["dist"] or "normal"
    if dist not in DISTRIBUTIONS:
        raise ValueError(f"dispersion {text!r}: distribution {dist!r} is not one of "
                         f"{', '.join(DISTRIBUTIONS)}")
    options = _options(text, m["options"] or "")
    allowed = {o.name for o in entry.options} | (
        {"channel"} if entry.acts_on == ActsOn.SENSOR else set())
    for k, v in options:
        if k not in allowed:
            raise ValueError(f"dispersion {text!r}: {name} has no option {k!r}"
                             + (f"; options: {', '.join(sorted(allowed))}" if allowed else ""))
        for o in entry.options:
            if o.name == k and o.choices and v not in o.choices:
                raise ValueError(f"dispersion {text!r}: {k} must be one of "
                                 f"{', '.join(o.choices)}, got {v!r}")
    if entry.acts_on == ActsOn.SENSOR and "channel" not in dict(options):
        raise ValueError(f"dispersion {text!r}: a sensor effect needs its channel, e.g. "
                         f"{name}[channel=q]:{m['width']}")
    return Dispersion(name, parameter, width, dist, options)


def _options(text: str, body: str) -> tuple[tuple[str, str], ...]:
    out = []
    for part in filter(None, (p.strip() for p in body.split(","))):
        k, sep, v = part.partition("=")
        if not sep or not k.strip() or not v.strip():
            raise ValueError(f"dispersion {text!r}: option {part!r} is not OPTION=VALUE")
        out.append((k.strip(), v.strip()))
    return tuple(sorted(out))


def parse_all(texts: Iterable[str]) -> tuple[Dispersion, ...]:
    """Several dispersions; the same parameter twice is an error.

    Parameters
    ----------
    texts : Iterable[str]
        Spec strings, as in :func:`parse`.

    Returns
    -------
    tuple[Dispersion, ...]
        The dispersions, in order.
    """
    out = tuple(parse(t) for t in texts)
    keys = [d.key for d in out]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise ValueError(f"dispersed twice: {', '.join(twice)}")
    return out


def draw(dispersions: Sequence[Dispersion], seed: int) -> dict[str, float]:
    """The drawn value of each dispersion (by key) for a realization's ``seed``.

    Parameters
    ----------
    dispersions : Sequence[Dispersion]
        The dispersions.
    seed : int
        The realization's seed.

    Returns
    -------
    dict[str, float]
        Dispersion key -> drawn value, in the parameter's unit.
    """
    rng = np.random.default_rng(sub_seed(seed, "disperse"))
    return {d.key: d.draw(rng) for d in dispersions}


def dispersed_card(card: Card, dispersions: Sequence[Dispersion],
                   values: Mapping[str, float]) -> Card:
    """``card`` with the drawn ``values``: airframe and actuator effects added to its
    augmentation (one effect per effect and options, undispersed parameters neutral),
    sensor effects put first in their channel's chain.

    Parameters
    ----------
    card : Card
        The flight card.
    dispersions : Sequence[Dispersion]
        The dispersions.
    values : Mapping[str, float]
        Their drawn values by key.

    Returns
    -------
    Card
        The changed card.
    """
    groups: dict[str, list[Dispersion]] = {}
    for d in dispersions:
        groups.setdefault(d.group, []).append(d)
    added: list[Any] = []
    suite = card.sensors
    for members in groups.values():
        first = members[0]
        entry = CATALOGUE[first.effect]
        params = entry.zeros()
        params.update({d.parameter: float(values[d.key]) for d in members})
        options = dict(first.options)
        if entry.acts_on in _AUGMENTED:
            added.append(entry.build(params, **options))
            continue
        channel = options.pop("channel")
        if suite is None or channel not in suite.channels:
            have = ", ".join(suite.channels) if suite is not None else "no sensors"
            raise ValueError(f"dispersion {first.key}: the card has no sensor channel "
                             f"{channel!r} ({have})")
        effect = entry.build(params, **options)
        chains = dict(suite.channels)
        chains[channel] = [effect, *chains[channel]]
        suite = dataclasses.replace(suite, channels=chains)
    return dataclasses.replace(card, augmentation=tuple(card.augmentation) + tuple(added),
                               sensors=suite)
