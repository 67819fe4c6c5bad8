"""A rate gyro's scale seen in the attitude kinematics (data compatibility).

The Euler-angle kinematics hold whatever the air does (Stevens, Lewis & Johnson 2016,
eq. 1.4-4; the kinematic consistency of Morelli & Klein 2016 ch. 10, Jategaonkar 2015
ch. 10):

    phi_dot   = p + tan(theta) (q sin(phi) + r cos(phi))
    theta_dot = q cos(phi) - r sin(phi)

A gyro reading k times the rate (p_m = k p) leaves the measured attitude's rate short of
it: the residual of the nominal relation, e = phi_m_dot - p_m - tan(theta)(...), is
(1/k - 1) p_m plus noise. So c = 1/k - 1 is the coefficient of the measured rate in e
(``x``), fitted beside nuisance regressors that are not tested (``z``): the relation's
other term (it carries the other gyros, which may be off too), the rate's first and second
derivatives (a time offset tau between the attitude and the gyro: p(t + tau) = p + tau
p_dot + tau^2 / 2 p_ddot + ..., whose second-order term alone reads as a scale of
1 + (omega tau)^2 / 2, 7 % for a 0.12 s gyro delay at 3 rad/s) and a constant (the gyro's
bias), and on the
lateral axis the yaw rate (an IMU pitched by a on its mount reads p cos a - r sin a). The
test is the window test's colored-residual Wald statistic (``verdict.channel_test``);
each window's c taken from the other windows must lower that window's residual (held
out). Both sides go through the same zero-phase low-pass (``LOWPASS_HZ``), which keeps
the relation and takes the differentiated attitude's noise out.

The relation sees the ratio of the two sensors: an attitude reading k_phi times the angle
gives c = k_phi - 1 to first order, the same as a gyro of 1 / k_phi. The report names the
gyro (the benchmark's catalogue draws gyro scales, not attitude scales) and says so. An
attitude computed from the same gyros (an AHRS that integrates them) obeys the relation
whatever their scale: such a record cannot show it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from flightid.identification.gap.candidates.ranges import INERTIAL_SCALE
from flightid.identification.gap.candidates.sensor import scale
from flightid.identification.gap.model.edits import Candidate
from flightid.identification.gap.verdict import ChannelTest, channel_test, p_text
from flightid.record import FlightRecord

# per axis: (the gyro, the attitude whose rate it drives)
GYROS = {"lateral": ("p", "phi"), "longitudinal": ("q", "theta")}
# found when the p is below the first and |k - 1| at or above the second. The blind
# check's null flights in light turbulence (seeds 0, 12 and 13, 300 flights, four
# aircraft, each in four windows) give k of 0.998-1.002 on both gyros; gyro delays and
# lags, IMU misalignments and structural modes at most 0.009 off; its drawn gyro scales
# are 10-35 % off (docs/gap_benchmark.md, "The rules for the seed-14 run")
LEVEL = (1e-7, 0.02)
LOWPASS_HZ = 1.0  # both sides of the relation, zero phase (a structural mode above 3 Hz out)
EDGE_S = 0.5  # cut at each end of a window, s (the filter's start and end)


@dataclass
class GyroScale:
    """The scale of one rate gyro in the attitude kinematics."""

    channel: str  # the gyro: "p" or "q"
    attitude: str  # the attitude whose rate it drives: "phi" or "theta"
    factor: float  # k: the gyro reads k times the rate
    std: float
    test: ChannelTest
    # per window: the residual energy that the other windows' c removes from it, over what
    # the nuisance regressors leave of it (positive: better held out)
    heldout: dict[str, float] = field(default_factory=dict)
    pooled: float = math.nan  # the held-out windows pooled

    @property
    def note(self) -> str:
        """The evidence, in words."""
        return (f"seen in the attitude kinematics (data compatibility: d{self.attitude}/dt "
                f"against {self.channel}): {self.channel} reads {self.factor:.4f} +- "
                f"{self.std:.4f} times the rate ({self.attitude} scale "
                f"{1.0 / self.factor:.4f} reads the same), p {p_text(self.test.p_value)}, "
                f"held-out share {self.pooled:.2f}")

    @property
    def found(self) -> bool:
        """Significant, material (``LEVEL``), a factor a calibrated gyro can have
        (``ranges.INERTIAL_SCALE``) and better on the held-out windows pooled."""
        alpha, material = LEVEL
        return bool(self.test.p_value < alpha and abs(self.factor - 1.0) >= material
                    and INERTIAL_SCALE[0] <= self.factor <= INERTIAL_SCALE[1]
                    and self.pooled > 0)

    def corrected(self, measured: np.ndarray, time: np.ndarray) -> np.ndarray:
        """The gyro's measured samples with the scale undone (rad/s)."""
        return np.asarray(measured, float) / self.factor

    def candidate(self) -> tuple[Candidate, dict[str, float], dict[str, float]]:
        """The linear model's ``scale`` candidate at this factor, and its std."""
        cand = scale(self.channel)
        (name,) = cand.free
        return cand, {name: self.factor}, {name: self.std}


