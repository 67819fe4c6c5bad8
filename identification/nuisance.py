"""The nuisance biases of a linear-model fit, split into what the trim explains and what is
left, and checked against what an instrument can have.

The linear models take the *measured* (absolute) states, so their biases absorb the trim
terms (``linear_models``: CL_0 and gravity in the az bias, a trim deflection's moment in
the qdot bias, ...): a bias of 15 m/s^2 on az can be the trim's lift and nothing wrong.
Each bias is split:

- **trim part**: the value the bias takes when the fitted model balances at the record's
  mean state and inputs. A state equation's rate is then the record's mean rate (its
  change over the window divided by the window's length). An accelerometer reads the
  specific force of the mean state: f_y = V (beta_dot + r - p alpha) - g cos(theta)
  sin(phi) and f_z = V (alpha_dot - q + p beta) - g cos(theta) cos(phi), body axes, z
  down: the force equations (Stevens, Lewis & Johnson 2016, eqs. 1.7-18 to 1.7-21;
  Morelli & Klein 2016, eqs. 3.32-3.38) with u = V, v = V beta, w = V alpha, as flight
  path reconstruction uses them (Jategaonkar 2015, ch. 10), averaged over the window;
- **excess**: the rest, fitted minus trim part. On the accelerometer outputs it is the
  accelerometer's bias as the kinematics see it; on a state equation it is the rate the
  fitted model has at the mean condition, which a consistent model does not have.

An excess beyond what an instrument can have (``LIMITS``: 0.2 g on a specific force, a
gyro's 5 deg/s on an angle's rate, the angular acceleration a 5 deg/s gyro bias would
need on a rate equation) is a sign that the model or its reference condition does not
fit the data (units, sign or position of a channel, mass, geometry), never an
instrument's bias.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields

import numpy as np

from flightid.identification.estimate import Estimate
from flightid.identification.models.a_priori import preset_derivatives
from flightid.identification.models.presets import MODELS, model_for_record
from flightid.record import FlightRecord
from flightid.units import DEG, G0

BIAS_PREFIX = "bias_"
ACCELEROMETER_LIMIT = 0.2 * G0  # m/s^2: an uncalibrated MEMS accelerometer's null offset
# is below 0.1 g (the hobby suite assumes 0.02 g); twice that is no instrument's
GYRO_LIMIT = 5.0 * DEG  # rad/s: an uncalibrated MEMS gyro's null offset is a few deg/s
# the state equations whose rate is an angle's rate (rad/s), a speed's (m/s^2), or an
# angular acceleration (rad/s^2); output biases on the accelerometers (m/s^2)
ANGLES = ("alpha", "beta", "phi", "theta")
RATES = ("p", "q", "r")
ACCELEROMETERS = ("ay", "az")


class ImplausibleBiasWarning(UserWarning):
    """A fitted nuisance bias beyond what an instrument can have, after its trim part."""


@dataclass(frozen=True)
class BiasTerm:
    """One nuisance bias of a fit: ``value`` and ``std`` as fitted, ``trim`` its part that
    the trim explains, ``excess`` = value - trim, ``limit`` the largest excess an
    instrument can have (all in ``unit``), ``instrument`` what the limit stands for."""

    name: str
    unit: str
    value: float
    std: float
    trim: float
    excess: float
    limit: float
    instrument: str

    @property
    def implausible(self) -> bool:
        """Whether the excess is beyond the limit by more than its 3-sigma bound."""
        return abs(self.excess) > self.limit + 3.0 * (self.std if np.isfinite(self.std)
                                                      else 0.0)

    def to_json(self) -> dict[str, object]:
        """The term as plain data, with ``implausible``."""
        return {**asdict(self), "implausible": self.implausible}


def from_fit(est: Estimate) -> list[BiasTerm]:
    """The bias terms ``identify`` stored in ``est.fit['biases']``.

    Parameters
    ----------
    est : Estimate
        An estimate from ``identify``.

    Returns
    -------
    list of BiasTerm
        The stored terms; [] when none.
    """
    keys = {f.name for f in fields(BiasTerm)}
    return [BiasTerm(**{k: v for k, v in t.items() if k in keys})
            for t in est.fit.get("biases", [])]


def _mean_rate(record: FlightRecord, channel: str) -> float:
    x = record[channel]
    span = float(record.time[-1] - record.time[0])
    return float((x[-1] - x[0]) / span) if span > 0 else 0.0


def _channel(record: FlightRecord, name: str) -> np.ndarray:
    return record[name] if name in record else np.zeros(len(record))


def specific_force(record: FlightRecord, output: str) -> float:
    """The mean specific force an unbiased accelerometer at the CG reads on ``output``.

    Computed over ``record`` from its airspeed, angles and rates (module note).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    output : str
        "ay" or "az".

    Returns
    -------
    float
        The mean specific force, m/s^2.

    Raises
    ------
    ValueError
        When ``output`` is neither "ay" nor "az".
    """
    t, v = record.time, record["V"]
    alpha, beta = _channel(record, "alpha"), _channel(record, "beta")
    p, q, r = (_channel(record, c) for c in RATES)
    theta, phi = _channel(record, "theta"), _channel(record, "phi")
    if output == "ay":
        f = v * (np.gradient(beta, t) + r - p * alpha) - G0 * np.cos(theta) * np.sin(phi)
    elif output == "az":
        f = v * (np.gradient(alpha, t) - q + p * beta) - G0 * np.cos(theta) * np.cos(phi)
    else:
        raise ValueError(f"no specific force for output {output!r}; known: ay, az")
    return float(np.mean(f))


def bias_budget(est: Estimate, record: FlightRecord, preset: str) -> list[BiasTerm]:
    """The nuisance biases of ``est``, each split into its trim part and its excess.

    See the module note for the split.

    Parameters
    ----------
    est : Estimate
        A fit of the linear model ``preset`` on ``record``.
    record : FlightRecord
        The window the fit was made on, SI channels.
    preset : str
        The linear model preset name.

    Returns
    -------
    list of BiasTerm
        One term per fitted state-derivative or accelerometer bias; [] when the fit has no
        bias, ``preset`` is not a linear model or the record lacks a model channel.
    """
    fitted = {n: (float(v), float(s)) for n, v, s in zip(est.names, est.values, est.std,
                                                           strict=True)}
    if preset not in MODELS or not any(n.startswith(BIAS_PREFIX) for n in fitted):
        return []
    # the parameters the fit held (a priori, or unidentifiable and kept at their start) are
    # part of the fitted model: without them a held CL_0 (2 CL_0 dV/V with the measured,
    # absolute V) would be read as an excess of the alphadot and az biases
    held = {n: float(v) for n, v in est.fit.get("fixed", {}).items()}
    derivatives = [n for n in preset_derivatives(preset) if n in fitted or n in held] or None
    model = model_for_record(preset, record, **({"derivatives": derivatives}
                                                if derivatives else {}))
    values = {n: v for n, v in {**held, **{n: v for n, (v, _) in fitted.items()}}.items()
              if n in model.parameters}
    a, b, c, d = model.matrices(values)
    missing = [ch for ch in (*model.inputs, *model.state_channels.values(), *model.outputs)
               if ch not in record]
    if missing:
        return []
    x = np.array([np.mean(record[model.state_channels[s]]) for s in model.states])
    u = np.array([*(np.mean(record[i]) for i in model.inputs), 0.0])
    out: list[BiasTerm] = []
    for i, state in enumerate(model.states):
        name = f"{BIAS_PREFIX}{state}dot"
        if name not in fitted:
            continue
        unit, limit, instrument = _state_limit(state, a[i, i])
        excess = float(a[i] @ x + b[i] @ u + b[i, -1]) - _mean_rate(
            record, model.state_channels[state])
        out.append(_term(name, unit, fitted[name], excess, limit, instrument))
    for j, output in enumerate(model.outputs):
        name = f"{BIAS_PREFIX}{output}"
        if name not in fitted or output not in ACCELEROMETERS:
            continue
        excess = float(c[j] @ x + d[j] @ u + d[j, -1]) - specific_force(record, output)
        out.append(_term(name, "m/s^2", fitted[name], excess, ACCELEROMETER_LIMIT,
                         "an accelerometer's bias"))
    return out


def _state_limit(state: str, damping: float) -> tuple[str, float, str]:
    if state in ANGLES:
        return "rad/s", GYRO_LIMIT, "a gyro's bias"
    if state in RATES:
        return ("rad/s^2", GYRO_LIMIT * max(abs(float(damping)), 1.0),
                "the angular acceleration a gyro's bias needs")
    return "m/s^2", ACCELEROMETER_LIMIT, "an accelerometer's bias"


def _term(name: str, unit: str, fitted: tuple[float, float], excess: float, limit: float,
          instrument: str) -> BiasTerm:
    value, std = fitted
    return BiasTerm(name, unit, value, std, value - excess, excess, limit, instrument)


def describe(terms: Sequence[BiasTerm]) -> list[str]:
    """One line per bias: value, trim part, excess and its limit.

    An implausible excess says what it means.

    Parameters
    ----------
    terms : sequence of BiasTerm
        The bias terms.

    Returns
    -------
    list of str
        One line per term.
    """
    lines = []
    for t in terms:
        line = (f"{t.name} = {t.value:.4g} {t.unit}: trim {t.trim:.4g}, excess "
                f"{t.excess:.3g} (limit {t.limit:.3g}, {t.instrument})")
        if t.implausible:
            line += (": beyond any instrument; the model or its reference condition does "
                     "not fit the data (check the channels' units, signs and sensor "
                     "positions, the mass and the geometry)")
        lines.append(line)
    return lines


def warn_implausible(terms: Sequence[BiasTerm], what: str) -> None:
    """An ImplausibleBiasWarning naming each bias whose excess is beyond an instrument.

    Parameters
    ----------
    terms : sequence of BiasTerm
        The bias terms.
    what : str
        What the biases belong to, the warning's first words.
    """
    bad = [t for t in terms if t.implausible]
    if bad:
        warnings.warn(f"{what}: nuisance bias(es) beyond what an instrument can have: "
                      + "; ".join(describe(bad)), ImplausibleBiasWarning, stacklevel=2)
