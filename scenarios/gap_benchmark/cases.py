"""What the blind check draws: per case an aircraft and an effect of the catalogue (one or a
pair), an effect outside it, or nothing (a null case), with magnitudes in catalogue units.

Every entry the gap diagnosis has (or is getting) a candidate for is a row of ``KINDS``:
its axis, how it is injected and how its magnitude is drawn. Magnitudes are 0.5-1.5 times
the entry's catalogue default (measured from the neutral value: a factor of default 0.8
is drawn in 0.7-0.9), except where the default is not what the maneuvers show; those rows
say why in ``SIZED``; per aircraft, rows whose smallest draw the diagnosis's window test
would not see as material have their base enlarged (``size_multiple``), up to a physical
cap. The draw is fixed by the seed and stratified in blocks of ``BLOCK``
cases (``PATTERN``: 12 single effects, 4 pairs, 4 outside the catalogue; each aircraft
equally often), so the shares hold for any n that is a multiple of 20 and nearly
so for the rest; the null cases
(nothing injected) are drawn on their own stream, so ``--nulls`` does not move the other
cases and n does not move the nulls.

How an effect reaches the record (``INJECT``):

- ``card``: airframe and actuator entries, the card's ``[[effect]]`` (the augmented JSBSim
  aircraft); the actuator ones on records whose surface channels hold the commands
  (``run.commands``: RC and autopilot logs record commands, not positions);
- ``measured``: sensor entries (bias, scale, delay, lag), the catalogue's own effect applied
  to one channel of the measured record (after the research suite: the same as a last
  element of its chain);
- ``mounting``: mounting entries, the suite's mounting list of the card;
- ``disturbance``: ``engine_vibration``, the card's ``[[disturbance]]`` (on the IMU from the
  engine speed, before the anti-alias filters).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from flightid.channels import LATERAL_INPUTS, LONGITUDINAL_INPUTS
from flightid.identification.gap.candidates.ranges import INERTIAL, INERTIAL_SCALE
from flightid.identification.gap.verdict import MATERIAL
from flightid.sim.effects.catalogue import CATALOGUE

LATERAL, LONGITUDINAL, BOTH = "lateral", "longitudinal", "both"
AXES = (LATERAL, LONGITUDINAL)
INJECT = ("card", "measured", "mounting", "disturbance")
TURBULENCE = ("calm", "light", "moderate")


@dataclass(frozen=True)
class Flight:
    """The test flight of one aircraft: condition, inputs (``run.SCHEDULE``: the aileron and
    the rudder twice each, then an elevator doublet and a 3211) and the reference chord."""

    altitude_m: float
    speed_m_s: float
    flaps_deg: float
    aileron_deg: float
    rudder_deg: float
    elevator_deg: float
    base_s: float  # lateral pulse width (doublet, the 2-1-1's unit)
    elevator_base_s: float  # the elevator doublet's pulse and the 3211's unit
    chord_m: float  # mean aerodynamic chord (the JSBSim model's cbarw), for cg offsets


AIRCRAFT: dict[str, Flight] = {
    "navion": Flight(1500.0, 55.0, 0.0, 4.0, 4.0, 2.0, 1.0, 0.5, 1.737),
    "twinotter": Flight(1890.0, 72.2, 0.0, 6.0, 2.8, 2.0, 1.0, 0.5, 1.980),
    "telemaster": Flight(30.0, 15.0, 0.0, 2.0, 1.5, 2.0, 0.5, 0.3, 0.350),
    # stock JSBSim: trimmed at 1500 m, 50 m/s (flightid trim c172p --altitude 1500
    # --speed 50: alpha 1.2 deg, elevator 3.0 deg, throttle 0.69)
    "c172p": Flight(1500.0, 50.0, 0.0, 4.0, 3.0, 2.0, 1.0, 0.5, 1.494),
}
STOCK = ("c172p",)  # aircraft shipped with JSBSim (the others are the project's)

# derivative deltas: the derivatives drawn per axis, in the axes the diagnosis's models
# use (``identification.gap.model.linearise.AXIS_FRAME``: lateral body, longitudinal stability)
DERIVATIVES = {
    LATERAL: ("Cn_beta", "Cl_beta", "Cn_r", "Cl_p", "Cl_r", "CY_beta", "Cl_da", "Cn_dr"),
    LONGITUDINAL: ("Cm_alpha", "Cm_q", "Cm_de", "CL_alpha", "CD_alpha", "Cm_alphadot"),
}
DERIVATIVE_AXES = {LATERAL: "body", LONGITUDINAL: "stability"}
# a delta is 30-50 % of the aircraft's own value (at most half: no sizeable derivative
# changes sign; the catalogue's 0.02 per rad is 3 % of a Cl_p and 30 % of a Cn_beta, so
# one default cannot size them all), or of DELTA_SCALE where the value is smaller
DELTA_FRACTION = (0.3, 0.5)
DELTA_SCALE = {"Cn_beta": 0.03, "Cl_beta": 0.03, "Cn_r": 0.05, "Cl_p": 0.1, "Cl_r": 0.03,
               "CY_beta": 0.1, "Cl_da": 0.05, "Cn_dr": 0.03, "Cm_alpha": 0.1, "Cm_q": 2.0,
               "Cm_de": 0.1, "CL_alpha": 0.5, "CD_alpha": 0.05, "Cm_alphadot": 1.0}
# the stable sign a delta on a near-zero stability derivative points to (a telemaster
# Cn_beta of -0.003 made -0.012 departs: not a case a flight test flies)
STABLE_SIGN = {"Cn_beta": 1.0, "Cl_beta": -1.0, "Cn_r": -1.0, "Cl_p": -1.0, "CY_beta": -1.0,
               "Cm_alpha": -1.0, "Cm_q": -1.0, "CL_alpha": 1.0}
# the channels a sensor effect is drawn on, per axis
CHANNELS = {LATERAL: ("beta", "p", "r", "ay"), LONGITUDINAL: ("alpha", "q", "az")}
FLOW_ANGLE = {LATERAL: ("beta",), LONGITUDINAL: ("alpha",)}  # biases the trim fixes
SURFACES = {LATERAL: LATERAL_INPUTS, LONGITUDINAL: LONGITUDINAL_INPUTS}
INERTIA = {LATERAL: ("ixx", "izz"), LONGITUDINAL: ("iyy",)}
K_RANGE = (0.5, 1.5)  # the drawn multiple of an entry's default magnitude

# rows whose magnitude is not 0.5-1.5 times the catalogue default, and why
SIZED = {
    "derivative_delta": "30-50 % of the aircraft's own value (DELTA_FRACTION)",
    "cg_offset": "x 0.5-1.5 times 5 % of the chord, sign drawn: the default 0.05 m is 3 % "
                 "of the Navion's chord but 14 % of the Telemaster's, and 2 % (0.035 m, "
                 "twinotter) changed the outputs by 0.0023 of their energy, at the "
                 "diagnosis's least gain (0.002); 5 % is a loading error a weight-and-"
                 "balance sheet can carry",
    "scale": "factor 1 + 0.5-1.5 times 0.2: the default 1.05 leaves a held-out gap of "
             "(0.05)^2 = 0.0025 of the channel's energy, under what light turbulence "
             "leaves on a null flight",
    "thrust_moment": "arm 0.5-1.5 times 0.25 m, sign drawn: the default 0.1 m changed the "
                     "longitudinal outputs by 0.0018 of their energy (0.06 m, navion), "
                     "below the diagnosis's least gain (0.002); thrust lines 0.2-0.5 m off "
                     "the CG are common on high-wing and twin aircraft",
    "delay": "tau 0.5-1.5 times 0.1 s: the default 0.05 s moved the calm flights' outputs "
             "by 0.004-0.03 of their energy (navion and telemaster, p and q), under what "
             "the test sees in light turbulence (an input-explained share of about 0.03); "
             "0.1 s moved them by 0.016-0.11. Air-data and IMU pipelines of autopilot and "
             "RC logs carry 0.05-0.15 s",
    "lag": "as delay (the same class: 1/(tau s + 1) and exp(-tau s) agree to first order)",
    "actuator_lag": "tau 0.5-1.5 times 0.1 s: the default 0.05 s moved the outputs by "
                    "0.004-0.06 (navion and telemaster, aileron and elevator), 0.1 s by "
                    "0.012-0.17; hobby and light-aircraft servos have time constants of "
                    "0.05-0.15 s (0.1-0.2 s per 60 deg of travel)",
    "inertia_scale": "factor 1 + 0.5-1.5 times 0.2: the default 1.1 moved the outputs by "
                     "0.002-0.027 (navion and telemaster, Izz and Iyy), 1.2 by 0.008-0.094; "
                     "inertias computed from a component breakdown are often 10-30 % off "
                     "(a swing test gets them to about 5 %)",
}
THRUST_ARM_M = 0.25
CG_CHORDS = 0.05
# the sized rows' base magnitudes (drawn 0.5-1.5 times, measured from neutral)
SIZED_BASE = {"delay": 0.1, "lag": 0.1, "actuator_lag": 0.1, "inertia_scale": 1.2}

# Sizing by visibility (seed-11 rules; docs/gap_benchmark.md): per row and aircraft the
# base is multiplied by sqrt(AIM / V), V the share (``verdict.ChannelTest.share``) the row
# adds at its base (k = 1) on its axis's most affected tested channel over the plain
# flight's, light turbulence (the larger axis for a row on both; a sensor scale's per 0.2
# of offset), median over the row's options, mean of flight seeds 12 and 13
# (benchmarks/gap_visibility.py --test-share). A small effect's share grows as its offset
# squared, so the smallest draw (k = K_RANGE[0]) reaches ``MATERIAL``. Not re-sized: the
# trim-level entries (bias, actuator bias, mass scale), derivative deltas, rate limits.
AIM = MATERIAL / K_RANGE[0] ** 2
# V per aircraft in the order of ``_SHARE_OF`` (None: at or above the aim)
_SHARE_OF = ("c172p", "navion", "telemaster", "twinotter")
_SHARES = {
    "actuator_lag/lateral": (0.053, 0.034, None, 0.05),
    "actuator_lag/longitudinal": (None, 0.061, None, None),
    "backlash/lateral": (0.005, 0.0036, 0.044, 0.0038),
    "backlash/longitudinal": (0.0072, 0.01, 0.035, 0.05),
    "cg_offset/longitudinal": (0.0086, 0.059, 0.034, 0.026),
    "control_effectiveness/lateral": (0.033, 0.026, 0.036, 0.029),
    "control_effectiveness/longitudinal": (0.039, 0.057, 0.061, None),
    "deadband/lateral": (0.0037, 0.005, 0.018, 0.0034),
    "delay/lateral": (0.073, 0.055, 0.069, 0.049),
    "delay/longitudinal": (None, 0.039, None, None),
    "engine_vibration/both": (0.0033, 0.00088, 0.0017, 0.0028),
    "inertia_scale/lateral": (0.012, 0.015, 0.014, 0.011),
    "inertia_scale/longitudinal": (0.011, 0.01, 0.013, 0.019),
    "lag/lateral": (0.045, 0.048, 0.06, 0.045),
    "lag/longitudinal": (None, 0.048, None, 0.068),
    "misalignment/both": (0.00089, 0.00096, 0.0014, 0.00072),
    "scale/lateral": (0.019, 0.024, 0.022, 0.027),
    "scale/longitudinal": (0.018, 0.018, 0.021, 0.021),
    "tail_ice/longitudinal": (0.0061, 0.013, 0.0058, 0.015),
    "thrust_moment/longitudinal": (0.003, 0.0032, None, 0.00037),
}
VISIBILITY = {kind: {a: v for a, v in zip(_SHARE_OF, shares, strict=True) if v is not None}
              for kind, shares in _SHARES.items()}
# the largest multiple per entry: the physical range its largest draw (1.5 x the base) keeps
SIZE_CAP = {
    "actuator_lag": 1.5,  # base <= 0.15 s: draws <= 0.225 s (a slow servo under load)
    "backlash": 2.0,  # base <= 1 deg of play: draws <= 1.5 deg (a worn linkage)
    "cg_offset": 2.0,  # base <= 10 % of the chord: draws <= 15 %, a CG envelope's width
    "control_effectiveness": 1.65,  # factor drawn >= 0.505: at most half the surface lost
    "deadband": 2.0,  # base <= 1 deg: draws <= 1.5 deg
    "delay": 1.5, "lag": 1.5,  # base <= 0.15 s, the longest of autopilot and RC pipelines
    "engine_vibration": 3.0,  # draws <= 13.5 m/s^2 (1.4 g) and 9 deg/s on an IMU
    "inertia_scale": 1.5,  # base <= 1.3: a component breakdown's 10-30 %
    "misalignment": 1.745,  # base <= 0.0349 rad (2 deg): draws <= 3 deg
    "scale": 1.65,  # factor drawn <= 1.5 (a flow angle's; an inertial channel's below)
    "tail_ice": 2.0,  # elevator drawn >= 0.55, stability and damping >= 0.7
    "thrust_moment": 2.0,  # base <= 0.5 m: draws <= 0.75 m, inside the catalogue's 1 m
}
# an inertial channel's scale (rates, accelerations) is drawn inside the diagnosis's range
# of a calibrated inertial sensor (``candidates.ranges.INERTIAL_SCALE``, 0.75-1.33; seed-10
# rules): at most 1.27, the range's top less the 0.034-0.055 that seeds 0 and 9's fits lay
# above the injected; its multiple of the 0.2 base is capped so (0.9: drawn 1.09-1.27)
SCALE_BASE = 0.2
INERTIAL_SCALE_TOP = 1.27
INERTIAL_SCALE_MULTIPLE = (INERTIAL_SCALE_TOP - 1.0) / (K_RANGE[1] * SCALE_BASE)


def size_multiple(kind: str, aircraft: str) -> float:
    """The factor sizing by visibility puts on a row's base magnitude for one aircraft.

    Parameters
    ----------
    kind : str
        The row's name, entry/axis (``Kind.name``).
    aircraft : str
        A name of ``AIRCRAFT``.

    Returns
    -------
    float
        sqrt(``AIM`` / V) capped at the entry's ``SIZE_CAP``; 1 for
        a row and aircraft not in ``VISIBILITY`` (at or above the aim, or not re-sized).
    """
    v = VISIBILITY.get(kind, {}).get(aircraft)
    if v is None:
        return 1.0
    return min(math.sqrt(AIM / v), SIZE_CAP[kind.split("/")[0]])


@dataclass(frozen=True)
class Kind:
    """One row of the draw: a catalogue entry on an axis, how it is injected, the options
    drawn (option -> choices) and the parameters that size it (drawn) or ``one_of`` them
    (one drawn, the others neutral: an inertia scale about one axis)."""

    entry: str
    axis: str
    inject: str
    choices: dict[str, tuple[str, ...]] = field(default_factory=dict)
    sized: tuple[str, ...] = ()
    one_of: bool = False

    @property
    def name(self) -> str:
        """The kind's name in the per-kind table: entry/axis."""
        return f"{self.entry}/{self.axis}"


