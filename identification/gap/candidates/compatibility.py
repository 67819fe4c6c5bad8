"""A lag or delay on an accelerometer, seen in the data-compatibility relation.

The output-error fit of a ``lag`` or ``delay`` of ``ay`` or ``az`` (``candidates.sensor``)
compares the measured acceleration with the model's: in turbulence most of the side and
normal acceleration is the gusts' (not in the model), so the time constant that fits the
maneuver part is lost in it (blind check, seed 8: accelerometer lags of 0.06-0.09 s fitted
worse than the model as is, delta BIC +660 to +4000). The relation between measured
channels holds through turbulence (equation error, Morelli & Klein 2016 ch. 5; data
compatibility, ch. 10): the acceleration is a linear function of the measured flow angle,
rates and surfaces (``nonlinearity.known_regressors``), and a sensor lag 1/(tau s + 1) on
the acceleration makes the measured a_m obey a_m + tau da_m/dt = a (a delay exp(-tau s)
the same to first order in tau s: one class). So tau is the negative coefficient of the
target's own rate, regressed beside the known set (Frisch-Waugh-Lovell: both residualised
on it first), tested with the window test's colored-residual Wald statistic
(``verdict.channel_test``), and checked held out: each window's coefficient taken from
the other windows must lower that window's residual energy.

The rate of stationary noise is uncorrelated with the noise at the same instant (its
autocorrelation is even), so the sensor noise does not bias the coefficient.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.gap.candidates.gyro_scale import GyroScale
from flightid.identification.gap.candidates.sensor import delay, lag
from flightid.identification.gap.fit import WindowFit
from flightid.identification.gap.model.edits import Candidate
from flightid.identification.gap.nonlinearity import known_regressors, signals
from flightid.identification.gap.verdict import ChannelTest, channel_test, p_text
from flightid.identification.gap.window.regressors import highpass
from flightid.record import FlightRecord

ACCELEROMETERS = {"lateral": "ay", "longitudinal": "az"}
# found when the partial p is below the first and the share (the energy the rate explains
# beyond the known set, chance removed, over what the known set leaves) at or above the
# second; set above the null flights of the blind check (docs/gap_benchmark.md, "The rules
# for the seed-9 run")
LEVEL = (1e-7, 0.03)
# a sensor pipeline's lag: above what the plain aircraft's record shows (the blind check's
# null flights: ay 0.005-0.010 s behind the vane and rates, az up to 0.005 s; the sample
# offsets of the simulated sensors), below the maneuvers' time scale
TAU_RANGE_S = (0.03, 0.5)
# the relation must explain this share of the measured acceleration (with the lag taken) to
# time a sensor by: the research suite's records 0.99-1.000 (null flights of the blind
# check), the hobby suite's (8-bit 25 Hz vanes, a 0.02 g accelerometer) 0.70, its noise
# leaving an apparent ay delay of 0.11 s on a plain Telemaster
RELATION_HOLDS = 0.9
DELAY_GRID_S = np.arange(0.0, 0.305, 0.005)  # the delays tried, s (0 first: none)


@dataclass
class SensorLag:
    """The lag or delay of one accelerometer in the data-compatibility relation."""

    channel: str
    entry: str  # "lag" or "delay": the form that explains more of the relation
    tau: float  # s
    std: float  # s
    test: ChannelTest
    # per window: the residual energy that the other windows' tau removes from it, over
    # what the known set leaves of it (positive: better held out)
    heldout: dict[str, float] = field(default_factory=dict)

    @property
    def note(self) -> str:
        """The evidence, in words."""
        return (f"seen in the relation of {self.channel} to the measured flow angle, rates "
                f"and surfaces (data compatibility): tau {self.tau:.3f} +- {self.std:.3f} s, "
                f"p {p_text(self.test.p_value)}, share {self.test.share:.2f}, held-out share "
                f"{self.pooled:.2f}")

    # the held-out windows pooled: the residual energy removed over what the known set
    # leaves (the cross-validated evidence, Stone 1974)
    pooled: float = math.nan
    # the share of the measured target that the known set explains (the relation's fit)
    related: float = math.nan

    @property
    def holds(self) -> float:
        """The share of the measured target's energy that the relation explains with the lag
        or delay taken: 1 - (1 - related) (1 - share)."""
        return 1.0 - (1.0 - self.related) * (1.0 - self.test.share)

    @property
    def found(self) -> bool:
        """Significant, material, in range, better on the held-out windows pooled, and the
        relation exact enough to time a sensor by (``RELATION_HOLDS``)."""
        return bool(self.test.passes(*LEVEL)
                    and TAU_RANGE_S[0] <= self.tau <= TAU_RANGE_S[1] and self.pooled > 0
                    and self.holds >= RELATION_HOLDS)

    def corrected(self, measured: np.ndarray, time: np.ndarray) -> np.ndarray:
        """The accelerometer's measured samples with the lag or delay undone: a lag's
        a_m + tau da_m/dt, a delay's a_m(t + tau) (the last samples held)."""
        a = np.asarray(measured, float)
        return (a + self.tau * np.gradient(a, time) if self.entry == "lag"
                else np.interp(time + self.tau, time, a))

    def candidate(self) -> tuple[Candidate, dict[str, float], dict[str, float]]:
        """The linear model's ``lag`` or ``delay`` candidate at this time constant, and its
        std (s)."""
        cand = (lag if self.entry == "lag" else delay)(self.channel)
        (name,) = cand.free
        return cand, {name: self.tau}, {name: self.std}

    def to_json(self) -> dict:
        return {"entry": self.entry, "channel": self.channel, "tau_s": self.tau,
                "std_s": self.std, "p_value": self.test.p_value, "share": self.test.share,
                "heldout_gain": self.heldout, "heldout_pooled": self.pooled,
                "related": self.related, "holds": self.holds,
                "found": self.found}


