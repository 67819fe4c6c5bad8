"""Input-design experiments: the same aircraft, condition, sensors and disturbances flown
with a doublet, a 2-1-1, a 3211, a frequency sweep and a phase-optimised multisine on one
surface, each over a Monte Carlo study (the same realization seeds for every design), so
that each derivative's scatter can be compared by design (``comparison.compare`` flies
them).

Designs are compared at equal peak amplitude (``equal="amplitude"``, the default) or at
equal input energy (``equal="energy"``: every design scaled, ``scale_to_energy``, to the
energy of the reference design, the 3211 by default). Each design's flight card is
written to ``STUDY/cards/<design>.toml`` and its study to ``STUDY/<design>/`` (continued
when rerun, as any Monte Carlo study). Classic expectation (Plaetschke & Schulz 1979;
Jategaonkar 2015, 2.5; Morelli & Klein 2016, 9.3): at equal amplitude a 3211 gives
smaller scatter than a doublet for most longitudinal derivatives, because its spectrum
is broader and it carries more energy (7 base times at full amplitude against 2).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from flightid.scenarios.equal_energy import energy, scale_amplitude, scale_to_energy
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.inputs import (
    Doublet,
    Maneuvers,
    Sweep,
    ThreeTwoOneOne,
    TwoOneOne,
)
from flightid.scenarios.multisine import Multisine
from flightid.units import DEG

DESIGNS = ("doublet", "211", "3211", "sweep", "multisine")
EQUAL = ("amplitude", "energy")
START_S = 2.0  # s of trimmed flight before the input
GAP_S = 4.0  # s between one surface's input and the next one's (DesignSettings.then)
SETTLE_S = 8.0  # s of free response after it (the identification window keeps 8 s)
CARDS = "cards"


@dataclass(frozen=True)
class DesignSettings:
    """What the designs share: ``surface``, peak ``amplitude`` (rad), multi-step ``base``
    (s), the sweep's band (Hz) and duration (s), the multisine's band (Hz) and period (s),
    and ``then``: further surfaces each design is flown on in turn after ``surface``, the
    next GAP_S s after the previous input ends (as the library cards fly an aileron and a
    rudder input)."""

    surface: str = "de"
    amplitude: float = 3.0 * DEG
    base: float = 0.4
    sweep_band: tuple[float, float] = (0.2, 2.0)
    sweep_duration: float = 12.0
    multisine_band: tuple[float, float] = (0.2, 2.0)
    multisine_period: float = 10.0
    then: tuple[str, ...] = ()


def make_design(kind: str, settings: DesignSettings = DesignSettings(),
                start: float = START_S) -> InputDesign:
    """The input design ``kind`` (one of DESIGNS) at the settings' peak amplitude, on the
    settings' surface and then on each of ``settings.then`` in turn (a Maneuvers).

    Parameters
    ----------
    kind : str
        Design kind, one of ``DESIGNS``.
    settings : DesignSettings, optional
        Surface, amplitude (rad) and the other settings.
    start : float, optional
        Start time, s.

    Returns
    -------
    InputDesign
        The design (a ``Maneuvers`` with ``settings.then``).
    """
    if settings.then:
        parts = [make_design(kind, replace(settings, then=()), start)]
        for surface in settings.then:
            parts.append(make_design(kind, replace(settings, surface=surface, then=()),
                                     parts[-1].end + GAP_S))
        return Maneuvers(parts=tuple(parts))
    s = settings
    common = dict(surface=s.surface, amplitude=s.amplitude, start=start)
    if kind == "doublet":
        return Doublet(base=s.base, **common)
    if kind == "211":
        return TwoOneOne(base=s.base, **common)
    if kind == "3211":
        return ThreeTwoOneOne(base=s.base, **common)
    if kind == "sweep":
        return Sweep(f_start=s.sweep_band[0], f_end=s.sweep_band[1],
                     duration=s.sweep_duration, law="log", fade_in=1.0, fade_out=1.0,
                     **common)
    if kind == "multisine":
        return Multisine(f_min=s.multisine_band[0], f_max=s.multisine_band[1],
                         period=s.multisine_period, phases="optimized", **common)
    raise ValueError(f"unknown design {kind!r}; designs: {', '.join(DESIGNS)}")


def time_grid(design: InputDesign, rate: float) -> np.ndarray:
    """Sample times (s) from 0 to the end of ``design`` plus SETTLE_S at ``rate`` (Hz).

    Parameters
    ----------
    design : InputDesign
        The input design.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    numpy.ndarray
        Sample times, s.
    """
    duration = design.end + SETTLE_S
    return np.arange(int(round(duration * rate)) + 1) / rate


def input_energy(design: InputDesign, rate: float) -> float:
    """Integral of u^2 dt over the flight (rad^2 s), summed over the design's surfaces.

    Parameters
    ----------
    design : InputDesign
        The input design.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    float
        Input energy, rad^2 s.
    """
    t = time_grid(design, rate)
    return float(sum(energy(t, u) for u in design.signals(t).values()))


def peak(design: InputDesign, rate: float) -> float:
    """The largest |u| of the design (rad).

    Parameters
    ----------
    design : InputDesign
        The input design.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    float
        Peak |u| over its surfaces, rad.
    """
    t = time_grid(design, rate)
    return float(max(np.abs(u).max() for u in design.signals(t).values()))


def equalized_designs(kinds: Sequence[str], settings: DesignSettings, equal: str,
                      rate: float, reference: str = "3211",
                      own: Mapping[str, InputDesign] | None = None) -> dict[str, InputDesign]:
    """The built-in designs ``kinds`` and the user's ``own`` designs (name -> design, a
    ``Maneuvers`` for several surfaces at once) at equal peak amplitude (an own design
    scaled so that its largest |u| over its surfaces is the settings' amplitude), or all
    scaled to the input energy of ``reference`` (a built-in or own name) at that
    amplitude.

    Parameters
    ----------
    kinds : Sequence[str]
        Built-in design kinds (``DESIGNS``).
    settings : DesignSettings
        Surface, amplitude (rad) and the other settings.
    equal : str
        ``"amplitude"`` or ``"energy"``.
    rate : float
        Sample rate, Hz.
    reference : str, optional
        Design whose energy the others get with ``equal="energy"``.
    own : Mapping[str, InputDesign] or None, optional
        The user's designs by name.

    Returns
    -------
    dict[str, InputDesign]
        Name -> scaled design, built-in ones first.
    """
    if equal not in EQUAL:
        raise ValueError(f"equal must be one of {', '.join(EQUAL)}, got {equal!r}")
    designs = {k: make_design(k, settings) for k in kinds}
    for name, d in (own or {}).items():
        top = peak(d, rate)
        if not top > 0:
            raise ValueError(f"design {name!r} does not move any surface")
        designs[name] = scale_amplitude(d, settings.amplitude / top)
    if equal == "amplitude":
        return designs
    ref = designs[reference] if reference in designs else make_design(reference, settings)
    target = input_energy(ref, rate)
    out = {}
    for k, d in designs.items():
        t = time_grid(d, rate)
        out[k] = scale_to_energy(d, t, target)
    return out


def toml_value(v: Any) -> str:
    """A plain value (str, number, bool, list, dict) as an inline TOML value.

    Parameters
    ----------
    v : Any
        The value.

    Returns
    -------
    str
        Inline TOML text.
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        x = float(v)
        return "nan" if math.isnan(x) else ("inf" if x == math.inf else
                                             "-inf" if x == -math.inf else repr(x))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_value(x)}"
                               for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} to TOML: {v!r}")


