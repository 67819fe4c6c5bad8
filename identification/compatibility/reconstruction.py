"""Data compatibility by flight path reconstruction: sensor biases, scale factors, time
shifts and air-data (vane, pitot) calibration from the kinematics alone.

Morelli & Klein (2016) ch. 10 and Jategaonkar (2015) ch. 10; Cooper, Drobik & Martin,
ARL Flight Mechanics Report 187 (1990; flight path reconstruction, vane calibration
alpha_m = K_alpha (alpha - x_alpha q / V) + b).

The parameters are estimated by output error (maximum likelihood with the noise
covariance R re-estimated every iteration, Gauss-Newton with Levenberg-Marquardt
damping; M&K ch. 6) together with the initial states ``x0_<state>``. The optimiser of
``output_error`` is built around the discretised linear model (exact matrix-exponential
sensitivities), so this nonlinear kinematic model has its own compact Gauss-Newton with
central finite-difference sensitivities (as SIDPAC's ``oe`` does for nonlinear models):
all perturbed parameter sets are integrated together in one vectorised RK4 loop, and
parameters that enter only the output equations reuse the nominal states. Cramer-Rao
bounds come from the information matrix, corrected for colored residuals (M&K eq. 6.54;
``output_error.colored_residual_covariance``) by default: the integrated input noise makes
the residuals of a reconstruction strongly colored. Parameters the maneuver cannot
separate (zero sensitivity, or a near-singular normalised information matrix;
``identifiability``) are fixed at their a priori values and reported in
``Estimate.unidentifiable``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from flightid.channels import CHANNELS
from flightid.identification.compatibility.correction import correct
from flightid.identification.compatibility.kinematics import (
    Problem,
    batch,
    corrected_inputs,
    integrate,
    model_outputs,
    outputs_and_sensitivities,
    simulate,
)
from flightid.identification.compatibility.parameters import (
    CATALOGUE_EFFECTS,
    DEFAULT_LATITUDE,
    INPUTS,
    MAX_CORRELATION,
    METHOD,
    MIN_SAMPLES,
    OUTPUTS,
    PARAMETERS,
    REQUIRED,
    START_WINDOW_S,
    STATES,
    WIND,
    default_free,
    default_outputs,
)
from flightid.identification.engine import convergence
from flightid.identification.engine import identifiability as ident
from flightid.identification.engine import problem as problem_skeleton
from flightid.identification.engine.bounds import colored_residual_covariance
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit
from flightid.identification.engine.metrics import r_squared_by_output
from flightid.identification.estimate import Estimate
from flightid.identification.models.rigid_body import local_gravity
from flightid.record import FlightRecord


def problem_from_record(record: FlightRecord, outputs: Sequence[str] | None = None,
                        gravity: float | None = None, latitude: float | None = None,
                        gyros: str | None = None) -> tuple[Problem, dict[str, str]]:
    """Arrange a record for the reconstruction.

    Checks channels, sampling and finite values.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    outputs : sequence of str, optional
        Measured channels to fit. Default ``default_outputs(record)``.
    gravity : float, optional
        Gravity, m/s^2. Default the WGS84 normal gravity at the mean altitude and latitude
        (45 deg if unknown).
    latitude : float, optional
        Latitude, rad; switches on the rotating round Earth. Default the mean of the record's
        latitude channel; without either the Earth is flat and still.
    gyros : str, optional
        'inertial' (real IMUs, they sense the Earth rate) or 'earth' (rates relative to the
        Earth, as JSBSim records them). Default ``meta.extra['gyro_frame']``, else 'earth'
        for records whose provenance starts with "jsbsim", else 'inertial'.

    Returns
    -------
    tuple of (Problem, dict of str to str)
        The problem and notes on the choices made.

    Raises
    ------
    ValueError
        For missing, unknown or non-finite channels, no output, or bad sampling.
    """
    notes: dict[str, str] = {}
    missing = [c for c in REQUIRED if c not in record]
    if missing:
        raise ValueError(
            f"record lacks channel(s) {', '.join(missing)}; flight path reconstruction needs "
            f"the inertial inputs {', '.join(INPUTS)} and the outputs V, alpha, beta, phi, theta"
        )
    outputs = tuple(outputs) if outputs is not None else tuple(default_outputs(record))
    bad = [o for o in outputs if o not in OUTPUTS]
    if bad:
        raise ValueError(f"unknown output(s) {', '.join(bad)}; outputs are {', '.join(OUTPUTS)}")
    absent = [o for o in outputs if o not in record]
    if absent:
        raise ValueError(f"output(s) {', '.join(absent)} requested but not in the record")
    if not outputs:
        raise ValueError("no outputs to fit")
    time = record.time
    dt = record.uniform_step("the reconstruction", min_samples=MIN_SAMPLES)
    for c in (*INPUTS, *outputs):
        finite = np.isfinite(record[c])
        if not finite.all():
            i = int(np.argmin(finite))
            raise ValueError(f"channel {c!r} is not finite at sample {i} (t = {time[i]:.4g} s)")
    z = np.column_stack([np.unwrap(record[o]) if o == "psi" else record[o] for o in outputs])
    known = latitude
    if known is None and "latitude" in record:
        known = float(np.mean(record["latitude"]))
        notes["latitude"] = "mean of the record's latitude channel"
    if known is None:
        notes["earth"] = ("latitude unknown: flat, non-rotating Earth (Earth rate and "
                          "transport rate, < 0.005 deg/s, go into the gyro biases)")
    else:
        notes["earth"] = "rotating WGS84 Earth: transport rate, Earth rate, Coriolis"
    if gravity is None:
        lat_g = DEFAULT_LATITUDE if known is None else known
        altitude = float(np.mean(record["h"])) if "h" in record else 0.0
        gravity = local_gravity(lat_g, altitude)
        notes["gravity"] = (f"WGS84 normal gravity {gravity:.5f} m/s^2 at latitude "
                            f"{math.degrees(lat_g):.2f} deg, {altitude:.0f} m"
                            + (" (latitude assumed; +-0.026 m/s^2 goes into bias_az)"
                               if known is None else "")
                            + ("" if "h" in record else " (no h channel: sea level)"))
    else:
        notes["gravity"] = f"given: {gravity:.5f} m/s^2"
    if gyros is None:
        gyros = str(record.meta.extra.get("gyro_frame", ""))
        if not gyros:
            sim = record.meta.provenance.lower().startswith("jsbsim")
            gyros = "earth" if sim else "inertial"
            notes["gyros"] = ("JSBSim record: rates relative to the Earth (JSBSim "
                              "velocities/p-rad_sec)" if sim else "rates sensed by inertial gyros")
    if gyros not in ("inertial", "earth"):
        raise ValueError(f"gyros must be 'inertial' or 'earth', got {gyros!r}")
    inputs = np.column_stack([record[c] for c in INPUTS])
    return Problem(time=time.copy(), dt=dt, inputs=inputs, outputs=outputs, z=z,
                   noise_floor=problem_skeleton.noise_floor(z), gravity=float(gravity),
                   latitude=known, gyros=gyros), notes


def _line_start(t: np.ndarray, x: np.ndarray) -> float:
    """Value at t[0] of a straight line fitted to the first START_WINDOW_S of x (noise-robust)."""
    n = max(3, min(len(t), int(round(START_WINDOW_S / (t[1] - t[0]))) + 1))
    c = np.polyfit(t[:n] - t[0], x[:n], 1)
    return float(c[1])


def initial_states(record: FlightRecord, values: Mapping[str, float]) -> dict[str, float]:
    """Start values x0_<state> from the record corrected with ``values``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    values : mapping of str to float
        Calibration parameter values, SI.

    Returns
    -------
    dict of str to float
        x0_u, x0_v, x0_w (m/s), x0_phi, x0_theta (rad) and, where recorded, x0_psi (rad),
        x0_h, x0_north, x0_east (m).
    """
    rec = correct(record, values, reconstruction=None)
    t = rec.time
    V, alpha, beta = (_line_start(t, rec[c]) for c in ("V", "alpha", "beta"))
    out = {
        "x0_u": V * math.cos(alpha) * math.cos(beta),
        "x0_v": V * math.sin(beta),
        "x0_w": V * math.sin(alpha) * math.cos(beta),
        "x0_phi": _line_start(t, rec["phi"]),
        "x0_theta": _line_start(t, rec["theta"]),
    }
    for s in ("psi", "h", "north", "east"):
        if s in rec:
            x = np.unwrap(rec[s]) if s == "psi" else rec[s]
            out[f"x0_{s}"] = _line_start(t, x)
    return out


# ------------------------------------------------------------------ estimation


def _iterate(problem: Problem, names: list[str], values: dict[str, float],
             max_iterations: int, step_tol: float, cost_tol: float,
             last: dict | None = None) -> MaximumLikelihoodFit:
    """Maximum likelihood with a diagonal R: the output-error optimiser
    (``engine.problem.fit``: Newton-Raphson on N/2 ln det R with R concentrated
    out, Levenberg-Marquardt safeguard; M&K eqs. 6.22-6.33) on the kinematic model.
    ``last``: the latest outputs and sensitivities, shared between the identifiability
    probe of a pass and the fit that starts where it did (one integration fewer).

    Returns its fit with ``noise`` as the vector of output noise variances.
    """
    fixed = {k: v for k, v in values.items() if k not in names}
    last = {} if last is None else last

    def sensitivities(vals: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        key = (tuple(names), tuple(sorted({**fixed, **vals}.items())))
        if key not in last:
            last.clear()
            last[key] = outputs_and_sensitivities(problem, {**fixed, **vals}, names)
        return last[key]

    fit = problem_skeleton.fit(
        problem, sensitivities,
        lambda vals: simulate(problem, {**fixed, **vals})[0],
        list(names), values, max_iterations, False, step_tol, cost_tol)
    fit.noise = np.diag(fit.noise).copy()
    return fit


# A scale factor k changes its channel by k * (peak-to-peak range): below these ranges that
# is under the calibration accuracy of flight-test sensors (Cooper, Drobik & Martin 1990,
# Table 1: vanes +-0.5 deg, rate gyros 0.5-3 deg/s, accelerometers 0.05 g, airspeed 10 kt) for any
# plausible k (< 25 %), so k cannot be told from the bias and the model error.
MIN_SCALE_RANGE = {"rad": math.radians(2.0), "rad/s": math.radians(10.0), "m/s^2": 0.2 * 9.80665,
                   "m/s": 20.0 * 0.514444}
_SCALED = {"upwash_alpha": "alpha", "sidewash_beta": "beta", "scale_V": "V",
           **{f"scale_{c}": c for c in INPUTS}}


def _unexcited(record: FlightRecord, names: Sequence[str]) -> dict[str, str]:
    """Scale factors whose channel barely moves in this flight, with the reason."""
    out = {}
    for name in names:
        channel = _SCALED.get(name)
        if channel is None:
            continue
        unit = CHANNELS[channel].unit
        span = float(np.ptp(record[channel]))
        need = MIN_SCALE_RANGE[unit]
        if span < need:
            out[name] = (f"{channel} moves only {span:.3g} {unit} peak to peak (< {need:.3g} "
                         f"{unit}): a scale factor cannot be told from the bias and the model "
                         "error; fly a larger excursion")
    return out


def _unidentifiable(names: list[str], fit: MaximumLikelihoodFit,
                    tolerance: float) -> dict[str, str]:
    values = np.array([fit.values[n] for n in names])
    found = ident.zero_sensitivity(names, fit.information, values)
    if found:
        return found
    # initial states must be estimated for the integration to start right: keep them
    keep = [n for n in names if n.startswith("x0_")]
    found = ident.collinear(names, fit.information, prefer_keep=keep, tolerance=tolerance)
    if found:
        return found
    corr = ident.correlation(np.linalg.inv(fit.information))
    sensors = [i for i, n in enumerate(names) if not n.startswith("x0_")]
    for i in sensors:
        for j in sensors:
            if j > i and abs(corr[i, j]) > MAX_CORRELATION:
                return {names[j]: (
                    f"correlation {corr[i, j]:+.4f} with {names[i]}: the maneuver cannot "
                    f"separate them; {names[j]} is fixed at its a priori value and "
                    f"{names[i]} absorbs both")}
    return {}


def _check_names(names: Sequence[str], outputs: Sequence[str], where: str) -> None:
    unknown = [n for n in names if n not in PARAMETERS]
    if unknown:
        raise ValueError(
            f"{where}: unknown parameter(s) {', '.join(unknown)}; known: {', '.join(PARAMETERS)}")
    for n in names:
        channel = n.split("_", 1)[1]
        if n.startswith(("bias_", "delay_")) and channel in OUTPUTS and channel not in INPUTS \
                and channel not in outputs:
            raise ValueError(f"{where}: {n} needs the output {channel!r}, which is not fitted "
                             f"(outputs: {', '.join(outputs)})")
    if any(n in names for n in WIND[:2]) and not any(o in outputs for o in ("north", "east")):
        raise ValueError(f"{where}: horizontal wind needs a north or east position output; the "
                         "air data and attitudes alone cannot see a constant wind")


def reconstruct(
    record: FlightRecord,
    *,
    free: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
    outputs: Sequence[str] | None = None,
    gravity: float | None = None,
    latitude: float | None = None,
    gyros: str | None = None,
    uncertainty: str = "noise",
    max_iterations: int = 60,
    step_tolerance: float = 1e-2,
    cost_tolerance: float = 1e-4,
    singular_eigenvalue: float = ident.SINGULAR_EIGENVALUE,
) -> tuple[FlightRecord, Estimate]:
    """Flight path reconstruction: estimate sensor calibration and return the corrected record.

    A reconstruction that does not converge warns (``convergence.NotConvergedWarning``).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    free : sequence of str, optional
        Parameters to estimate (names of ``PARAMETERS``). Default ``default_free``; the
        initial states x0_<state> are always added unless given in ``fixed``.
    fixed : mapping of str to float, optional
        Known values (SI) of parameters not estimated, e.g. vane positions from drawings.
    outputs : sequence of str, optional
        Measured channels to fit. Default V alpha beta phi theta psi h, those present.
    gravity : float, optional
        Gravity, m/s^2 (see ``problem_from_record``).
    latitude : float, optional
        Latitude, rad (see ``problem_from_record``).
    gyros : str, optional
        'inertial' or 'earth' (see ``problem_from_record``).
    uncertainty : str, optional
        How the standard errors are formed (see ``UNCERTAINTY``). Default "noise".
    max_iterations : int, optional
        Iteration limit, at least 1. Default 60.
    step_tolerance : float, optional
        Converged when no parameter moves by more than this many standard errors. Default
        1e-2.
    cost_tolerance : float, optional
        Converged when the cost changes by less than this. Default 1e-4.
    singular_eigenvalue : float, optional
        Collinearity threshold of the identifiability check. Default
        ``ident.SINGULAR_EIGENVALUE``.

    Returns
    -------
    tuple of (FlightRecord, Estimate)
        The record with the estimates applied (``correct``) and the Estimate (values in SI
        units; ``PARAMETERS[name].unit``).

    Raises
    ------
    ValueError
        For an unknown uncertainty, a bad parameter list, or ``max_iterations`` below 1.
    """
    convergence.check_limit("compatibility", "max_iterations", max_iterations)
    if uncertainty not in UNCERTAINTY:
        raise ValueError(f"uncertainty must be one of {', '.join(UNCERTAINTY)}, "
                         f"got {uncertainty!r}")
    fixed = dict(fixed or {})
    problem, notes = problem_from_record(record, outputs, gravity, latitude, gyros)
    names = list(default_free(record, problem.outputs) if free is None else free)
    _check_names(names, problem.outputs, "free")
    _check_names(list(fixed), problem.outputs, "fixed")
    both = [n for n in names if n in fixed]
    if both:
        raise ValueError(f"{', '.join(both)} given both as free and fixed")
    if len(set(names)) != len(names):
        raise ValueError("free lists a parameter twice")
    start = {**{n: p.default for n, p in PARAMETERS.items()}, **fixed}
    start.update({k: v for k, v in initial_states(record, start).items() if k not in fixed})
    used_states = [s for s in STATES if s in ("u", "v", "w", "phi", "theta")
                   or s in problem.outputs
                   or (s == "psi" and any(o in problem.outputs for o in ("north", "east")))]
    names += [f"x0_{s}" for s in used_states if f"x0_{s}" not in fixed and f"x0_{s}" not in names]

    unidentifiable: dict[str, str] = _unexcited(record, names)
    last: dict = {}
    for _ in range(len(names) + 1):
        active = [n for n in names if n not in unidentifiable]
        values = {**start, **{n: start[n] for n in active}}
        # at the start values first, so that the iteration never meets a singular M
        probe = _iterate(problem, active, values, 0, step_tolerance, cost_tolerance, last)
        found = _unidentifiable(active, probe, singular_eigenvalue)
        if found:
            unidentifiable.update(found)
            continue
        fit = _iterate(problem, active, values, max_iterations, step_tolerance, cost_tolerance,
                       last)
        found = _unidentifiable(active, fit, singular_eigenvalue)
        if not found:
            break
        unidentifiable.update(found)
    estimate = _result(problem, fit, {**start, **fit.values}, unidentifiable, uncertainty,
                       notes, fixed)
    applied = {**start, **fit.values}
    corrected = correct(record, applied, reconstruction=(problem, estimate))
    convergence.warn(estimate, "compatibility")
    return corrected, estimate


UNCERTAINTY = {
    "noise": "Cramer-Rao bound for the output noise plus the Monte Carlo scatter caused by "
             "the input noise (both noise levels from the data)",
    "colored": "Cramer-Rao bound corrected for colored residuals (M&K eq. 6.54)",
    "cramer-rao": "Cramer-Rao bound with the residual covariance (M&K eq. 6.50)",
}
MONTE_CARLO_RUNS = 200
OUTPUT_NOISE = "residual"


def white_noise_std(x: np.ndarray) -> float:
    """Standard deviation of the white noise on a sampled signal.

    From third differences, which remove a smooth signal: var(d3 x) = 20 sigma^2 for white
    noise; robust (median absolute deviation) against the few samples where the signal
    jerks, falling back to the rms for a coarsely quantised signal whose median is 0.

    Parameters
    ----------
    x : numpy.ndarray
        The signal, any unit; shape (n,).

    Returns
    -------
    float
        The noise standard deviation, unit of ``x``.
    """
    d = np.diff(np.asarray(x, dtype=float), 3)
    robust = 1.4826 * float(np.median(np.abs(d - np.median(d))))
    return (robust if robust > 0 else float(np.std(d))) / math.sqrt(20.0)


def _noise_covariance(problem: Problem, fit: MaximumLikelihoodFit, values: Mapping[str, float],
                      runs: int = MONTE_CARLO_RUNS, seed: int = 0) -> tuple[np.ndarray, dict]:
    """Parameter covariance from the output noise and the input noise, with their levels.

    Output noise (white, level from ``white_noise_std``): the sandwich M^-1 S^T W R_out W
    S M^-1 of the weighted least-squares step. Input noise is integrated by the model,
    so its effect is a random walk that no stationary correction captures (the colored
    correction understates it several fold); it is propagated instead: ``runs`` input
    noise histories of the measured level go through the model at the estimate, and the
    Gauss-Newton step each one causes, -M^-1 S^T W dy, gives the covariance by Monte
    Carlo (fixed ``seed``). The two sources are independent, so the covariances add.
    """
    names = fit.names
    weight = 1.0 / fit.noise
    info_inv = np.linalg.inv(fit.information)
    out_sigma = np.array([white_noise_std(problem.z[:, j]) for j in range(problem.z.shape[1])])
    # an output held between slow updates (or coarsely quantised) is far from white: its
    # error is then at least the residual (conservative), which gives M^-1 for it
    out_var = np.maximum(out_sigma**2, fit.noise) if OUTPUT_NOISE == "residual" else out_sigma**2
    ws = fit.sens * weight[None, :, None]
    middle = np.einsum("iak,a,ial->kl", ws, out_var, ws)
    cov_out = info_inv @ middle @ info_inv
    in_sigma = np.array([white_noise_std(problem.inputs[:, j]) for j in range(len(INPUTS))])
    rng = np.random.default_rng(seed)
    steps = []
    for start in range(0, runs, 50):
        k = min(50, runs - start)
        P = batch(values, k)
        a = corrected_inputs(problem, P)
        a = a + rng.standard_normal(a.shape) * in_sigma[None, :, None]
        dy = model_outputs(problem, P, integrate(problem, P, a), a) - fit.y[:, :, None]
        steps.append(-info_inv @ np.einsum("iak,a,iar->kr", fit.sens, weight, dy))
    delta = np.concatenate(steps, axis=1)
    cov_in = delta @ delta.T / delta.shape[1]
    levels = {"input_noise_std": dict(zip(INPUTS, in_sigma.tolist(), strict=True)),
              "output_noise_std": dict(zip(problem.outputs, out_sigma.tolist(), strict=True)),
              "monte_carlo_runs": runs,
              "std_output_noise": dict(zip(names, np.sqrt(np.diag(cov_out)).tolist(),
                                           strict=True)),
              "std_input_noise": dict(zip(names, np.sqrt(np.diag(cov_in)).tolist(),
                                          strict=True))}
    return cov_out + cov_in, levels


def _result(problem: Problem, fit: MaximumLikelihoodFit, values: Mapping[str, float],
            unidentifiable: dict[str, str], uncertainty: str, notes: dict[str, str],
            fixed: Mapping[str, float]) -> Estimate:
    names = fit.names
    levels: dict = {}
    if uncertainty == "noise":
        cov, levels = _noise_covariance(problem, fit, values)
    elif uncertainty == "colored":
        weight = np.diag(1.0 / fit.noise)
        cov = colored_residual_covariance(fit.sens, fit.residuals, weight, fit.information)
    else:
        cov = np.linalg.inv(fit.information)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    r2 = r_squared_by_output(problem.z, fit.residuals, problem.outputs)
    outputs = {o: {"measured": problem.z[:, j], "model": fit.y[:, j],
                   "residual": fit.residuals[:, j]} for j, o in enumerate(problem.outputs)}
    stats = {
        "model": "kinematic flight path reconstruction (flat Earth, constant wind)",
        "converged": fit.converged,
        "reason": fit.reason,
        "iterations": fit.iterations,
        "cost": fit.cost_history[-1],
        "cost_history": list(fit.cost_history),
        "noise_std": {o: float(np.sqrt(fit.noise[j])) for j, o in enumerate(problem.outputs)},
        "R2_per_output": r2,
        "std_kind": UNCERTAINTY[uncertainty],
        "noise_levels": levels,
        "samples": int(problem.z.shape[0]),
        "outputs": list(problem.outputs),
        "inputs": list(INPUTS),
        "gravity_m_s2": problem.gravity,
        "notes": dict(notes),
        "fixed": {n: float(v) for n, v in fixed.items()},
        "units": {n: PARAMETERS[n].unit for n in names},
        "effects": {n: "{}.{}".format(*CATALOGUE_EFFECTS[n]) for n in names
                    if n in CATALOGUE_EFFECTS},
        "high_correlations": ident.high_correlations(names, cov, 0.9),
    }
    return Estimate(METHOD, list(names), np.array([fit.values[n] for n in names]), std, cov,
                    stats, dict(unidentifiable), outputs, problem.time.copy())


