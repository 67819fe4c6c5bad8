"""State-space fits to frequency responses with the CIFER cost, and their time-domain
verification on a maneuver not used for fitting.

* ``fit_state_space``: the CIFER cost of ``transfer_function`` summed over the
  frequency responses of several input-output pairs (Tischler & Remple ch. 11; seed
  004 sec. 5.3), with Cramer-Rao bounds and insensitivities.
* ``verify_time_domain``: the fitted model flown on a maneuver not used for fitting,
  with output biases and reference shifts fitted by linear least squares, scored by
  J_rms (Tischler & Remple eq. 12.2; <= 1-2 is good) and Theil's inequality coefficient
  per output.

Frequencies are in Hz.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import StateSpace, lsim

from flightid.identification.estimate import Estimate
from flightid.identification.frequency.response import FrequencyResponse
from flightid.identification.frequency.state_space_fit import _split_bias
from flightid.identification.frequency.transfer_function import (
    COHERENCE_MIN,
    central_jacobian,
    cifer_residuals,
)
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord
from flightid.units import DEG, FT


# ----------------------------------------------------------------------------- CIFER state space
def model_response(model: LinearModel, values: Mapping[str, float], output: str, input: str,
                   frequency: np.ndarray) -> np.ndarray:
    """Model frequency response output/input at ``frequency``.

    Parameters
    ----------
    model : LinearModel
        The linear model.
    values : mapping of str to float
        Its parameter values.
    output : str
        A model output.
    input : str
        A model input.
    frequency : numpy.ndarray
        Frequencies, Hz.

    Returns
    -------
    numpy.ndarray
        The complex response, SI per SI; shape of ``frequency``.
    """
    a, b, c, d = _split_bias(model, values)
    i, j = model.outputs.index(output), model.inputs.index(input)
    eye = np.eye(a.shape[0])
    s = 2j * np.pi * np.asarray(frequency, dtype=float)
    return np.array([c[i] @ np.linalg.solve(sk * eye - a, b[:, j]) + d[i, j] for sk in s])


def fit_state_space(
    responses: Sequence[FrequencyResponse],
    model: LinearModel,
    *,
    estimate: Sequence[str] | None = None,
    coherence_min: float = COHERENCE_MIN,
    start: Mapping[str, float] | None = None,
) -> Estimate:
    """Fit a linear model to measured frequency responses with the CIFER cost.

    The total cost is the sum of the pair costs; ``fit['cost_per_pair']`` and
    ``fit['average_cost']`` are the CIFER numbers (<= 100 per pair is a good fit). Standard
    errors are Cramer-Rao bounds scaled by the residual variance, insensitivities in
    ``fit['insensitivity']`` (Tischler & Remple sec. 11.6; guidelines CR <= 20 %,
    insensitivity <= 10 %).

    Parameters
    ----------
    responses : sequence of FrequencyResponse
        Measured responses; each (output, input) must be a pair of the model.
    model : LinearModel
        The linear model.
    estimate : sequence of str, optional
        The parameters to fit. Default all but the biases.
    coherence_min : float, optional
        The smallest coherence of a point used. Default ``COHERENCE_MIN``.
    start : mapping of str to float, optional
        Start values over the model's own.

    Returns
    -------
    Estimate
        The fitted parameters and their standard errors.

    Raises
    ------
    ValueError
        When a response is not a model pair or has fewer than 3 usable points.
    """
    names = list(estimate) if estimate is not None else [
        p for p in model.parameters if not p.startswith("bias_")]
    pairs = []
    for r in responses:
        if r.output not in model.outputs or r.input not in model.inputs:
            raise ValueError(
                f"response {r.output}/{r.input} is not an output/input pair of model "
                f"{model.name} (outputs {model.outputs}, inputs {model.inputs})"
            )
        m = r.valid(coherence_min)
        if m.sum() < 3:
            raise ValueError(f"response {r.output}/{r.input} has fewer than 3 points with "
                             f"coherence >= {coherence_min}")
        pairs.append(r.select(m))
    values = dict(model.start)
    if start:
        values.update(start)
    theta0 = np.array([values[n] for n in names], dtype=float)

    def residuals(th: np.ndarray) -> np.ndarray:
        v = {**values, **dict(zip(names, th, strict=True))}
        return np.concatenate([
            cifer_residuals(model_response(model, v, p.output, p.input, p.frequency),
                            p.response, p.coherence) for p in pairs])

    sol = least_squares(residuals, theta0, method="lm", x_scale="jac", xtol=1e-10,
                        ftol=1e-12, max_nfev=500 * (len(names) + 1))
    theta = sol.x
    r = residuals(theta)
    jac = central_jacobian(residuals, theta)
    fisher = jac.T @ jac
    dof = max(r.size - theta.size, 1)
    s2 = float(r @ r) / dof
    cov = s2 * np.linalg.pinv(fisher)
    std = np.sqrt(np.clip(np.diag(cov), 0, None))
    insens = np.sqrt(s2 / np.maximum(np.diag(fisher), 1e-300))
    per_pair, start_idx = {}, 0
    for p in pairs:
        n = 2 * p.frequency.size
        seg = r[start_idx : start_idx + n]
        per_pair[f"{p.output}/{p.input}"] = float(seg @ seg)
        start_idx += n
    final = {**values, **dict(zip(names, theta, strict=True))}
    outputs = {f"{p.output}/{p.input}": {
        "frequency": p.frequency, "measured": p.response, "coherence": p.coherence,
        "model": model_response(model, final, p.output, p.input, p.frequency)}
        for p in pairs}
    return Estimate(
        method="cifer_state_space",
        names=names,
        values=theta,
        std=std,
        covariance=cov,
        fit={"cost_per_pair": per_pair, "average_cost": float(np.mean(list(per_pair.values()))),
             "insensitivity": insens,
             "cr_percent": 100 * std / np.maximum(np.abs(theta), 1e-300),
             "insensitivity_percent": 100 * insens / np.maximum(np.abs(theta), 1e-300),
             "std_kind": "cramer-rao",
             "converged": bool(sol.success),
             "reason": str(sol.message),
             "model": model.name},
        outputs=outputs,
    )


# ----------------------------------------------------------------------------- verification
# output weights of J_rms: deg, deg/s, ft/s, ft/s^2 (Tischler & Remple sec. 12.2)
_ANGLE_CHANNELS = {"alpha", "beta", "phi", "theta", "psi", "de", "da", "dr"}
_RATE_CHANNELS = {"p", "q", "r"}


def _jrms_scale(channel: str, unit: str) -> float:
    if channel in _ANGLE_CHANNELS or channel in _RATE_CHANNELS or unit in ("rad", "rad/s"):
        return 1.0 / DEG
    if unit in ("m/s", "m/s^2", "m"):
        return 1.0 / FT
    return 1.0


def verify_time_domain(
    record: FlightRecord,
    model: LinearModel,
    values: Mapping[str, float] | Estimate,
    *,
    outputs: Sequence[str] | None = None,
) -> dict:
    """Fly the model on ``record`` (a maneuver not used for fitting) and score the fit.

    The model starts from the measured states at the first sample and is driven by the
    measured inputs (perturbations from the first sample); a bias per state equation and per
    output (reference shifts) are fitted by linear least squares, as CIFER's VERIFY does.

    Parameters
    ----------
    record : FlightRecord
        The verification maneuver, SI channels.
    model : LinearModel
        The linear model.
    values : mapping of str to float or Estimate
        The parameter values over the model's start values.
    outputs : sequence of str, optional
        The outputs scored. Default all the model's.

    Returns
    -------
    dict
        {'J_rms', 'tic' {output: TIC}, 'time', 'measured', 'model', 'biases'}; J_rms in the
        units deg, deg/s, ft/s, ft/s^2 (<= 1-2 is good, Tischler & Remple),
        TIC = ||z - y|| / (||z|| + ||y||) (< 0.25-0.3 is good).
    """
    vals = dict(model.start)
    if isinstance(values, Estimate):
        vals.update(dict(zip(values.names, values.values, strict=True)))
    else:
        vals.update(values)
    outs = list(outputs) if outputs is not None else list(model.outputs)
    a, b, c, d = _split_bias(model, vals)
    t = record.time - record.time[0]
    u = np.column_stack([record[ch] - record[ch][0] for ch in model.inputs])
    x0 = np.zeros(len(model.states))  # perturbations from the first sample
    n_x, n_y = a.shape[0], c.shape[0]
    # columns: the model driven by the inputs, then unit biases on each state equation
    sys = StateSpace(a, np.hstack([b, np.eye(n_x)]), c, np.hstack([d, np.zeros((n_y, n_x))]))
    drive = np.hstack([u, np.zeros((t.size, n_x))])
    y_u = lsim(sys, drive, t, X0=x0)[1].reshape(t.size, n_y)
    basis = []
    for k in range(n_x):
        e = np.zeros((t.size, u.shape[1] + n_x))
        e[:, u.shape[1] + k] = 1.0
        basis.append(lsim(sys, e, t)[1].reshape(t.size, n_y))
    rows = [model.outputs.index(o) for o in outs]
    z = np.column_stack([record[o] - record[o][0] for o in outs])
    scale = np.array([_jrms_scale(o, record.unit(o)) for o in outs])
    # least squares for state biases (shared) and output shifts (one per output)
    n_o = len(outs)
    design = np.zeros((t.size * n_o, n_x + n_o))
    target = np.zeros(t.size * n_o)
    for i, row in enumerate(rows):
        sl = slice(i * t.size, (i + 1) * t.size)
        for k in range(n_x):
            design[sl, k] = basis[k][:, row] * scale[i]
        design[sl, n_x + i] = scale[i]
        target[sl] = (z[:, i] - y_u[:, row]) * scale[i]
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    y = np.column_stack([
        y_u[:, row] + sum(coef[k] * basis[k][:, row] for k in range(n_x)) + coef[n_x + i]
        for i, row in enumerate(rows)])
    err = (z - y) * scale
    j_rms = float(np.sqrt(np.mean(err**2)))
    tic = {o: float(np.linalg.norm(z[:, i] - y[:, i])
                    / (np.linalg.norm(z[:, i]) + np.linalg.norm(y[:, i])))
           for i, o in enumerate(outs)}
    return {"J_rms": j_rms, "tic": tic, "time": record.time, "measured": z, "model": y,
            "outputs": outs, "biases": coef}
