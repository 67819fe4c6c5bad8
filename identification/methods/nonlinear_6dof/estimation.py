"""Output error on the nonlinear 6-DOF rigid-body equations with a linear aerodynamic model.

Morelli & Klein (2016) sec. 6.4 (nonlinear dynamic models) and Jategaonkar (2015)
ch. 4: the measured outputs V, alpha, beta, p, q, r, phi, theta, psi, ax, ay, az are
matched by the flat-earth body-axis equations of ``rigid_body``, driven by the measured
controls de, da, dr, the measured thrust (N, along body x) and air density, with the
aerodynamic coefficients linear in the perturbations from a reference:

    C = C_0 + C_alpha (alpha - alpha_ref) + C_beta (beta - beta_ref) + C_p (phat - phat_ref)
          + C_q (qhat - qhat_ref) + C_r (rhat - rhat_ref) + C_de (de - de_ref) + ...

for C in CX CY CZ Cl Cm Cn (body axes, ``force_axes="body"``) or CD CY CL Cl Cm Cn (lift and
drag in the local stability axes, ``force_axes="stability"``: CX = CL sin(alpha) - CD
cos(alpha), CZ = -CL cos(alpha) - CD sin(alpha)). Rates are nondimensional, phat = p b/2V,
qhat = q cbar/2V, rhat = r b/2V, computed from the model's own states; the references are
the record means, as in equation error, so the biases C_0 are the coefficients at the mean
condition and the equation-error start values carry over unchanged. With
``moment_axes="stability"`` the rolling and yawing moments are those of the stability axes
(Cl_s, Cn_s), with the stability-axis rates phat = (p cos(alpha) + r sin(alpha)) b/2V and
rhat = (r cos(alpha) - p sin(alpha)) b/2V in every coefficient, rotated to the body axes at
the instantaneous alpha: Cl = Cl_s cos(alpha) - Cn_s sin(alpha), Cn = Cl_s sin(alpha) + Cn_s
cos(alpha) (Morelli & Klein 2016 ch. 3; the stability-axis convention of most lateral data
sets); a body-axis model of such an aircraft misses the products of the alpha perturbation
with the lateral terms. Moment coefficients may carry an alphadot term (alphadot cbar/2V,
alphadot from the translational equations at the same instant). ``rotor_momentum`` adds the
angular momentum of the engine rotor ``h_engine`` (N m s), whose gyroscopic moment is
otherwise read as aerodynamics; ``engine_torque`` a constant engine rolling moment
``L_engine`` (N m), which a coefficient bias would wrongly scale with dynamic pressure;
``propulsive_moments`` takes the record's propulsive moments L_prop, M_prop, N_prop (N m
about the CG, from the engine model, as the thrust is) as known inputs, so that a twin's
differential thrust in yaw (each propeller sees u - r y) is not read as aerodynamic damping
(it replaces h_engine and L_engine). The mass is the record's time history (fuel burn),
gravity the local effective one (``rigid_body.local_gravity``).

Integration: classical RK4 at the record rate; the inputs at the half steps come from the
4-point cubic interpolant of the samples (``controls="linear"`` takes the mean of the two
neighbours, ``"zoh"`` holds the earlier one). Recorded signals are band-limited by the anti-
alias filters, and a linear midpoint of a smooth signal is off by its curvature: on a 50 Hz
Twin Otter record behind a 10 Hz 4-pole filter, linear midpoints bias Cl_p, Cl_da and
Cl_beta by -0.85 %, cubic ones by -0.03 % (noise-free). Output sensitivities: complex step
(Martins et al. 2003) in parallel columns, one integration carrying every parameter
perturbation as a batch: dy/dtheta_k = Im y(theta + i h e_k) / h, exact to rounding for
these analytic equations, so the Gauss-Newton steps are those of the exact information
matrix. The optimiser, bounds and refit loop are those of the shared engine
(``identification.engine``), as in output error: ``gauss_newton.maximum_likelihood``
(Newton-Raphson with R concentrated out, Levenberg-Marquardt safeguard, R re-estimated
every iteration); Cramer-Rao bounds sqrt(diag M^-1) (M&K eq. 6.50), optionally corrected
for colored residuals (M&K eq. 6.54, ``bounds``); identifiability as in output error
(unexcited controls, zero sensitivity, collinearity of the normalised information matrix)
with ``refit.refit_without_unidentifiable``; start values from equation error.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from flightid.identification.engine import identifiability as ident
from flightid.identification.engine import problem as problem_skeleton
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit
from flightid.identification.engine.refit import refit_iterated
from flightid.identification.engine.results import estimate_from_fit
from flightid.identification.estimate import Estimate
from flightid.identification.methods import equation_error
from flightid.identification.methods.nonlinear_6dof.simulation import (
    Problem,
    model_from_record,
    outputs,
    outputs_and_sensitivities,
    problem_from_record,
)
from flightid.identification.methods.protocol import Method, OutputErrorOptions, option
from flightid.identification.models import rigid_body as rb
from flightid.identification.models.six_dof import (
    CONTROLS,
    MODELS,
    ROTOR,
    SixDofModel,
    default_structure,
    parameter_name,
)
from flightid.record import FlightRecord

ID = "oe6dof"


# ------------------------------------------------------------------ estimation


def start_from_equation_error(record: FlightRecord, model: SixDofModel) -> dict[str, float]:
    """Start values of every derivative and bias from equation error on the same record.

    One least-squares fit per coefficient on the model's variables (record means as
    references, so the biases are the same parameters). Terms the regression cannot
    estimate keep the model's start values.
    """
    out: dict[str, float] = {}
    for coef, terms in model.structure.items():
        fit = equation_error.estimate(record, coef, list(terms), colored=False)
        for name in (*(parameter_name(coef, v) for v in terms), parameter_name(coef, "0")):
            if name in fit.names and name not in fit.unidentifiable:
                out[name] = fit[name]
    return out


def estimate(
    record: FlightRecord,
    model: SixDofModel | None = None,
    *,
    free: Sequence[str] | None = None,
    start: Mapping[str, float] | str | None = "equation_error",
    initial_state: str = "measured",
    controls: str = "cubic",
    full_noise_covariance: bool = False,
    colored: bool = False,
    max_iterations: int = 30,
    step_tolerance: float = 1e-3,
    cost_tolerance: float = 1e-7,
    check_identifiability: bool = True,
    min_input_range: float = ident.MIN_INPUT_RANGE,
    singular_eigenvalue: float = ident.SINGULAR_EIGENVALUE,
) -> Estimate:
    """Output-error maximum-likelihood estimate of the 6-DOF model's parameters from ``record``.

    model: default ``model_from_record(record)`` (body axes, no alphadot, no rotor).
    free: parameters to estimate (default all); the others stay at their start values.
    start: "equation_error" (default: the free parameters' start from equation error, the
    fixed ones keep the model's), a mapping of start values, or None (model's).
    initial_state: 'measured' (first sample) or 'estimate' (x0_<state> parameters, SI).
    controls: 'cubic' (default) or 'linear' interpolation between samples, or 'zoh' (held).
    Values are nondimensional derivatives, h_engine in N m s; standard errors are
    Cramer-Rao bounds (corrected for colored residuals when ``colored``).
    """
    if model is None:
        model = model_from_record(record)
    if isinstance(start, str):
        if start != "equation_error":
            raise ValueError(f"start must be a mapping, 'equation_error' or None, got {start!r}")
        start = start_from_equation_error(record, model)
        if free is not None:  # a parameter held fixed keeps its a priori value
            start = {n: v for n, v in start.items() if n in free}
    if start:
        unknown = [k for k in start if k not in model.parameters]
        if unknown:
            raise ValueError(f"start values for unknown parameter(s) {', '.join(unknown)}")
        model = replace(model, start={**model.start, **start})
    problem = problem_from_record(record, model, initial_state, controls)
    names = list(model.parameters if free is None else free)
    unknown = [n for n in names if n not in model.parameters]
    if unknown:
        raise ValueError(f"{', '.join(unknown)} not parameter(s) of the 6-DOF model "
                         f"({', '.join(model.parameters)})")
    x0_start = {n: float(problem.x0[rb.STATES.index(n[3:])]) for n in problem.x0_names}
    names += list(problem.x0_names)
    values = {**{n: model.start[n] for n in names if n in model.start}, **x0_start}

    unexcited = _unexcited(problem, names, min_input_range) if check_identifiability else {}

    # the identifiability probe of a pass (zero iterations) and the fit that follows it
    # start at the same values with the same free parameters: the fit reuses the probe's
    # outputs and sensitivities, one batched integration of the record fewer per pass
    last: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}

    def sensitivities(active: list[str], v: dict[str, float]
                      ) -> tuple[np.ndarray, np.ndarray]:
        key = (tuple(active), tuple(sorted(problem.fixed.items())), tuple(sorted(v.items())))
        if key not in last:
            last.clear()
            last[key] = outputs_and_sensitivities(problem, v, active)
        return last[key]

    def fit(active: list[str], current: dict[str, float],
            iterations: int = max_iterations) -> MaximumLikelihoodFit:
        problem.fixed = {n: v for n, v in {**model.start, **x0_start}.items() if n not in active}
        with np.errstate(over="ignore", invalid="ignore"):  # rejected diverging trial steps
            return problem_skeleton.fit(
                problem,
                lambda v: sensitivities(active, v),
                lambda v: outputs(problem, v),
                active, current, iterations, full_noise_covariance, step_tolerance,
                cost_tolerance)

    final, unidentifiable = refit_iterated(
        names, values, fit, lambda active, fitted: _singular(active, fitted, singular_eigenvalue),
        check_identifiability=check_identifiability, known=unexcited)
    # the estimate of output error ("oe"; ``run`` names the 6-DOF variant)
    est = estimate_from_fit(
        final, method="oe", model=problem.model.name, time=problem.time, measured=problem.z,
        output_names=problem.output_names, fixed=problem.fixed,
        unidentifiable=unidentifiable, colored=colored,
        full_noise_covariance=full_noise_covariance)
    est.fit.update({
        "force_axes": model.force_axes,
        "moment_axes": model.moment_axes,
        "structure": {c: list(t) for c, t in model.structure.items()},
        "references": dict(model.references),
        "integration": f"RK4 at the record rate ({1.0 / problem.dt:g} Hz), controls "
                       f"{controls}",
        "sensitivities": "complex step, batched",
        "initial_state": initial_state,
    })
    return est


def _unexcited(problem: Problem, names: Sequence[str], min_range: float) -> dict[str, str]:
    """Control derivatives whose control does not move (they multiply only that input)."""
    model = problem.model
    used = [c for c in CONTROLS if c in model.variables]
    flat = ident.unexcited_inputs(used, problem.inputs[:, [CONTROLS.index(c) for c in used]],
                                  min_range)
    out = {}
    for name in names:
        var = name.partition("_")[2]
        if var in flat:
            out[name] = (
                f"input {var} is not excited (peak-to-peak {flat[var]:.3g} rad < {min_range:g}): "
                f"{name} multiplies only {var}, so it cannot be separated from the bias terms"
            )
    return out


def _singular(names: list[str], fit: MaximumLikelihoodFit, tol: float) -> dict[str, str]:
    """Unidentifiable parameters of a fit; biases, initial states and h_engine kept in
    preference."""
    keep = [n for n in names if n.endswith("_0") or n.startswith("x0_") or n == ROTOR]
    return problem_skeleton.singular(names, fit, tol, keep)


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(OutputErrorOptions):
    """Options of ``--method oe6dof``."""

    structure: dict[str, list[str]] | None = option(
        None, "{coefficient: variables}, e.g. {\"Cm\": [\"alpha\", \"q\", \"de\"]} "
              "(default: every coefficient on its usual variables)")
    alphadot: bool = option(False, "add the alphadot terms (CL_alphadot, Cm_alphadot)")
    outputs: list[str] | None = option(None, "outputs fitted (default: those of V alpha beta "
                                             "p q r phi theta psi ax ay az the record has)")
    rotor_momentum: bool = option(False, "estimate the engine's angular momentum h_engine "
                                         "(N m s)")
    engine_torque: bool = option(False, "estimate a constant engine rolling moment (N m)")
    gravity: float | None = option(None, "gravity (m/s^2; default: at the record's latitude)")
    moment_axes: str = option("body", "axes of Cl and Cn: 'body' or 'stability'")
    propulsive_moments: bool = option(False, "take L_prop M_prop N_prop as measured inputs")
    free: list[str] | None = option(None, "parameters to estimate (default: all)")
    start: dict[str, float] | str | None = option(
        "equation_error", "start values, or 'equation_error'")
    initial_state: str = option("estimate", "'estimate' (x0 parameters) or 'measured'")
    controls: str = option("cubic", "controls between samples: 'cubic', 'linear' or 'zoh'")
    colored: bool = option(True, "Cramer-Rao bounds corrected for colored residuals")
    full_noise_covariance: bool = option(False, "estimate the full output-noise covariance")
    max_iterations: int = option(30, "Gauss-Newton iteration limit")


def run(record: FlightRecord, model: str = "6dof", options: Options | None = None
        ) -> Estimate:
    """6-DOF output error: model '6dof' (body-axis forces) or '6dof_stability' (lift and
    drag), the coefficients' structure and outputs from ``options``."""
    options = options or Options()
    if model not in MODELS:
        raise ValueError(f"6-DOF output error takes model {' or '.join(MODELS)}, got {model!r}")
    six = model_from_record(
        record, options.structure, force_axes=MODELS[model], alphadot=options.alphadot,
        outputs=options.outputs, rotor_momentum=options.rotor_momentum,
        engine_torque=options.engine_torque, gravity=options.gravity,
        moment_axes=options.moment_axes, propulsive_moments=options.propulsive_moments)
    est = estimate(
        record, six, free=options.free, start=options.start,
        initial_state=options.initial_state, controls=options.controls,
        full_noise_covariance=options.full_noise_covariance, colored=options.colored,
        max_iterations=options.max_iterations, **options.tuning())
    est.method = ID
    return est