def _residualised(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    return y - x @ coef


def _gains(pairs: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> tuple[dict, float]:
    """Per window and pooled: the energy of what the known set leaves (the first of each
    pair) that the held-out estimate removes (the second: what it leaves), over the first."""
    per, removed, left = {}, 0.0, 0.0
    for k, (y, r) in pairs.items():
        e = float(y @ y)
        per[k] = (e - float(r @ r)) / e if e > 0 else 0.0
        removed, left = removed + e - float(r @ r), left + e
    return per, (removed / left if left > 0 else math.nan)


def _lag(ys: dict, xs: dict, target: str) -> SensorLag | None:
    """The lag: tau the negative coefficient of the target's own rate."""
    y, x = np.concatenate(list(ys.values())), np.concatenate(list(xs.values()))
    if x @ x <= 0:
        return None
    test = channel_test(y, x[:, None], float(y @ y), target)
    coef = float(x @ y / (x @ x))
    std = abs(coef) / math.sqrt(test.statistic) if test.statistic > 0 else math.inf
    pairs = {}
    for k in ys if len(ys) > 1 else ():
        xo = np.concatenate([xs[j] for j in ys if j != k])
        yo = np.concatenate([ys[j] for j in ys if j != k])
        c = float(xo @ yo / (xo @ xo)) if xo @ xo > 0 else 0.0
        pairs[k] = (ys[k], ys[k] - c * xs[k])
    return SensorLag(target, "lag", -coef, std, test, *_gains(pairs))


def _delay(shifted: dict, target: str) -> SensorLag | None:
    """The delay: tau the shift of the measured target, on ``DELAY_GRID_S``, that leaves
    least of it unexplained by the known set; the test is that of the shifted-less-measured
    target as one regressor."""
    labels = list(shifted)

    def costs(keys: list[str]) -> list[float]:
        return [sum(float(shifted[k][i] @ shifted[k][i]) for k in keys)
                for i in range(len(DELAY_GRID_S))]

    def best(keys: list[str]) -> int:
        return int(np.argmin(costs(keys)))

    cost = costs(labels)
    i = int(np.argmin(cost))
    if i == 0:
        return None
    step = DELAY_GRID_S[1] - DELAY_GRID_S[0]
    tau = float(DELAY_GRID_S[i])
    if i + 1 < len(cost):  # the parabola through the least cost and its neighbours
        curve = cost[i - 1] - 2 * cost[i] + cost[i + 1]
        tau += 0.5 * step * (cost[i - 1] - cost[i + 1]) / curve if curve > 0 else 0.0
    y = np.concatenate([shifted[k][0] for k in labels])
    x = np.concatenate([shifted[k][i] - shifted[k][0] for k in labels])
    test = channel_test(y, x[:, None], float(y @ y), target)
    pairs = {k: (shifted[k][0], shifted[k][best([o for o in labels if o != k])])
             for k in (labels if len(labels) > 1 else ())}
    # the standard error from the windows' own delays (their spread over sqrt(n)): the
    # colored residual makes a bound from the cost's curvature too small
    own = [float(DELAY_GRID_S[best([k])]) for k in labels]
    std = float(np.std(own, ddof=1)) / math.sqrt(len(own)) if len(own) > 1 else step
    return SensorLag(target, "delay", tau, max(std, step / math.sqrt(12)), test,
                     *_gains(pairs))


def sensor_lag(fits: Mapping[str, WindowFit], records: Mapping[str, FlightRecord],
               inputs: Sequence[str], axis: str) -> SensorLag | None:
    """The accelerometer lag or delay of ``axis`` in the data-compatibility relation (module
    note): the lag's form (the target's own rate) and the delay's (the target shifted) both
    fitted, the one that explains more kept.

    Parameters
    ----------
    fits : mapping of str to WindowFit
        The model as is on each window (for the windows' time and measured outputs).
    records : mapping of str to FlightRecord
        The windows' records (inputs, airspeed, thrust).
    inputs : sequence of str
        The axis's surface channels.
    axis : str
        "lateral" (ay) or "longitudinal" (az).

    Returns
    -------
    SensorLag or None
        The form, time constant (s), its standard error, the test and the held-out gains;
        None when the windows lack the accelerometer.
    """
    target = ACCELEROMETERS.get(axis)
    labels = [k for k in fits if k in records]
    if target is None or not labels:
        return None
    ys, xs, shifted, energy = {}, {}, {}, 0.0
    for k in labels:
        sig = signals(fits[k], records[k], axis, inputs)
        t = fits[k].time
        if target not in sig or len(t) < 4:
            return None
        dt = float(np.median(np.diff(t)))
        keep = slice(0, len(t) - int(math.ceil(DELAY_GRID_S[-1] / dt)) - 1)
        known = highpass(known_regressors(sig, dt, axis, target, inputs), dt)
        known = known[keep][:, np.sqrt(np.sum(known[keep] ** 2, axis=0)) > 0]
        y = highpass(sig[target], dt)[keep]
        energy += float(y @ y)
        ys[k] = _residualised(y, known)
        xs[k] = _residualised(highpass(np.gradient(sig[target], dt), dt)[keep], known)
        shifted[k] = [_residualised(highpass(np.interp(t + d, t, sig[target]), dt)[keep], known)
                      for d in DELAY_GRID_S]
    if not all(np.all(np.isfinite(v)) for v in (*ys.values(), *xs.values())):
        return None
    found = [f for f in (_lag(ys, xs, target), _delay(shifted, target)) if f is not None]
    left = sum(float(y @ y) for y in ys.values())
    for f in found:
        f.related = 1.0 - left / energy if energy > 0 else math.nan
    return max([f for f in found if f.found] or found, key=lambda f: f.test.share,
               default=None)


def undone(fits: Mapping[str, WindowFit],
           found: SensorLag | GyroScale) -> dict[str, WindowFit]:
    """The windows' fits with the sensor's measurement undone by ``found`` (an
    accelerometer's lag or delay, a gyro's scale), for the tests that read the measured
    channels (``nonlinearity.nonlinear_test``).

    Parameters
    ----------
    fits : mapping of str to WindowFit
        The windows' fits.
    found : SensorLag or GyroScale
        The sensor's lag, delay or scale.

    Returns
    -------
    dict of str to WindowFit
        The fits with the channel's measured samples corrected (the rest unchanged).
    """
    return {k: (dataclasses.replace(f, measured={
        **f.measured, found.channel: found.corrected(f.measured[found.channel], f.time)})
        if found.channel in f.measured else f) for k, f in fits.items()}

