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

Integration: classical RK4 at the record rate, the inputs at the half steps from the
4-point cubic interpolant of the samples (``controls``); output sensitivities by complex
step (Martins et al. 2003), one batched integration carrying every parameter perturbation,
exact to rounding. Optimiser, bounds, identifiability checks and refit loop: the shared
engine (``identification.engine``), as in output error; start values from equation error.
Details and measured effects: docs/methods.md ("Output error on the nonlinear 6-DOF").
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
from flightid.identification.methods.nonlinear_6dof.problem import (
    Problem,
    model_from_record,
    problem_from_record,
)
from flightid.identification.methods.nonlinear_6dof.simulation import (
    outputs,
    outputs_and_sensitivities,
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
    estimate are left out, so they keep the model's start values.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : SixDofModel
        The 6-DOF model structure.

    Returns
    -------
    dict of str to float
        {parameter: value}: derivatives per rad (dimensionless), biases C_0 dimensionless.
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

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval.
    model : SixDofModel or None, optional
        The model; default ``model_from_record(record)`` (body axes, no alphadot, no rotor).
    free : sequence of str or None, optional
        Parameters to estimate (default all); the others stay at their start values.
    start : mapping of str to float, str or None, optional
        "equation_error" (default: the free parameters' start from equation error, the
        fixed ones keep the model's), a mapping of start values, or None (the model's).
    initial_state : str, optional
        'measured' (default: first sample) or 'estimate' (x0_<state> parameters, SI).
    controls : str, optional
        Controls between samples: 'cubic' (default) or 'linear' interpolation, or 'zoh'
        (held).
    full_noise_covariance : bool, optional
        Estimate the full output-noise covariance. Default False.
    colored : bool, optional
        Cramer-Rao bounds corrected for colored residuals. Default False.
    max_iterations : int, optional
        Gauss-Newton iteration limit. Default 30.
    step_tolerance : float, optional
        Converged when no step exceeds this many standard errors. Default 1e-3.
    cost_tolerance : float, optional
        Or when the ML cost changes less than this (absolute). Default 1e-7.
    check_identifiability : bool, optional
        Fix the parameters the flight cannot determine and refit. Default True.
    min_input_range : float, optional
        A control spanning less than this (peak to peak, rad) is not excited.
    singular_eigenvalue : float, optional
        Relative eigenvalue of the information matrix below which it is singular.

    Returns
    -------
    Estimate
        Nondimensional derivatives and biases, h_engine in N m s, L_engine in N m, x0 in SI
        units, with Cramer-Rao bounds; method "oe" (``run`` names the 6-DOF variant), ``fit``
        also holding the axes, structure, references, integration and initial state.

    Raises
    ------
    ValueError
        An invalid ``start``, start values or free parameters not in the model, or a record
        the model cannot use.
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
    """6-DOF output error with the coefficients' structure and outputs from ``options``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval.
    model : str, optional
        '6dof' (default, body-axis forces) or '6dof_stability' (lift and drag).
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        The estimate (``estimate``), method ``ID``.

    Raises
    ------
    ValueError
        ``model`` is not a 6-DOF model.
    """
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
    """Channels the 6-DOF model needs: states, controls, specific forces, air data.

    Parameters
    ----------
    model : str
        The 6-DOF model name (the channels are the same for both).

    Returns
    -------
    tuple of str
        V, alpha, beta, p, q, r, phi, theta, ax, ay, az, de, da, dr, qbar.
    """
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