def _kinds() -> tuple[Kind, ...]:
    rows: list[Kind] = []
    for ax in AXES:
        rows += [
            Kind("derivative_delta", ax, "card", {"derivative": DERIVATIVES[ax]}, ("delta",)),
            Kind("control_effectiveness", ax, "card", {"surface": SURFACES[ax]}, ("factor",)),
            Kind("scale", ax, "measured", {"channel": CHANNELS[ax]}, ("factor",)),
            Kind("bias", ax, "measured", {"channel": FLOW_ANGLE[ax]}, ("value",)),
            Kind("delay", ax, "measured", {"channel": CHANNELS[ax]}, ("tau",)),
            Kind("lag", ax, "measured", {"channel": CHANNELS[ax]}, ("tau",)),
            *(Kind(e, ax, "card", {"surface": SURFACES[ax]}, (p,)) for e, p in (
                ("actuator_lag", "tau"), ("rate_limit", "rate"), ("backlash", "width"),
                ("actuator_bias", "bias"))),
            Kind("inertia_scale", ax, "card", {}, INERTIA[ax], one_of=True),
        ]
    # the deadband sits around zero deflection: the aileron and rudder cross it, the
    # elevator (trimmed at 2-5 deg) never does (a telemaster deadband(de) of 0.75 deg
    # changed the longitudinal outputs by 1e-14 of their energy)
    rows += [Kind("deadband", LATERAL, "card", {"surface": SURFACES[LATERAL]}, ("width",))]
    rows += [
        Kind("cg_offset", LONGITUDINAL, "card", {}, ("x",)),
        Kind("mass_scale", LONGITUDINAL, "card", {}, ("factor",)),
        Kind("thrust_moment", LONGITUDINAL, "card", {}, ("arm",)),
        Kind("tail_ice", LONGITUDINAL, "card", {}, ("elevator", "stability", "damping")),
        # the IMU's rates and accelerations on both axes, at the defaults' ratios
        Kind("engine_vibration", BOTH, "disturbance", {}, ("ax", "ay", "az", "p", "q", "r")),
    ]
    # a misalignment of the IMU, a mounting entry: its parameters are whatever the entry
    # declares, each 0.5-1.5 times its default. The row is drawn whether or not this
    # catalogue has the entry yet (the draw of every other case stays the same when it
    # lands); without it, its cases fail to fly, named as unknown, and are listed
    sized = tuple(p.name for p in CATALOGUE["misalignment"].parameters if p.sizes) \
        if "misalignment" in CATALOGUE else ()
    rows.append(Kind("misalignment", BOTH, "mounting", {}, sized))
    return tuple(rows)


