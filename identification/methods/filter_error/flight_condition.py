"""The filter-error derivatives corrected for the flight condition drifting from the model's
reference condition during the record.

The linear model scales every aerodynamic term with the reference dynamic pressure q0
(and the rate derivatives, through p b / 2V, with 1 / V0): force and moment = q0 S C x.
In flight they are q(t) S C x (Morelli & Klein 2016 eq. 3.31-3.35: the coefficients are
nondimensional, the dynamic pressure is the measured one), and a constant-coefficient fit
returns each derivative multiplied by the dynamic pressure its information was gathered
at, relative to q0. In light turbulence the longitudinal gust moves q by about 3 %
(navion-demo: sigma 57 Pa of 1770), the phugoid after an elevator input moves it by
more, and the filter's tight fit turns this into errors of 20-50 of its Cramer-Rao
bounds on CY_beta, correlated +1.00 across flights with the information-weighted q / q0
(docs/montecarlo.md, "Filter error").

The correction is the first-order (one Gauss-Newton step) difference between the fit of
the constant-condition model and that of the model whose aerodynamic terms scale with the
measured condition, each aerodynamic term scaled by 1 + s_k, s_k = q_k / q0 - 1
(q_k / q0 - V_k / V0 for the rate derivatives). At the true parameters the constant
model's innovations are the time-varying model's (white) innovations e_k minus their
first-order change d_k (``innovation_change``: the predictor's sensitivity recursion
driven by s_k, the Kalman gain held), so

    theta_hat - theta = M^-1 sum_k dnu_k^T S^-1 d_k,

M the filter's information matrix at the estimate. Only models without an airspeed state
are corrected: a model with V as a state already varies its dynamic pressure, and so does
one driven by ``measured_inputs.with_dynamic_pressure`` (filter error's lateral default,
exact rather than first order).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flightid.identification.methods.filter_error.kalman_filter import FilterEvaluation
from flightid.identification.methods.output_error_problem import Problem
from flightid.identification.models.discrete import propagate
from flightid.identification.models.linear import LinearModel
from flightid.identification.models.measured_inputs import is_scheduled
from flightid.record import FlightRecord

# nondimensional rate derivatives: the rate enters as p b / 2V (q c / 2V, alphadot c / 2V)
RATE_SUFFIXES = ("_p", "_q", "_r", "_alphadot")
CHANNELS = ("qbar", "V")


@dataclass(frozen=True)
class ConditionDeparture:
    """Relative departures of the measured dynamic pressure and airspeed from the model's
    reference condition on the fit's time grid: q / q0 - 1 and V / V0 - 1 (N,)."""

    qbar: np.ndarray
    airspeed: np.ndarray


def condition_departure(record: FlightRecord, time: np.ndarray,
                        model: LinearModel) -> ConditionDeparture | None:
    """The departures of ``record``'s qbar and V channels from ``model``'s reference condition.

    Parameters
    ----------
    record : FlightRecord
        The flight, with channels qbar (Pa) and V (m/s).
    time : numpy.ndarray
        The fit's time grid, s, shape (N,); the channels are interpolated onto it.
    model : LinearModel
        The fitted linear model.

    Returns
    -------
    ConditionDeparture or None
        q / q0 - 1 and V / V0 - 1 (dimensionless, shape (N,)); None when the correction does
        not apply: the record lacks one of the channels, the model has no reference
        condition, it carries the airspeed as a state, or its aerodynamic terms already
        follow the measured qbar (``measured_inputs.with_dynamic_pressure``).
    """
    c = model.condition
    if (c is None or "V" in model.states or is_scheduled(model)
            or any(ch not in record for ch in CHANNELS)):
        return None
    t = np.asarray(record.time, dtype=float)

    def relative(channel: str, reference: float) -> np.ndarray:
        return np.interp(time, t, np.asarray(record[channel], dtype=float)) / reference - 1.0

    return ConditionDeparture(relative("qbar", c.qbar), relative("V", c.V))