def aerodynamic_parameters(model: str = "6dof", options: Options | None = None
                           ) -> tuple[str, ...]:
    """The aerodynamic parameters ``run`` estimates for ``model`` and ``options``, known
    before the record: every coefficient's derivatives, then its bias C_0 (what a start
    mapping, ``options.start``, may hold besides h_engine and L_engine).

    Parameters
    ----------
    model : str
        '6dof' (body-axis forces) or '6dof_stability' (lift and drag).
    options : Options or None
        The method's options (their ``structure`` and ``alphadot``).

    Returns
    -------
    tuple of str
        Names such as 'Cm_alpha', 'Cm_0'.
    """
    options = options or Options()
    if model not in MODELS:
        raise ValueError(f"6-DOF output error takes model {' or '.join(MODELS)}, got {model!r}")
    structure = options.structure or default_structure(MODELS[model], options.alphadot)
    return (*(parameter_name(c, v) for c, terms in structure.items() for v in terms),
            *(parameter_name(c, "0") for c in structure))


def channels(model: str) -> tuple[str, ...]:
    """Channels the 6-DOF model needs: states, controls, specific forces, air data."""
    return ("V", "alpha", "beta", "p", "q", "r", "phi", "theta", "ax", "ay", "az", "de", "da",
            "dr", "qbar")


METHOD = Method(
    id=ID, name="6-DOF output error",
    summary="maximum likelihood on the nonlinear rigid-body equations (RK4, complex-step "
            "sensitivities) with linear aerodynamic coefficients",
    reference="Morelli & Klein, Aircraft System Identification: Theory and Practice, "
              "2nd ed., 2016, ch. 6; Jategaonkar 2015 ch. 4",
    options=Options, models=tuple(MODELS), default_model="6dof", channels=channels,
    run=run, contract_model="6dof",
)