def card_text(data: Mapping[str, Any]) -> str:
    """A flight card (plain dict) as TOML text, one key per line with inline tables.

    Parameters
    ----------
    data : Mapping[str, Any]
        The card's data.

    Returns
    -------
    str
        TOML text.
    """
    return "".join(f"{json.dumps(str(k))} = {toml_value(v)}\n" for k, v in data.items())


def design_card(base: Mapping[str, Any], kind: str, design: InputDesign,
                rate: float) -> dict[str, Any]:
    """The base card's data with its maneuvers replaced by ``design`` and its duration
    set to the input plus SETTLE_S.

    Parameters
    ----------
    base : Mapping[str, Any]
        The base card's data.
    kind : str
        Design name, for the card's name.
    design : InputDesign
        The design flown.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    dict[str, Any]
        The new card's data.
    """
    data = {k: v for k, v in base.items() if k != "maneuver"}
    data["name"] = f"{base.get('name', 'card')}-{kind}"
    data["description"] = f"design-compare: {kind} on {', '.join(design.surfaces())}"
    data["duration"] = float(time_grid(design, rate)[-1])
    data["maneuver"] = maneuver_dicts(design)
    return data


def maneuver_dicts(design: InputDesign) -> list[dict[str, Any]]:
    """The card's ``[[maneuver]]`` tables of a design (one per part of a Maneuvers).

    Parameters
    ----------
    design : InputDesign
        The design.

    Returns
    -------
    list[dict[str, Any]]
        One table per part.
    """
    parts = design.parts if isinstance(design, Maneuvers) else (design,)
    return [d.to_dict() for d in parts]


def check_own(own: Mapping[str, InputDesign]) -> None:
    """Raise ValueError unless every own design's name is a usable folder name that is
    not a built-in design's.

    Parameters
    ----------
    own : Mapping[str, InputDesign]
        The user's designs by name.
    """
    for name in own:
        if name in DESIGNS:
            raise ValueError(f"design name {name!r} is a built-in design's; name it "
                             "otherwise (the maneuver table's name = \"...\")")
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", name) or name in (CARDS, ".", ".."):
            raise ValueError(f"design name {name!r}: use letters, digits, '_', '.', '-' "
                             f"(not {CARDS!r})")