KINDS: tuple[Kind, ...] = _kinds()
KIND_BY_NAME = {k.name: k for k in KINDS}

# effects outside the catalogue (``outside_catalogue.py``): name -> axis it shows on
OUTSIDE = {"structural_mode": (LATERAL, LONGITUDINAL), "vane_nonlinearity": (LATERAL,),
           "vane_hysteresis": (LATERAL, LONGITUDINAL), "cm_alpha_break": (LONGITUDINAL,)}

SINGLE, PAIR, OUT, NULL = "single", "pair", "outside", "null"
BLOCK = 20
PATTERN = (SINGLE,) * 12 + (PAIR,) * 4 + (OUT,) * 4  # one block of the draw
NULL_INDEX = 1_000_000  # the null cases' indices start here (their own stream)


@dataclass(frozen=True)
class Effect:
    """One injected effect: a catalogue entry (or one outside it), its options and its
    magnitude (catalogue units, SI; the sized parameters only, the others neutral)."""

    entry: str
    axis: str
    inject: str
    options: dict[str, str] = field(default_factory=dict)
    magnitude: dict[str, float] = field(default_factory=dict)
    in_catalogue: bool = True

    @property
    def kind(self) -> str:
        return f"{self.entry}/{self.axis}"

    @property
    def label(self) -> str:
        opts = ",".join(self.options.values())
        mag = " ".join(f"{k} {v:.4g}" for k, v in self.magnitude.items())
        return f"{self.entry}({opts}) {mag}".strip()

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Effect:
        return cls(**d)


