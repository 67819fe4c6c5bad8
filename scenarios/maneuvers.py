"""Hand-flown maneuvers as an RC pilot flies them (Monash Boomerang 60 paper, c. 2008).

Each maneuver is a plan of knots shared by all the surfaces it moves: nominal phase
durations (s) and the surface increment at every knot (rad, throttle fraction), joined by
ramps. The pilot is imperfect, reproducibly from ``seed``: each phase duration scatters by
``timing_sigma`` (s), each held level by ``amplitude_sigma`` (relative), and small
corrections of rms ``tremor`` (rad) with bandwidth ``tremor_bandwidth`` (Hz) ride on the
active part. ``lead`` and ``trail`` are trimmed segments (zero increment) before and after:
the Boomerang 60 paper asks for trimmed level flight before and after each maneuver (after
Jategaonkar 2006), for a duration that is not legible in the source; 5 s is our default.

Signs follow flightid.channels: pulling up is trailing edge up, de < 0; a left roll is
da > 0 (Cl_da < 0); left rudder (nose left) is dr > 0.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from flightid.scenarios.input_design import InputDesign, check_time, require
from flightid.units import DEG


@dataclass(frozen=True)
class Plan:
    """Knots of a maneuver: phase durations (s) and surface values at the len+1 knots."""

    durations: tuple[float, ...]
    values: dict[str, tuple[float, ...]]


@dataclass(kw_only=True)
class PilotManeuver(InputDesign):
    """Base of the hand-flown maneuvers: trimmed lead/trail (s) and a seeded imperfect pilot."""

    kind: ClassVar[str] = ""
    lead: float = 5.0
    trail: float = 5.0
    seed: int = 0
    timing_sigma: float = 0.15  # s; assumption: RC pilot timing scatter
    amplitude_sigma: float = 0.1  # relative; assumption
    tremor: float = dataclasses.field(default=0.2 * DEG, metadata={"unit": "rad"})  # assumption
    tremor_bandwidth: float = 1.0  # Hz; assumption (human operator bandwidth, McRuer)

    def __post_init__(self) -> None:
        require(self.lead >= 0, "lead", f"must be >= 0 s, got {self.lead}")
        require(self.trail >= 0, "trail", f"must be >= 0 s, got {self.trail}")
        require(self.timing_sigma >= 0, "timing_sigma", f"must be >= 0, got {self.timing_sigma}")
        require(
            self.amplitude_sigma >= 0,
            "amplitude_sigma",
            f"must be >= 0, got {self.amplitude_sigma}",
        )
        require(self.tremor >= 0, "tremor", f"must be >= 0 rad, got {self.tremor}")
        require(
            self.tremor_bandwidth > 0,
            "tremor_bandwidth",
            f"must be > 0 Hz, got {self.tremor_bandwidth}",
        )

    def plan(self) -> Plan:
        """The nominal knots of the maneuver."""
        raise NotImplementedError

    def surfaces(self) -> tuple[str, ...]:
        return tuple(self.plan().values)

    def _flown(self) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray], float]:
        """Knot times (s, absolute), knot values, tremor knots per surface, active end (s)."""
        plan = self.plan()
        rng = np.random.default_rng(self.seed)
        d = np.asarray(plan.durations, float)
        d = np.maximum(d + self.timing_sigma * rng.standard_normal(d.size), 0.3 * d)
        t0 = self.start + self.lead
        knots = t0 + np.concatenate([[0.0], np.cumsum(d)])
        values: dict[str, np.ndarray] = {}
        for s, v in plan.values.items():
            v = np.asarray(v, float)
            out = v.copy()
            factor, prev = 1.0, None
            for i, x in enumerate(v):
                if x != prev:  # a new level: the pilot misjudges it afresh
                    factor = 1.0 + self.amplitude_sigma * rng.standard_normal()
                    prev = x
                out[i] = x * factor
            values[s] = out
        spacing = 1.0 / (2.0 * self.tremor_bandwidth)
        n_tremor = int(np.ceil((knots[-1] - knots[0]) / spacing)) + 1
        tremor: dict[str, np.ndarray] = {}
        for s in plan.values:
            amp = 0.0 if s == "throttle" else self.tremor
            w = amp * rng.standard_normal(n_tremor)
            w[0] = w[-1] = 0.0  # corrections start and stop with the maneuver
            tremor[s] = w
        return knots, values, tremor, float(knots[-1])

    @property
    def end(self) -> float:
        return self._flown()[3] + self.trail

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        t = check_time(t)
        knots, values, tremor, _ = self._flown()
        out = {}
        for s, v in values.items():
            u = np.interp(t, knots, v, left=0.0, right=0.0)
            w = tremor[s]
            tk = np.linspace(knots[0], knots[-1], w.size)
            out[s] = u + np.interp(t, tk, w, left=0.0, right=0.0)
        return out


@dataclass(kw_only=True)
class PullUpPushOver(PilotManeuver):
    """Pull-up then push-over for the short period (Boomerang 60 paper, Fig. 11).

    "An elevator deflection of -10 degrees is immediately applied and released over a
    period of 4 seconds" (section 5); then the opposite input starts the dive. ``amplitude``
    is the pull magnitude (rad, applied as de < 0); the push is ``push_ratio`` of it
    (assumption).
    """

    kind: ClassVar[str] = "pullup_pushover"
    amplitude: float = dataclasses.field(default=10 * DEG, metadata={"unit": "rad"})
    onset: float = 0.3  # s, "immediately applied": assumption
    release: float = 4.0  # s, Boomerang 60 paper
    pause: float = 1.0  # s, assumption
    push_ratio: float = 0.6  # assumption
    push_release: float = 3.0  # s, assumption

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("onset", "release", "pause", "push_release"):
            require(getattr(self, name) > 0, name, f"must be > 0 s, got {getattr(self, name)}")

    def plan(self) -> Plan:
        a, b = self.amplitude, self.push_ratio * self.amplitude
        return Plan(
            (self.onset, self.release, self.pause, self.onset, self.push_release),
            {"de": (0.0, -a, 0.0, 0.0, b, 0.0)},
        )


@dataclass(kw_only=True)
class ThrottleCut(PilotManeuver):
    """Throttle to idle with an elevator ramp to hold altitude, for the phugoid.

    "At circa 5 seconds, the throttle is reduced to idle and the elevator gradually
    increased to 20 degrees [from a 5 degree trim] to maintain constant altitude" (Monash
    Boomerang 60 paper, c. 2008, Fig. 14). ``drop`` is the throttle decrement (fraction; set
    it to the trim throttle for a cut to idle), ``elevator`` the nose-up increment magnitude
    (rad, applied as de < 0), then both are restored over ``recover`` s.
    """

    kind: ClassVar[str] = "throttle_cut"
    drop: float = 0.5
    elevator: float = dataclasses.field(default=15 * DEG, metadata={"unit": "rad"})
    cut_time: float = 0.5  # s, assumption
    ramp: float = 10.0  # s, "gradually": assumption
    hold: float = 5.0  # s, assumption
    recover: float = 2.0  # s, assumption

    def __post_init__(self) -> None:
        super().__post_init__()
        require(0 <= self.drop <= 1, "drop", f"throttle fraction 0..1, got {self.drop}")
        for name in ("cut_time", "ramp", "hold", "recover"):
            require(getattr(self, name) > 0, name, f"must be > 0 s, got {getattr(self, name)}")

    def plan(self) -> Plan:
        e = self.elevator
        return Plan(
            (self.cut_time, self.ramp, self.hold, self.recover),
            {
                "throttle": (0.0, -self.drop, -self.drop, -self.drop, 0.0),
                "de": (0.0, 0.0, -e, -e, 0.0),
            },
        )


def _roll_sign(direction: str) -> float:
    require(direction in ("left", "right"), "direction", f"'left' or 'right', got {direction!r}")
    return 1.0 if direction == "left" else -1.0  # da > 0 rolls left


@dataclass(kw_only=True)
class BankToBank(PilotManeuver):
    """Bank-to-bank roll: roll into a bank, hold, roll through to the other bank, roll out.

    Aileron pulses of ``amplitude`` (rad) for ``roll_time`` s (twice that for the
    reversal), ramps of ``ramp`` s, banks held ``hold`` s; rudder coordinated as
    dr = ``rudder_ratio`` * da (left aileron with left rudder). First roll ``direction``.
    """

    kind: ClassVar[str] = "bank_to_bank"
    amplitude: float = dataclasses.field(default=10 * DEG, metadata={"unit": "rad"})
    direction: str = "left"
    roll_time: float = 1.0
    ramp: float = 0.2
    hold: float = 3.0
    rudder_ratio: float = 0.3  # assumption

    def __post_init__(self) -> None:
        super().__post_init__()
        _roll_sign(self.direction)
        for name in ("roll_time", "ramp", "hold"):
            require(getattr(self, name) > 0, name, f"must be > 0 s, got {getattr(self, name)}")

    def _durations(self, hold: float) -> tuple[float, ...]:
        r, p = self.ramp, self.roll_time
        return (r, p, r, hold, r, 2 * p, r, hold, r, p, r)

    def _aileron(self) -> tuple[float, ...]:
        a = _roll_sign(self.direction) * self.amplitude
        return (0.0, a, a, 0.0, 0.0, -a, -a, 0.0, 0.0, a, a, 0.0)

    def plan(self) -> Plan:
        da = self._aileron()
        values = {"da": da}
        if self.rudder_ratio:
            values["dr"] = tuple(self.rudder_ratio * x for x in da)
        return Plan(self._durations(self.hold), values)


@dataclass(kw_only=True)
class FigureEight(BankToBank):
    """Figure of eight for the lateral modes (Boomerang 60 paper, Figs 10, 18A/B).

    "A left turn was initiated until a half circle was completed. Then the aircraft
    rolled in the opposite direction": banks held ``turn_time`` s (a half circle;
    pi V / (g tan phi), about 11 s at 20 m/s and 30 deg), with elevator back pressure
    ``back_pressure`` (rad, applied as de < 0) in the turns.
    """

    kind: ClassVar[str] = "figure_eight"
    turn_time: float = 10.0
    back_pressure: float = dataclasses.field(default=2 * DEG, metadata={"unit": "rad"})

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.turn_time > 0, "turn_time", f"must be > 0 s, got {self.turn_time}")

    def plan(self) -> Plan:
        da = self._aileron()
        bp = -self.back_pressure
        values = {"da": da, "de": (0.0, 0.0, bp, bp, bp, 0.0, 0.0, bp, bp, 0.0, 0.0, 0.0)}
        if self.rudder_ratio:
            values["dr"] = tuple(self.rudder_ratio * x for x in da)
        return Plan(self._durations(self.turn_time), values)