def _relation(record: FlightRecord, axis: str) -> tuple[np.ndarray, ...] | None:
    """The residual of the nominal relation, the gyro, and the nuisance regressors of one
    window, filtered and cut (None without the channels or samples)."""
    attitude = GYROS[axis][1]
    if not all(c in record for c in ("phi", "theta", "p", "q", "r")):
        return None
    t = np.asarray(record.time, float)
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    edge = int(math.ceil(EDGE_S / dt)) if dt > 0 else 0
    if dt <= 0 or len(t) < 4 * edge + 16 or LOWPASS_HZ * 2 * dt >= 1.0:
        return None
    phi, theta, p, q, r = (np.asarray(record[c], float) for c in ("phi", "theta", "p", "q",
                                                                    "r"))
    if axis == "lateral":  # r beside: an IMU pitched on its mount reads p cos a - r sin a
        rate, other, beside = p, np.tan(theta) * (q * np.sin(phi) + r * np.cos(phi)), [r]
    else:
        rate, other, beside = q * np.cos(phi), -r * np.sin(phi), []
    b, a = signal.butter(4, LOWPASS_HZ * 2 * dt)
    rdot = np.gradient(rate, dt)
    low = [signal.filtfilt(b, a, v) for v in
           (np.gradient(phi if attitude == "phi" else theta, dt) - rate - other, rate,
            other, rdot, np.gradient(rdot, dt), *beside)]
    keep = slice(edge, len(t) - edge)
    e, x, *z = (v[keep] for v in low)
    return e, x, np.column_stack([*z, np.ones_like(e)])


def _residual(e: np.ndarray, x: np.ndarray, z: np.ndarray, c: float | None) -> np.ndarray:
    """What the nuisance regressors leave of e (with c x taken out first, when given)."""
    y = e if c is None else e - c * x
    coef, *_ = np.linalg.lstsq(z, y, rcond=None)
    return y - z @ coef


def gyro_scale(records: Mapping[str, FlightRecord], axis: str) -> GyroScale | None:
    """The scale of ``axis``'s gyro (p lateral, q longitudinal) in the attitude kinematics
    (module note).

    Parameters
    ----------
    records : mapping of str to FlightRecord
        The windows' records by label: phi, theta, p, q, r (rad, rad/s).
    axis : str
        "lateral" or "longitudinal".

    Returns
    -------
    GyroScale or None
        The factor k (the gyro reads k times the rate), its standard error, the test and
        the held-out gains; None when the windows lack an attitude or a rate.
    """
    if axis not in GYROS:
        return None
    parts = {}
    for k in records:
        got = _relation(records[k], axis)
        if got is None:
            return None
        parts[k] = got
    if not parts:
        return None
    e, x, z = (np.concatenate([v[i] for v in parts.values()]) for i in range(3))
    if not (np.all(np.isfinite(e)) and np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
        return None
    test = channel_test(e, x[:, None], float(e @ e), GYROS[axis][0], z)
    c = float(np.linalg.lstsq(np.column_stack([x, z]), e, rcond=None)[0][0])
    if c <= -1.0:
        return None
    std_c = abs(c) / math.sqrt(test.statistic) if test.statistic > 0 else math.inf
    per, removed, left = {}, 0.0, 0.0
    for k, (ek, xk, zk) in parts.items() if len(parts) > 1 else ():
        others = [j for j in parts if j != k]
        eo, xo, zo = (np.concatenate([parts[j][i] for j in others]) for i in range(3))
        co = float(np.linalg.lstsq(np.column_stack([xo, zo]), eo, rcond=None)[0][0])
        before, after = _residual(ek, xk, zk, None), _residual(ek, xk, zk, co)
        energy = float(before @ before)
        per[k] = (energy - float(after @ after)) / energy if energy > 0 else 0.0
        removed, left = removed + energy - float(after @ after), left + energy
    return GyroScale(GYROS[axis][0], GYROS[axis][1], 1.0 / (1.0 + c),
                     std_c / (1.0 + c) ** 2, test, per,
                     removed / left if left > 0 else math.nan)

