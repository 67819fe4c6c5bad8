"""Equation error and output error in the frequency domain; state-space fits with the CIFER
cost; time-domain verification of a frequency-domain model.

Data (Morelli & Klein 2016 ch. 7): each channel minus its mean over the maneuver is
Fourier transformed at chosen frequencies (typically 0.1-1.5 Hz for rigid-body
dynamics) with the high-accuracy finite Fourier transform
(``fourier.finite_fourier_transform``: chirp z-transform plus cubic end
corrections).

Removing the means is exact for algebraic relations (coefficients, outputs): constants
cancel. For a state equation xdot = A x + B u + b it leaves, in the mean-removed
variables x~, a constant c = A xbar + B ubar + b, and integrating over the maneuver gives
c = (x(T) - x(0)) / T exactly, so the transformed state equation

    j w X~ + x~(T) e^{-jwT} - x~(0) = A X~ + B U~ + c (1 - e^{-jwT}) / (j w)

(finite Fourier transform of a derivative, Morelli & Klein eq. 7.8) needs no bias
parameters: the end values and c come from the measured states. They are the
"initial-condition" terms that make output error in the frequency domain independent of
the trim values.

* ``equation_error``: complex linear regression of a transformed coefficient on
  transformed regressors, theta = Re(X^H X)^-1 Re(X^H z) (Morelli & Klein eq. 7.14).
* ``output_error``: maximum likelihood with the model outputs
  Y = C (jwI - A)^-1 [B U~ + x~(0) - x~(T) e^{-jwT} + c (1 - e^{-jwT})/(jw)] + D U~
  and the residual spectral density S (diagonal) estimated with the parameters (relaxation),
  J = sum_w v^H S^-1 v (Morelli & Klein eqs. 7.29-7.33); Cramer-Rao bounds from
  M = 2 sum_w Re(dY^H S^-1 dY).
* ``fit_state_space``: the CIFER cost of ``transfer_function`` summed over the
  frequency responses of several input-output pairs (Tischler & Remple ch. 11; seed
  004 sec. 5.3), with Cramer-Rao bounds and insensitivities.
* ``verify_time_domain``: the fitted model flown on a maneuver not used for fitting,
  with output biases and reference shifts fitted by linear least squares, scored by
  J_rms (Tischler & Remple eq. 12.2; <= 1-2 is good) and Theil's inequality coefficient
  per output.

Frequencies are in Hz. With frequencies spaced 1/T apart (T the maneuver length) the
transformed noise at different frequencies is nearly independent; a finer grid adds
correlated points, and the Cramer-Rao bounds then come out too small.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import StateSpace, lsim

from flightid.identification.data.coefficients import channel_values, nondimensional_rates
from flightid.identification.estimate import Estimate
from flightid.identification.frequency.fourier import finite_fourier_transform
from flightid.identification.frequency.grids import fourier_frequencies
from flightid.identification.frequency.response import FrequencyResponse
from flightid.identification.frequency.transfer_function import (
    COHERENCE_MIN,
    central_jacobian,
    cifer_residuals,
)
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord
from flightid.units import DEG, FT

NOISE_MODELS = ("full", "diagonal")

# regressor channel -> derivative variable (flightid.derivatives)
REGRESSOR_VARIABLES: dict[str, str] = {
    "alpha": "alpha", "beta": "beta", "phat": "p", "qhat": "q", "rhat": "r",
    "de": "de", "da": "da", "dr": "dr", "throttle": "dt",
}


def fourier_data(record: FlightRecord, channels: Sequence[str], frequencies: np.ndarray
                 ) -> dict[str, np.ndarray]:
    """Finite Fourier transforms of channels minus their means.

    Parameters
    ----------
    record : FlightRecord
        A uniformly sampled flight, SI channels.
    channels : sequence of str
        The channels transformed.
    frequencies : numpy.ndarray
        Frequencies, Hz.

    Returns
    -------
    dict of str to numpy.ndarray
        Per channel its transform, unit * s; shape (n_f,).
    """
    _check_uniform(record)
    x = np.column_stack([record[c] - np.mean(record[c]) for c in channels])
    xf = finite_fourier_transform(x, record.dt, frequencies)
    return {c: xf[:, i] for i, c in enumerate(channels)}


def _check_uniform(record: FlightRecord) -> None:
    record.uniform_step("the Fourier transform", min_samples=8, rtol=1e-3)


def _with_rates(record: FlightRecord, names: Sequence[str]) -> FlightRecord:
    missing = [n for n in names if n in ("phat", "qhat", "rhat") and n not in record]
    if not missing:
        return record
    rates = nondimensional_rates(record)
    return record.with_channels(**{n: rates[n] for n in missing})


# ----------------------------------------------------------------------------- equation error
def equation_error(
    record: FlightRecord,
    coefficient: str,
    regressors: Sequence[str],
    *,
    frequencies: np.ndarray | None = None,
) -> Estimate:
    """Frequency-domain equation error: a coefficient channel regressed on regressor channels.

    Standard errors from the residual variance of the real-stacked regression,
    cov = s^2 Re(X^H X)^-1, s^2 = sum |v|^2 / (2 n_w - n_p) (Morelli & Klein eq. 7.16).

    Parameters
    ----------
    record : FlightRecord
        A uniformly sampled flight, SI channels.
    coefficient : str
        The coefficient channel (e.g. 'Cl'); computed from the rigid-body equations when the
        record lacks it.
    regressors : sequence of str
        Regressor channels (beta, phat, rhat, da, dr ...).
    frequencies : numpy.ndarray, optional
        Frequencies, Hz. Default ``fourier_frequencies(record)``.

    Returns
    -------
    Estimate
        Derivatives named C<coef>_<var> (per rad, rates nondimensional) with their standard
        errors.

    Raises
    ------
    ValueError
        For a malformed coefficient, an unknown regressor or too few frequencies.
    """
    if not coefficient.startswith("C") or len(coefficient) != 2:
        raise ValueError(f"coefficient must be a channel like 'Cl' or 'CY', got {coefficient!r}")
    unknown = [r for r in regressors if r not in REGRESSOR_VARIABLES]
    if unknown:
        raise ValueError(
            f"no derivative name for regressor(s) {', '.join(unknown)}; known: "
            f"{', '.join(REGRESSOR_VARIABLES)}"
        )
    record = _with_rates(record, regressors)
    if coefficient not in record:  # computed from the rigid-body equations
        record = record.with_channels(**{coefficient: channel_values(record, coefficient)})
    f = fourier_frequencies(record) if frequencies is None else np.asarray(frequencies, float)
    data = fourier_data(record, [coefficient, *regressors], f)
    z = data[coefficient]
    x = np.column_stack([data[r] for r in regressors])
    info = np.real(x.conj().T @ x)
    theta = np.linalg.solve(info, np.real(x.conj().T @ z))
    v = z - x @ theta
    n_p = len(regressors)
    dof = 2 * f.size - n_p
    if dof <= 0:
        raise ValueError(f"{f.size} frequencies are too few for {n_p} parameters")
    s2 = float(np.real(v.conj() @ v)) / dof
    cov = s2 * np.linalg.inv(info)
    names = [f"{coefficient}_{REGRESSOR_VARIABLES[r]}" for r in regressors]
    fit_z = float(1 - np.real(v.conj() @ v) / np.real(z.conj() @ z))
    return Estimate(
        method="fdee",
        names=names,
        values=theta,
        std=np.sqrt(np.diag(cov)),
        covariance=cov,
        fit={"R2": fit_z, "residual_variance": s2, "frequencies_hz": f,
             "std_kind": "cramer-rao",
             "coefficient": coefficient},
        outputs={coefficient: {"frequency": f, "measured": z, "model": x @ theta,
                               "residual": v}},
    )


# ----------------------------------------------------------------------------- output error
def _split_bias(model: LinearModel, values: Mapping[str, float]):
    a, b, c, d = model.matrices(values)
    m = len(model.inputs)
    return a, b[:, :m], c, d[:, :m]


def _endpoint_terms(record: FlightRecord, model: LinearModel, omega: np.ndarray) -> np.ndarray:
    """x~(0) - x~(T) e^{-jwT} + c (1 - e^{-jwT}) / (jw) for each state (n_w, n_x)."""
    t_end = record.time[-1] - record.time[0]
    e = np.exp(-1j * omega * t_end)
    cols = []
    for s in model.states:
        ch = model.state_channels.get(s, s)
        if ch not in record:
            raise ValueError(
                f"state {s!r} (channel {ch!r}) is not measured; frequency-domain output "
                "error needs measured states for the initial/final-condition terms"
            )
        x = record[ch] - np.mean(record[ch])
        c = (x[-1] - x[0]) / t_end
        cols.append(x[0] - x[-1] * e + c * (1 - e) / (1j * omega))
    return np.column_stack(cols)


def model_outputs(model: LinearModel, values: Mapping[str, float], omega: np.ndarray,
                  inputs: np.ndarray, endpoint: np.ndarray | None = None) -> np.ndarray:
    """Transformed model outputs Y(jw) for transformed inputs.

    Parameters
    ----------
    model : LinearModel
        The linear model.
    values : mapping of str to float
        Its parameter values.
    omega : numpy.ndarray
        Angular frequencies, rad/s; shape (n_w,).
    inputs : numpy.ndarray
        Transformed inputs, unit * s; shape (n_w, n_u).
    endpoint : numpy.ndarray, optional
        End terms added to the state equation's right-hand side; shape (n_w, n_x).

    Returns
    -------
    numpy.ndarray
        Y(jw), output unit * s; shape (n_w, n_y).
    """
    a, b, c, d = _split_bias(model, values)
    n = a.shape[0]
    eye = np.eye(n)
    out = np.empty((omega.size, c.shape[0]), dtype=complex)
    for k, w in enumerate(omega):
        rhs = b @ inputs[k]
        if endpoint is not None:
            rhs = rhs + endpoint[k]
        x = np.linalg.solve(1j * w * eye - a, rhs)
        out[k] = c @ x + d @ inputs[k]
    return out


def output_error(
    record: FlightRecord | Sequence[FlightRecord],
    model: LinearModel,
    *,
    estimate: Sequence[str] | None = None,
    frequencies: np.ndarray | None = None,
    start: Mapping[str, float] | None = None,
    end_terms: bool = True,
    noise: str = "full",
    max_relaxations: int = 20,
) -> Estimate:
    """Frequency-domain output error (maximum likelihood) of a linear model's parameters.

    Several records are fitted together with one residual spectral density. The residual
    spectral density and the parameters are relaxed in turn.

    Parameters
    ----------
    record : FlightRecord or sequence of FlightRecord
        One maneuver or several (e.g. a roll and a yaw sweep, each exciting one input).
    model : LinearModel
        The linear model.
    estimate : sequence of str, optional
        The parameters to fit. Default every parameter of the model but the biases, which
        the mean removal and end terms replace; the rest stay at their start values.
    frequencies : numpy.ndarray, optional
        Frequencies, Hz. Default 0.1-1.5 Hz spaced 1/T, per record.
    start : mapping of str to float, optional
        Start values over the model's own.
    end_terms : bool, optional
        Model the records' end terms. Default True.
    noise : str, optional
        "full" estimates the real part of the residual spectral matrix
        S = Re(1/n sum v v^H) (outputs' residuals correlated, as in Morelli & Klein
        eq. 7.32), "diagonal" only its diagonal. Default "full".
    max_relaxations : int, optional
        The limit on noise-density relaxations. Default 20.

    Returns
    -------
    Estimate
        Derivatives with Cramer-Rao standard errors.

    Raises
    ------
    ValueError
        For an unknown noise model or parameter, a bias in ``estimate``, no record, or a
        record lacking a model channel.
    """
    if noise not in NOISE_MODELS:
        raise ValueError(f"noise must be one of {', '.join(NOISE_MODELS)}, got {noise!r}")
    records = [record] if isinstance(record, FlightRecord) else list(record)
    if not records:
        raise ValueError("give at least one record")
    names = list(estimate) if estimate is not None else [
        p for p in model.parameters if not p.startswith("bias_")]
    bad = [n for n in names if n not in model.parameters]
    if bad:
        raise ValueError(f"model {model.name} has no parameter {', '.join(bad)}")
    if any(n.startswith("bias_") for n in names):
        raise ValueError("biases are not identifiable in the frequency domain after mean "
                         "removal; leave them out of estimate=")
    parts = [_transformed(rec, model, frequencies, end_terms, k)
             for k, rec in enumerate(records)]
    f = np.concatenate([p[0] for p in parts])
    omega = 2 * np.pi * f
    u = np.vstack([p[1] for p in parts])
    z = np.vstack([p[2] for p in parts])
    ends = np.vstack([p[3] for p in parts]) if end_terms else None
    values = dict(model.start)
    if start:
        values.update(start)
    theta = np.array([values[n] for n in names], dtype=float)

    def predict(th: np.ndarray) -> np.ndarray:
        return model_outputs(model, {**values, **dict(zip(names, th, strict=True))},
                             omega, u, ends)

    def whitened(th: np.ndarray, chol_inv: np.ndarray) -> np.ndarray:
        w = (z - predict(th)) @ chol_inv.T
        return np.concatenate([w.real.ravel(), w.imag.ravel()])

    def noise_density(th: np.ndarray) -> np.ndarray:
        # S = Re(1/n_w sum v v^H): the residuals [Re v, Im v] stacked as real numbers with
        # one covariance for both parts. The complex (Hermitian) S would also weight
        # the quadrature correlation between outputs; on the Twin Otter record it moves
        # Cn_r by 6 published standard errors from example 7.1, the real part does not.
        v = z - predict(th)
        s_full = np.real(v.conj().T @ v) / f.size
        return s_full if noise == "full" else np.diag(np.diag(s_full))

    s_mat = noise_density(theta)
    history = []
    converged, reason = False, f"noise density still changing after {max_relaxations} " \
                               "relaxations"
    for _ in range(max_relaxations):
        chol_inv = np.linalg.inv(np.linalg.cholesky(s_mat))
        sol = least_squares(whitened, theta, args=(chol_inv,), method="lm", xtol=1e-10,
                            ftol=1e-12, gtol=1e-12, max_nfev=200 * (len(names) + 1))
        theta = sol.x
        new = noise_density(theta)
        change = np.max(np.abs(new - s_mat)) / np.max(np.abs(np.diag(s_mat)))
        s_mat = new
        history.append(float(2 * sol.cost))
        if change < 1e-3:
            converged = bool(sol.success)
            reason = ("noise density change below 1e-3" if converged
                      else f"least squares stopped: {sol.message}")
            break
    chol_inv = np.linalg.inv(np.linalg.cholesky(s_mat))
    jac = central_jacobian(lambda th: whitened(th, chol_inv), theta)
    fisher = 2.0 * jac.T @ jac
    cov = np.linalg.inv(fisher)
    y = predict(theta)
    v = z - y
    fit = {
        "cost": float(np.real(np.sum(np.conj(v) * (v @ np.linalg.inv(s_mat).T)))),
        "frequencies_hz": f,
        "records": len(records),
        "noise": noise,
        "noise_density_diag": np.real(np.diag(s_mat)),
        "outputs": list(model.outputs),
        "fit_error_percent": {o: float(100 * np.linalg.norm(v[:, i]) / np.linalg.norm(z[:, i]))
                              for i, o in enumerate(model.outputs)},
        "std_kind": "cramer-rao",
        "relaxations": len(history),
        "converged": converged,
        "reason": reason,
        "model": model.name,
        "fixed": {p: float(values[p]) for p in model.parameters if p not in names},
    }
    freq = f if z.shape[0] == f.size else np.resize(f, z.shape[0])
    outputs = {o: {"frequency": freq, "measured": z[:, i], "model": y[:, i],
                   "residual": v[:, i]} for i, o in enumerate(model.outputs)}
    return Estimate(method="fdoe", names=names, values=theta,
                    std=np.sqrt(np.diag(cov)), covariance=cov, fit=fit, outputs=outputs)


def _transformed(record: FlightRecord, model: LinearModel, frequencies: np.ndarray | None,
                 end_terms: bool, index: int):
    """(f, U, Z, end terms) of one record for output error; channels checked."""
    for ch in (*model.inputs, *model.outputs):
        if ch not in record:
            raise ValueError(f"record {index} has no channel {ch!r} needed by model "
                             f"{model.name}")
    f = fourier_frequencies(record) if frequencies is None else np.asarray(frequencies, float)
    omega = 2 * np.pi * f
    data = fourier_data(record, list(dict.fromkeys([*model.inputs, *model.outputs])), f)
    u = np.column_stack([data[c] for c in model.inputs])
    z = np.column_stack([data[c] for c in model.outputs])
    ends = _endpoint_terms(record, model, omega) if end_terms else None
    return f, u, z, ends


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