@dataclass(frozen=True)
class Case:
    """One blind case: what is injected (the diagnosis is not told). ``category``: single,
    pair, outside or null; ``effects``: none for a null case, two for a pair."""

    index: int
    seed: int  # the flight's seed (sensor noise, turbulence)
    aircraft: str
    category: str
    effects: tuple[Effect, ...] = ()

    @property
    def kind(self) -> str:
        """The per-kind table's row: the effect's kind, "pair", or "null"."""
        if self.category in (SINGLE, OUT):
            return self.effects[0].kind
        return self.category

    @property
    def label(self) -> str:
        inner = " + ".join(e.label for e in self.effects) or "nothing injected"
        return f"{self.aircraft}: {inner}"

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Case:
        return cls(d["index"], d["seed"], d["aircraft"], d["category"],
                   tuple(Effect.from_json(e) for e in d["effects"]))


def fingerprint() -> str:
    """A hash of everything the draw draws from (kinds, outside kinds, pattern, ranges,
    the sizing by visibility, the aircraft's flights): a stored study continues only under
    the same draw.

    Returns
    -------
    str
        16 hex digits of a SHA-256.
    """
    text = json.dumps([[asdict(k) for k in KINDS], OUTSIDE, PATTERN, BLOCK, DERIVATIVES,
                       DELTA_FRACTION, DELTA_SCALE, STABLE_SIGN, K_RANGE, CG_CHORDS,
                       THRUST_ARM_M, SIZED_BASE, AIM, VISIBILITY, SIZE_CAP,
                       INERTIAL, INERTIAL_SCALE, INERTIAL_SCALE_TOP,
                       {a: asdict(f) for a, f in AIRCRAFT.items()}],
                      sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def draw(n: int, seed: int, truths: dict[str, dict[str, float]], nulls: int = 0,
         aircraft: tuple[str, ...] = tuple(AIRCRAFT)) -> list[Case]:
    """``n`` drawn cases and ``nulls`` null cases from ``seed``.

    ``truths``: each aircraft's derivatives at its condition (lateral in body axes,
    longitudinal in stability axes; ``run.truths``); ``aircraft``: the ones drawn from.
    Case k of a seed is the same whatever n (its block's pattern and its own stream).

    Parameters
    ----------
    n : int
        Number of drawn cases.
    seed : int
        Study seed.
    truths : dict[str, dict[str, float]]
        Aircraft -> derivative values.
    nulls : int, optional
        Number of null cases. Default 0.
    aircraft : tuple[str, ...], optional
        Aircraft drawn from. Default all of ``AIRCRAFT``.

    Returns
    -------
    list[Case]
        The drawn cases, then the null cases.
    """
    out = [_case(k, seed, truths, aircraft) for k in range(n)]
    out += [_null(k, seed, aircraft) for k in range(nulls)]
    return out


def _stream(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng([int(seed), *key])


def _case(k: int, seed: int, truths: dict[str, dict[str, float]],
          aircraft: tuple[str, ...]) -> Case:
    block, slot = divmod(k, BLOCK)
    pattern = list(PATTERN)
    _stream(seed, 1, block).shuffle(pattern)
    # each aircraft equally often in a block (as near as the block allows)
    names = list(np.resize(np.arange(len(aircraft)), BLOCK))
    _stream(seed, 4, block).shuffle(names)
    rng = _stream(seed, 2, k)
    name = aircraft[int(names[slot])]
    flight_seed = int(rng.integers(2**31))
    category = pattern[slot]
    if category == OUT:
        return Case(k, flight_seed, name, OUT, (_outside(rng, truths[name]),))
    first = _effect(KINDS[int(rng.integers(len(KINDS)))], rng, name, truths[name])
    if category == SINGLE:
        return Case(k, flight_seed, name, SINGLE, (first,))
    while True:  # a second effect of another entry, drawn the same way
        second = _effect(KINDS[int(rng.integers(len(KINDS)))], rng, name, truths[name])
        if second.entry != first.entry:
            return Case(k, flight_seed, name, PAIR, (first, second))


def _null(k: int, seed: int, aircraft: tuple[str, ...]) -> Case:
    rng = _stream(seed, 3, k)
    name = aircraft[int(rng.integers(len(aircraft)))]
    return Case(NULL_INDEX + k, int(rng.integers(2**31)), name, NULL)


def _scaled(entry: str, name: str, k: float, base: float | None = None) -> float:
    """``k`` times the catalogue default (or the sized row's ``base``), measured from the
    neutral value."""
    p = CATALOGUE[entry].parameter(name)
    base = p.default if base is None else base
    if p.neutral is None or not math.isfinite(p.neutral):
        return k * base
    return p.neutral + k * (base - p.neutral)


def _effect(kind: Kind, rng: np.random.Generator, aircraft: str,
            truth: dict[str, float]) -> Effect:
    options = {o: str(rng.choice(c)) for o, c in kind.choices.items()}
    multiple = size_multiple(kind.name, aircraft)
    if kind.entry == "scale" and options["channel"] in INERTIAL:
        multiple = min(multiple, INERTIAL_SCALE_MULTIPLE)
    k = float(rng.uniform(*K_RANGE)) * multiple
    sign = float(rng.choice([-1.0, 1.0]))
    if kind.entry == "derivative_delta":
        d = options["derivative"]
        value = truth[d]
        if abs(value) < DELTA_SCALE[d] and d in STABLE_SIGN:
            sign = STABLE_SIGN[d]
        mag = {"delta": sign * float(rng.uniform(*DELTA_FRACTION))
               * max(abs(value), DELTA_SCALE[d])}
        options["axes"] = DERIVATIVE_AXES[kind.axis]
    elif kind.entry == "cg_offset":
        mag = {"x": sign * k * CG_CHORDS * AIRCRAFT[aircraft].chord_m}
    elif kind.entry == "thrust_moment":
        mag = {"arm": sign * k * THRUST_ARM_M}
    elif kind.entry == "scale":
        mag = {"factor": 1.0 + k * SCALE_BASE}
    elif kind.one_of:
        which = str(rng.choice(kind.sized))
        mag = {which: _scaled(kind.entry, which, k, SIZED_BASE.get(kind.entry))}
    elif kind.entry in SIZED_BASE:
        mag = {p: _scaled(kind.entry, p, k, SIZED_BASE[kind.entry]) for p in kind.sized}
    elif kind.entry not in CATALOGUE:  # (misalignment, until the catalogue has it)
        mag = {}
    else:
        signed = {p.name for p in CATALOGUE[kind.entry].parameters
                  if p.low < 0 and p.neutral == 0.0}
        mag = {p: (sign if p in signed else 1.0) * _scaled(kind.entry, p, k)
               for p in kind.sized}
    return Effect(kind.entry, kind.axis, kind.inject, options, mag)


def _outside(rng: np.random.Generator, truth: dict[str, float]) -> Effect:
    name = list(OUTSIDE)[int(rng.integers(len(OUTSIDE)))]
    axes = OUTSIDE[name]
    axis = axes[int(rng.integers(len(axes)))]
    if name == "structural_mode":
        mag = {"frequency_hz": float(rng.uniform(3.0, 6.0)),
               "damping": float(rng.uniform(0.02, 0.05)), "gain": float(rng.uniform(0.5, 1.0))}
        return Effect(name, axis, "measured", {}, mag, in_catalogue=False)
    if name == "vane_nonlinearity":
        return Effect(name, axis, "measured", {"channel": "beta"},
                      {"k": float(rng.uniform(4.0, 8.0))}, in_catalogue=False)
    if name == "vane_hysteresis":
        channel = FLOW_ANGLE[axis][0]
        return Effect(name, axis, "measured", {"channel": channel},
                      {"width": float(rng.uniform(0.5, 1.0)) * math.pi / 180},
                      in_catalogue=False)
    # a pitch break: above the trim alpha plus 0.3-0.7 deg, Cm_alpha 50-80 % less stable.
    # The elevator doublet and 3211 take alpha 1.3-1.9 deg above trim (calm air), so the
    # break is crossed by 0.6-1.6 deg; the outputs move by 0.007-0.3 of their energy
    # (0.002-0.017 with the break at 0.5-1 deg and 30-50 %, near the least gain named)
    mag = {"above": float(rng.uniform(0.3, 0.7)) * math.pi / 180,
           "delta": float(rng.uniform(0.5, 0.8)) * abs(truth["Cm_alpha"])}
    return Effect(name, axis, "card", {}, mag, in_catalogue=False)