def is_aerodynamic(name: str) -> bool:
    """Whether a parameter is a nondimensional aerodynamic derivative (CY_beta, Cl_p, CL_0, ...).

    These are the parameters whose terms scale with the dynamic pressure.

    Parameters
    ----------
    name : str
        Parameter name.

    Returns
    -------
    bool
        True for a derivative; False for biases and F_<state>.
    """
    return name.startswith("C") and "_" in name


def innovation_change(names: Sequence[str], theta: np.ndarray, ev: FilterEvaluation,
                      data: Problem, departure: ConditionDeparture) -> np.ndarray:
    """The innovations' first-order change when the aerodynamic terms follow the measured
    condition, sample by sample, instead of the reference (the Kalman gain held).

    The aerodynamic part of the filter's matrices at sample k is scaled by 1 + s_k: with
    the directions dPhi = sum_j theta_j dPhi/dtheta_j over the static (or the rate)
    derivatives, and the same for Gamma, C and D, the predictor's sensitivity recursion
    (``kalman_filter.evaluate``) is driven by s_k times its forcing.

    Parameters
    ----------
    names : sequence of str
        The estimated parameters.
    theta : numpy.ndarray
        Their values, shape (np,).
    ev : FilterEvaluation
        The filter's evaluation at ``theta``, with sensitivities.
    data : Problem
        The fit's record (inputs, outputs, held inputs).
    departure : ConditionDeparture
        Relative departures of qbar and V (``condition_departure``).

    Returns
    -------
    numpy.ndarray
        d, shape (N, ny), in the outputs' units.
    """
    aero = np.array([is_aerodynamic(n) for n in names])
    rate = np.array([is_aerodynamic(n) and n.endswith(RATE_SUFFIXES) for n in names])
    flt, x, grads = ev.flt, ev.x, ev.matrix_sensitivities
    gain = flt.phi @ flt.K
    closed = flt.phi - gain @ flt.C
    change = np.zeros_like(ev.nu)
    for weights, s in ((np.where(aero & ~rate, theta, 0.0), departure.qbar),
                       (np.where(rate, theta, 0.0), departure.qbar - departure.airspeed)):
        d_phi, d_gamma, d_c, d_d = (np.tensordot(weights, grads[m], axes=1)
                                    for m in ("phi", "gamma", "C", "D"))
        d_gain = d_phi @ flt.K
        d_closed = d_phi - d_gain @ flt.C - gain @ d_c
        forcing = s[:, None] * (x @ d_closed.T + (data.z - data.u @ flt.D.T) @ d_gain.T
                                - data.u @ d_d.T @ gain.T + data.w @ d_gamma.T)
        sens = propagate(closed, forcing, np.zeros(x.shape[1]))
        change -= sens @ flt.C.T + s[:, None] * (x @ d_c.T + data.u @ d_d.T)
    return change


def condition_correction(information: np.ndarray, sensitivities: np.ndarray,
                         innovation_weight: np.ndarray, scaled: np.ndarray) -> np.ndarray:
    """The parameter error the drifting condition causes, M^-1 sum_k dnu_k^T W d_k.

    Parameters
    ----------
    information : numpy.ndarray
        The filter's information matrix M at the estimate, shape (np, np).
    sensitivities : numpy.ndarray
        Innovation sensitivities dnu/dtheta, shape (N, ny, np).
    innovation_weight : numpy.ndarray
        W = S^-1, shape (ny, ny).
    scaled : numpy.ndarray
        d = ``innovation_change``, shape (N, ny).

    Returns
    -------
    numpy.ndarray
        The correction, shape (np,), in the parameters' units, to subtract from the
        estimate.
    """
    rhs = np.einsum("iaj,ab,ib->j", sensitivities, innovation_weight, scaled)
    return np.linalg.solve(information, rhs)
