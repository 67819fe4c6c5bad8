"""Output-error (maximum likelihood) estimation for linear models, with Cramer-Rao bounds.

Morelli & Klein (2016) ch. 6 and Jategaonkar (2015) ch. 4: minimise
    J(theta) = 1/2 sum_i v_i^T R^-1 v_i,   v_i = z_i - y_i(theta)
by Gauss-Newton (modified Newton-Raphson) with Levenberg-Marquardt damping, the
measurement-noise covariance R re-estimated from the residuals at every iteration
(relaxation algorithm, M&K eq. 6.27). Output sensitivities come from the exact derivative
of the zero-order-hold discretisation: for each parameter the augmented system
[[A, 0], [A_k, A]], [[B], [B_k]] is discretised with one matrix exponential (batched),
and the state and all sensitivities are propagated together (``models.discrete``).

The optimiser, the bounds and the refit loop are those of the shared engine
(``identification.engine``): ``gauss_newton.maximum_likelihood`` on the outputs and
sensitivities of this module; Cramer-Rao bounds sqrt(diag M^-1) with
M = sum_i S_i^T R^-1 S_i (M&K eq. 6.50), or with ``colored=True`` corrected for colored
residuals (M&K eq. 6.54, SIDPAC ``m_colores``, ``bounds``). Parameters the flight cannot
determine (``identifiability``) are fixed at their a priori values and the rest refitted
(``refit.refit_without_unidentifiable``); they are listed with the reason in
``Estimate.unidentifiable``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flightid.identification.engine import identifiability as ident
from flightid.identification.engine import problem as problem_skeleton
from flightid.identification.engine.bounds import (
    colored_residual_covariance as colored_residual_covariance,  # public here too
)
from flightid.identification.engine.bounds import leverage_power
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit
from flightid.identification.engine.refit import refit_iterated
from flightid.identification.engine.results import estimate_from_fit
from flightid.identification.estimate import Estimate
from flightid.identification.methods.equation_error_reference import (
    check_structure,
    start_from_equation_error,
)
from flightid.identification.methods.output_error_problem import (
    Problem,
    _outputs,
    _outputs_and_sensitivities,
    problem_from_record,
)
from flightid.identification.methods.protocol import (
    HeldOptions,
    Method,
    OutputErrorOptions,
    option,
)
from flightid.identification.models import a_priori
from flightid.identification.models import linear as lm
from flightid.identification.models import measured_inputs as mi
from flightid.identification.models import structure as model_structure
from flightid.identification.models.linear import LinearModel, matrix_sensitivities
from flightid.record import FlightRecord

ID = "oe"


# ------------------------------------------------------------------ estimation


def estimate(
    record: FlightRecord,
    model: LinearModel,
    *,
    free: Sequence[str] | None = None,
    start: Mapping[str, float] | str | None = None,
    initial_state: str = "measured",
    hold: str = "foh",
    full_noise_covariance: bool = False,
    colored: bool = False,
    multistep_inputs: Sequence[str] = (),
    max_iterations: int = 50,
    step_tolerance: float = 1e-3,
    cost_tolerance: float = 1e-7,
    check_identifiability: bool = True,
    min_input_range: float = ident.MIN_INPUT_RANGE,
    singular_eigenvalue: float = ident.SINGULAR_EIGENVALUE,
) -> Estimate:
    """Output-error maximum-likelihood estimate of ``model``'s parameters from ``record``.

    Converged when the last step changed no parameter by more than ``step_tolerance``
    of its standard error, or the ML cost N/2 ln det R by less than ``cost_tolerance``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval.
    model : LinearModel
        The linear model.
    free : sequence of str or None, optional
        Parameters to estimate (default all); the others stay at their start values.
    start : mapping of str to float, str or None, optional
        Start (a priori) values overriding the model's, or "equation_error" to take the
        free parameters' from ``start_from_equation_error`` (the fixed ones keep theirs).
    initial_state : str, optional
        'measured' (default: x0 from the first sample of the state channels), 'estimate'
        (x0_<state> parameters, SI units) or 'zero'.
    hold : str, optional
        Inputs between samples: 'foh' (default) or 'zoh'.
    full_noise_covariance : bool, optional
        Estimate the full output-noise covariance R instead of its diagonal. Default False.
    colored : bool, optional
        Cramer-Rao bounds corrected for colored residuals (M&K eq. 6.54). Default False.
    multistep_inputs : sequence of str, optional
        Input channels flown as multisteps (doublet, 3211, pulse) whose levels and edge
        times are estimated with the derivatives (``multistep_input``: parameters
        level_<channel>_<k> in the input unit and edge_<channel>_<k> in s); their
        measurements join the outputs, so the surface noise and the timing of a step
        between two samples enter the bounds instead of biasing the derivatives.
    max_iterations : int, optional
        Gauss-Newton iteration limit. Default 50.
    step_tolerance : float, optional
        Converged when no step exceeds this many standard errors. Default 1e-3.
    cost_tolerance : float, optional
        Or when the ML cost changes less than this (absolute). Default 1e-7.
    check_identifiability : bool, optional
        Fix the parameters the flight cannot determine at their a priori values and refit,
        listing them in ``unidentifiable``. Default True.
    min_input_range : float, optional
        An input spanning less than this (peak to peak, rad) is not excited.
    singular_eigenvalue : float, optional
        Relative eigenvalue of the information matrix below which it is singular.

    Returns
    -------
    Estimate
        Nondimensional derivatives and SI-unit biases (and x0, input levels and edges),
        Cramer-Rao bounds as standard errors, fit statistics and the outputs.

    Raises
    ------
    ValueError
        An invalid ``start``, an unknown free parameter, or a record the model cannot use.
    """
    if isinstance(start, str):
        if start != "equation_error":
            raise ValueError(f"start must be a mapping or 'equation_error', got {start!r}")
        start = start_from_equation_error(record, model)
        if free is not None:  # a parameter held fixed keeps its a priori value
            start = {n: v for n, v in start.items() if n in free}
    if start:
        model = model.with_start(**start)
    problem = problem_from_record(record, model, initial_state, hold, multistep_inputs)
    names = list(model.parameters if free is None else free)
    unknown = [n for n in names if n not in model.parameters]
    if unknown:
        raise ValueError(
            f"{', '.join(unknown)} not parameter(s) of the {model.name} model "
            f"({', '.join(model.parameters)})"
        )
    names += [*problem.input_names, *problem.x0_names]
    input_start = {n: v for c, ms in problem.multistep.items()
                   for n, v in ms.parameters(c).items()}
    values = {n: model.start[n] for n in names if n in model.start}
    values.update(input_start)
    values.update({n: problem.x0[j] for j, n in enumerate(problem.x0_names)})
    problem.fixed = {n: v for n, v in model.start.items() if n not in names}

    unexcited = (_unexcited(problem, names, values, min_input_range)
                 if check_identifiability else {})
    a_priori_values = {**model.start, **input_start,
                       **dict(zip(problem.x0_names, problem.x0, strict=False))}

    def fit(active: list[str], current: dict[str, float],
            iterations: int = max_iterations) -> MaximumLikelihoodFit:
        problem.fixed = {n: v for n, v in a_priori_values.items() if n not in active}
        return _iterate(problem, active, current, iterations, full_noise_covariance,
                        step_tolerance, cost_tolerance)

    final, unidentifiable = refit_iterated(
        names, values, fit, lambda active, fitted: _singular(active, fitted, singular_eigenvalue),
        check_identifiability=check_identifiability, known=unexcited)
    return estimate_from_fit(
        final, method=ID, model=problem.model.name, time=problem.time, measured=problem.z,
        output_names=problem.output_names, fixed=problem.fixed,
        unidentifiable=unidentifiable, colored=colored,
        full_noise_covariance=full_noise_covariance,
        leverage_power=leverage_power(problem.model.name))


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(HeldOptions, OutputErrorOptions):
    """Options of ``--method oe`` (defaults: the settings validated on simulated cards)."""

    free: list[str] | None = option(None, "parameters to estimate (default: all not held)")
    start: dict[str, float] | str | None = option(
        "equation_error", "start values, or 'equation_error' for the free parameters")
    initial_state: str = option("estimate", "'estimate' (x0 parameters), 'measured' or 'zero'")
    hold: str = option("foh", "inputs between samples: 'foh' (linear), 'zoh' (held) or "
                                    "'cubic' (Catmull-Rom through four samples)")
    colored: bool = option(True, "Cramer-Rao bounds corrected for colored residuals "
                                 "(Morelli & Klein 2016 eq. 6.54)")
    full_noise_covariance: bool = option(False, "estimate the full output-noise covariance")
    multistep_inputs: list[str] = option(
        [], "inputs flown as multisteps whose levels and edge times are estimated")
    max_iterations: int = option(50, "Gauss-Newton iteration limit")
    propulsive_moments: bool = option(
        True, "drive the lateral model with the record's L_prop, N_prop (N m) where it has "
              "them, as equation error removes them: aerodynamic derivatives")
    dynamic_pressure: bool = option(
        True, "lateral model: the aerodynamic terms follow the measured qbar(t)/qbar_ref "
              "(second-order terms with the measured states and inputs as pseudo-inputs)")
    moment_axes: str = option(
        "body", "lateral model: 'stability' for an aircraft whose rolling and yawing "
                "moments are linear in the stability axes of the instantaneous alpha")
    structure_check: bool = option(
        True, "widen the bounds where equation error on the same record disagrees beyond "
              "3 combined bounds (a model structure error)")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """Output error with a linear-model preset at the record's reference condition.

    A priori parameters are held; the model is driven by the measured known inputs
    (``measured_inputs.driven_by_measurements``); attitudes the record lacks are left out
    of the outputs. A fit from the equation-error start that explains its outputs poorly
    (``RESTART_R2``) or withholds too many parameters (``RESTART_WITHHELD``) is repeated
    from the typical values and the lower cost kept.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval.
    model : str, optional
        A linear-model preset ('lateral' default, 'longitudinal', 'short_period').
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        The estimate; ``fit`` also holds the a priori values ('a_priori'), the known
        inputs, the start used ('start') and the outputs left out.
    """
    options = options or Options()
    linear, free, held = a_priori.linear_model(
        model_structure.linear(model), record, options.derivatives, options.a_priori,
        "output error")
    if options.free is not None:
        free = list(options.free)
    unmeasured = [o for o in linear.outputs
                  if o in model_structure.OPTIONAL_OUTPUTS and o not in record]
    if unmeasured:
        linear = lm.without_outputs(linear, unmeasured)
    record, linear = mi.driven_by_measurements(
        record, linear, dynamic_pressure=options.dynamic_pressure,
        propulsive_moments=options.propulsive_moments, moment_axes=options.moment_axes)
    start, start_note = options.start, ""
    if start == "equation_error":
        try:  # the free parameters' start values; the held ones keep theirs
            start = {n: v for n, v in start_from_equation_error(record, linear).items()
                     if n in free}
        except (KeyError, ValueError) as exc:  # e.g. no accelerometers for the coefficients
            start, start_note = None, f"typical values (no equation-error start: {exc})"

    def fit_from(start_values: Mapping[str, float] | None) -> Estimate:
        return estimate(
            record, linear, free=free, start=start_values,
            initial_state=options.initial_state, hold=options.hold,
            full_noise_covariance=options.full_noise_covariance, colored=options.colored,
            multistep_inputs=options.multistep_inputs, max_iterations=options.max_iterations,
            **options.tuning())

    est = fit_from(start)
    note = start_note or ("equation error" if options.start == "equation_error" else "given")
    if options.start == "equation_error" and start and _failed_fit(est, free):
        retry = fit_from(None)  # the model's typical values
        if retry.fit["cost"] < est.fit["cost"]:
            note = (f"typical values: the fit from the equation-error start ended with R^2 "
                    f"{est.fit['R2']:.2f} and {len(_withheld(est, free))} of {len(free)} "
                    f"parameters withheld, at a higher cost")
            est = retry
    est.method = ID
    if options.structure_check:
        check_structure(est, record, linear, free, held)
    est.fit["a_priori"] = a_priori.describe(record, held)
    est.fit.update(mi.known_input_notes(linear))
    est.fit["start"] = note
    if unmeasured:
        est.fit["outputs_left_out"] = {o: "not in the record (state integrated from the "
                                          "rates)" for o in unmeasured}
    return est


# a fit whose outputs explain less than this share of their variance (mean R^2), or that
# withholds more than this share of its free parameters, is started again from the
# model's typical values. On navion-sweep-yaw (a 90 s rudder sweep) the equation-error
# start led to R^2 < 0 and every derivative withheld on each development seed; from the
# typical values the same fit put 11 of 13 within 3 sigma on seed 1.
RESTART_R2 = 0.5
RESTART_WITHHELD = 0.5


def _withheld(est: Estimate, free: Sequence[str]) -> list[str]:
    return [n for n in free if n in est.unidentifiable]


def _failed_fit(est: Estimate, free: Sequence[str]) -> bool:
    """Whether a fit explains its outputs too poorly, or withholds too much, to be kept
    without trying the typical start (``RESTART_R2``, ``RESTART_WITHHELD``)."""
    r2 = est.fit.get("R2", float("nan"))
    return (not np.isfinite(r2) or r2 < RESTART_R2
            or len(_withheld(est, free)) > RESTART_WITHHELD * max(len(free), 1))


METHOD = Method(
    id=ID, name="output error",
    summary="maximum likelihood on a linear perturbation model (Gauss-Newton, exact "
            "sensitivities, Cramer-Rao bounds)",
    reference="Morelli & Klein, Aircraft System Identification: Theory and Practice, "
              "2nd ed., 2016, ch. 6; Jategaonkar, Flight Vehicle System Identification, "
              "2nd ed., 2015, ch. 4",
    options=Options, models=model_structure.LINEAR, default_model="lateral",
    channels=model_structure.output_error_channels, run=run, contract_model="lateral",
)


def _unexcited(problem: Problem, names: Sequence[str], values: Mapping[str, float],
               min_range: float) -> dict[str, str]:
    model = problem.model
    flat = ident.unexcited_inputs(model.inputs, problem.u[:, :-1], min_range)
    if not flat:
        return {}
    params = [n for n in names if n in model.parameters]
    _, (dA, dB, dC, dD) = matrix_sensitivities(model, {**model.start, **values}, params)
    # a pseudo-input of the dynamic pressure ('dr*dqbar0') belongs to its input ('dr')
    sources = [mi.pseudo_input_source(c) for c in (*model.inputs, "1")]
    touched = np.any(dB != 0, axis=1) | np.any(dD != 0, axis=1)  # (parameter, column)
    only = {}
    for k, name in enumerate(params):
        used = {sources[j] for j in np.flatnonzero(touched[k])}
        if not (np.any(dA[k]) or np.any(dC[k])) and len(used) == 1:
            only[name] = used.pop()
    out = {}
    for name, inp in only.items():
        if inp in flat:
            out[name] = (
                f"input {inp} is not excited (peak-to-peak {flat[inp]:.3g} rad < "
                f"{min_range:g}): {name} multiplies only {inp}, so it cannot be separated "
                "from the bias terms"
            )
    return out


def _iterate(problem: Problem, names: list[str], values: dict[str, float], max_iterations: int,
             full: bool, step_tol: float, cost_tol: float) -> MaximumLikelihoodFit:
    """``engine.problem.fit`` on a linear-model problem (outputs from ``_outputs``)."""
    return problem_skeleton.fit(
        problem,
        lambda current: _outputs_and_sensitivities(problem, current, names),
        lambda trial: _outputs(problem, trial),
        names, values, max_iterations, full, step_tol, cost_tol,
    )


def _singular(names: list[str], fit: MaximumLikelihoodFit, tol: float) -> dict[str, str]:
    """Unidentifiable parameters of a fit; biases and initial states kept in preference."""
    keep = [n for n in names if n.startswith("bias_") or n.startswith("x0_")]
    return problem_skeleton.singular(names, fit, tol, keep)
