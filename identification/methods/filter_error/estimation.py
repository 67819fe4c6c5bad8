"""Filter-error method: maximum likelihood with a steady-state Kalman filter inside.

For flights in turbulence (Jategaonkar 2015, ch. 5; Maine & Iliff 1985; Morelli & Klein
2016, ch. 6) the linear model of ``linear_models`` is given process noise:

    x_{k+1} = Phi x_k + Gamma w_k + e_k,   e_k ~ N(0, Q_d),   z_k = C x_k + D u_k + v_k,

with Phi, Gamma the exact discretisation of (A, B) used by output error (first-order hold
on the inputs), Q_d = int_0^dt e^{A s} F F^T e^{A^T s} ds the discretisation of the
continuous white process noise F n(t) (unit intensity, F diagonal; Van Loan 1978) and
v_k ~ N(0, R) the measurement noise. The steady-state predicted-state covariance P solves
the discrete algebraic Riccati equation (``scipy.linalg.solve_discrete_are``); the Kalman
gain is K = P C^T S^-1 with the innovation covariance S = C P C^T + R. The one-step
predictor

    nu_k = z_k - C x~_k - D u_k,   x~_{k+1} = Phi (x~_k + K nu_k) + Gamma w_k

gives the innovations nu, and the negative log-likelihood (Jategaonkar ch. 5)

    J(theta) = 1/2 sum_k nu_k^T S^-1 nu_k + N/2 ln det S.

Estimation (default, ``joint_noise``): Gauss-Newton on the derivatives, biases, the
diagonal of F and the measurement-noise standard deviations sigma_<output> together, on
the full likelihood J, started twice, from output error and from the end point of
Jategaonkar's relaxation (sec. 5.8; ``joint_noise=False`` gives the relaxation alone);
the lower J is kept. At the converged point the derivatives are corrected for the
measured dynamic pressure and airspeed departing from the reference condition
(``flight_condition``), and the bounds are the Cramer-Rao bounds sqrt(diag M^-1) (M&K
eq. 6.50) or, with ``colored``, the score sandwich of
``iteration.robust_covariance``. Output error supplies the start values and decides
which parameters the flight cannot determine; the same checks of ``identifiability`` are
repeated on the filter's information matrix, and the fit is repeated without the
parameters they find (``refit.refit_without_unidentifiable``). The relaxation's two
steps, the noise floor and the measured comparisons are in docs/methods.md ("Filter
error").
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from flightid.identification.engine import identifiability as ident
from flightid.identification.engine.bounds import cramer_rao_covariance, standard_errors
from flightid.identification.engine.metrics import r_squared_by_output
from flightid.identification.engine.refit import refit_without_unidentifiable
from flightid.identification.engine.threads import one_blas_thread
from flightid.identification.estimate import Estimate, StdKind
from flightid.identification.methods import output_error as oe
from flightid.identification.methods.filter_error.flight_condition import (
    ConditionDeparture,
    condition_correction,
    condition_departure,
    innovation_change,
)
from flightid.identification.methods.filter_error.iteration import robust_covariance
from flightid.identification.methods.filter_error.kalman_filter import (
    FilterProblem,
    is_noise_parameter,
    measurement_noise_name,
    process_noise_name,
    require_filter,
)
from flightid.identification.methods.filter_error.relaxation import Relaxed, relax, two_starts
from flightid.identification.methods.output_error_problem import problem_from_record
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

ID = "fem"
KINEMATIC_STATES = ("phi", "theta", "psi")
# smallest measurement-noise standard deviation, as a fraction of the output-error residual
# standard deviation of the same output: on real data the process noise can explain all
# of an output's innovation, which drives R to zero (K C -> I, the filter then follows the
# measured states and the method degenerates towards equation error)
MIN_NOISE_FRACTION = 0.01


# ------------------------------------------------------------------ estimation


@one_blas_thread
def estimate(
    record: FlightRecord,
    model: LinearModel,
    *,
    free: Sequence[str] | None = None,
    start: Mapping[str, float] | None = None,
    process_noise: Sequence[str] | None = None,
    process_noise_start: Mapping[str, float] | None = None,
    initial_state: str = "measured",
    hold: str = "foh",
    max_iterations: int = 60,
    max_relaxations: int = 20,
    step_tolerance: float = 1e-3,
    cost_tolerance: float = 1e-6,
    noise_tolerance: float = 1e-3,
    check_identifiability: bool = True,
    condition_correction: bool = True,
    colored: bool = False,
    joint_noise: bool = True,
    warm_start: Estimate | None = None,
) -> Estimate:
    """Filter-error maximum-likelihood estimate of ``model``'s parameters from ``record``.

    Converged when a Gauss-Newton pass moved no parameter by more than ``step_tolerance``
    of its standard error (or J by less than ``cost_tolerance`` of |J|) and the R update
    changed no variance by more than ``noise_tolerance`` (relative).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval.
    model : LinearModel
        The linear model.
    free : sequence of str or None, optional
        Model parameters to estimate (default all).
    start : mapping of str to float or None, optional
        A priori values overriding the model's (the iteration starts from an output-error
        fit from there).
    process_noise : sequence of str or None, optional
        The states whose equations carry process noise, each with a free F_<state> (state
        units per sqrt(s)); default every state except the Euler angles. A text
        'beta,p,r' is split on commas.
    process_noise_start : mapping of str to float or None, optional
        Start values of F_<state> (default: half the output-error residual standard
        deviation of the state's channel, per sqrt(s)).
    initial_state : str, optional
        'measured' (default) or 'zero' (the filter forgets it within a few samples).
    hold : str, optional
        Inputs between samples: 'foh' (default here), 'zoh' or 'cubic' (the default of
        ``--method fem``, ``method.Options``).
    max_iterations : int, optional
        Gauss-Newton iterations (per relaxation pass). Default 60.
    max_relaxations : int, optional
        Limit of alternating parameter / R updates. Default 20.
    step_tolerance : float, optional
        Step tolerance, standard errors. Default 1e-3.
    cost_tolerance : float, optional
        Relative cost tolerance. Default 1e-6.
    noise_tolerance : float, optional
        Relative change of R below which it has converged. Default 1e-3.
    check_identifiability : bool, optional
        Fix the parameters the flight cannot determine and refit. Default True.
    condition_correction : bool, optional
        Subtract the first-order effect of the measured dynamic pressure and airspeed
        departing from the reference condition (``flight_condition``; models without an
        airspeed state, records with qbar and V channels). Default True.
    colored : bool, optional
        Standard errors from ``iteration.robust_covariance`` (the sandwich for colored
        innovations) instead of the Cramer-Rao bounds M^-1, which are then in
        ``fit['cramer_rao_std']``. Default False.
    joint_noise : bool, optional
        Estimate the measurement-noise standard deviations sigma_<output> (output units)
        with the other parameters, by Gauss-Newton on the full likelihood from the
        output-error start and from the relaxation's end point, keeping the lower J
        (default True), instead of the relaxation alone with the closed-form R update.
    warm_start : Estimate or None, optional
        A filter-error estimate of the same record by a model that this one contains
        (the same outputs and process-noise states): the iteration starts from its end
        point (its parameters, process noise, measurement noise and noise floor; this
        model's other parameters at their start values) instead of from an output-error
        fit. From the contained model's optimum the relaxation can only lower J, where
        a start from output error may end on a worse local optimum of the noise
        parameters (docs/gap.md, step 4b). Default None.

    Returns
    -------
    Estimate
        Nondimensional derivatives, SI-unit biases, F_<state> (and sigma_<output>) with
        their standard errors; ``fit`` holds the noise and innovation standard deviations,
        the Kalman gain, the condition correction, the starts' costs and the convergence.

    Raises
    ------
    ValueError
        An invalid ``initial_state``, process noise on an unknown state or on none, an
        unknown ``process_noise_start`` key, or a ``warm_start`` that is not a
        filter-error estimate of this model's outputs.
    """
    if initial_state not in ("measured", "zero"):
        raise ValueError(
            f"filter error takes initial_state 'measured' or 'zero', got {initial_state!r} "
            "(the Kalman filter forgets the initial state, so it is not estimated)"
        )
    if warm_start is not None and not (
            warm_start.method == ID
            and set(model.outputs) <= set(warm_start.fit.get("noise_floor", {}))):
        raise ValueError(
            "warm_start must be a filter-error estimate of the same record by a model this "
            f"one contains (outputs {', '.join(model.outputs)}); got a "
            f"{warm_start.method!r} estimate")
    if start:
        model = model.with_start(**start)
    if isinstance(process_noise, str):  # 'beta' or 'beta,p,r' from the command line
        process_noise = [s.strip() for s in process_noise.split(",") if s.strip()]
    noise_states = tuple(s for s in model.states if s not in KINEMATIC_STATES) \
        if process_noise is None else tuple(process_noise)
    bad = [s for s in noise_states if s not in model.states]
    if bad:
        raise ValueError(f"process noise on unknown state(s) {', '.join(bad)}; the "
                         f"{model.name} model has states {', '.join(model.states)}")
    if not noise_states:
        raise ValueError("filter error needs process noise on at least one state; without "
                         "it the method is output error (use output_error.estimate)")
    names = list(model.parameters if free is None else free)

    # output error first (start values, measurement noise and identifiability), or the
    # end point of a contained model's filter-error fit
    oe_fit = warm_start if warm_start is not None else oe.estimate(
        record, model, free=names, initial_state=initial_state, hold=hold,
        check_identifiability=check_identifiability)
    data = problem_from_record(record, model, initial_state, hold)
    unidentifiable = dict(oe_fit.unidentifiable)
    R = np.diag([oe_fit.fit["noise_std"][o] ** 2 for o in model.outputs])
    f_start = {}
    for s in noise_states:
        channel = model.state_channels.get(s, s)
        sigma = oe_fit.fit["noise_std"].get(channel, np.sqrt(np.mean(np.diag(R))))
        name = process_noise_name(s)
        f_start[name] = (abs(oe_fit[name]) if warm_start is not None and name in oe_fit.names
                         else 0.5 * sigma)
    for k, v in (process_noise_start or {}).items():
        if k not in f_start:
            raise ValueError(f"process_noise_start has {k!r}; process-noise parameters are "
                             f"{', '.join(f_start)}")
        f_start[k] = float(v)
    values = {n: (oe_fit[n] if n in oe_fit.names else model.start[n]) for n in names}
    values.update(f_start)
    all_names = [n for n in names if n not in unidentifiable] + list(f_start)
    if joint_noise:
        sigma_start = {measurement_noise_name(o): float(np.sqrt(R[j, j]))
                       for j, o in enumerate(model.outputs)}
        values.update(sigma_start)
        all_names += list(sigma_start)

    # lower bound of R: a fixed fraction of the output-error residual variance
    floor = np.maximum(data.noise_floor, MIN_NOISE_FRACTION**2 * np.diag(R))
    if warm_start is not None:  # the contained model's floor: its optimum stays feasible
        floor = np.array([warm_start.fit["noise_floor"][o] ** 2 for o in model.outputs])

    def fit(active: list[str], current: dict[str, float]) -> Relaxed:
        # parameters found unidentifiable stay at the values of the fit that found them,
        # and the next relaxation starts from its R
        nonlocal R
        prob = FilterProblem(data, active,
                        {n: v for n, v in {**model.start, **current}.items()
                         if n in model.parameters and n not in active},
                        noise_states,
                        {n: 0.0 for n in f_start if n not in active})
        theta = np.array([current[n] for n in active])
        if joint_noise:
            relaxed = two_starts(prob, theta, R, data.x0, max_iterations, max_relaxations,
                                  step_tolerance, cost_tolerance, noise_tolerance, floor)
        else:
            relaxed = relax(prob, theta, R, data.x0, max_iterations, max_relaxations,
                             step_tolerance, cost_tolerance, noise_tolerance, floor)
        R = relaxed.R
        return relaxed

    def singular(active: list[str], relaxed: Relaxed) -> dict[str, str]:
        if not (check_identifiability and active):
            return {}
        keep = [n for n in active if n.startswith("bias_") or is_noise_parameter(n)]
        return ident.unidentifiable(active, relaxed.information, relaxed.theta,
                                    prefer_keep=keep)

    final, unidentifiable = refit_without_unidentifiable(all_names, values, fit, singular,
                                                         known=unidentifiable)
    departure = condition_departure(record, data.time, model) if condition_correction else None
    return _result(final.problem, final, unidentifiable, oe_fit, departure, colored)


def _result(prob: FilterProblem, fit: Relaxed, unidentifiable: dict[str, str],
            oe_fit: Estimate, departure: ConditionDeparture | None,
            colored: bool) -> Estimate:
    names = prob.names
    d = prob.data
    ev = fit.evaluation
    require_filter(ev)
    correction = np.zeros(len(names))
    if names:
        innovations = ev.nu
        if departure is not None:
            scaled = innovation_change(names, fit.theta, ev, d, departure)
            correction = condition_correction(fit.information, ev.sensitivities,
                                              np.linalg.inv(ev.flt.S), scaled)
            innovations = ev.nu + scaled  # those of the model that follows the condition
        crb = cramer_rao_covariance(fit.information)
        crb = 0.5 * (crb + crb.T)
        cov = robust_covariance(fit.information, ev.sensitivities,
                                ev.covariance_sensitivities, innovations,
                                ev.flt.S) if colored else crb
        kind = StdKind.CRAMER_RAO_COLORED if colored else StdKind.CRAMER_RAO
    else:
        crb = cov = np.zeros((0, 0))
        kind = StdKind.NONE
    std = standard_errors(cov)
    values = fit.theta - correction
    for j, name in enumerate(names):
        if is_noise_parameter(name):
            values[j] = abs(values[j])
    predicted = d.z - ev.nu
    outputs = {
        name: {"measured": d.z[:, j], "model": predicted[:, j], "residual": ev.nu[:, j]}
        for j, name in enumerate(d.model.outputs)
    }
    r2 = r_squared_by_output(d.z, ev.nu, d.model.outputs)
    outs = d.model.outputs
    joint = {o for o in outs if measurement_noise_name(o) in names}
    fit_stats = {
        "model": d.model.name,
        "converged": fit.converged,
        "reason": fit.reason,
        "iterations": fit.iterations,
        "relaxation_steps": fit.passes,
        "start": fit.start,
        "start_costs": fit.start_costs,
        "cost_history": list(fit.cost_history),
        "cost": ev.cost,
        "noise_std": {o: float(np.sqrt(fit.R[j, j])) for j, o in enumerate(outs)},
        "noise_floor": {o: float(np.sqrt(fit.lower[j])) for j, o in enumerate(outs)},
        # the relaxation's R update stops at the floor; the joint fit's sigma_<output> has
        # no bound, and one estimated below the floor is reported as such
        "noise_at_lower_bound": [o for j, o in enumerate(outs) if o not in joint
                                 and fit.R[j, j] <= fit.lower[j] * (1 + 1e-9)],
        "noise_below_floor": [o for j, o in enumerate(outs) if o in joint
                              and fit.R[j, j] < fit.lower[j]],
        "noise_covariance": fit.R,
        "noise_history": [dict(zip(outs, np.sqrt(r).tolist(), strict=True))
                          for r in fit.noise_history],
        "innovation_std": {o: float(np.sqrt(ev.flt.S[j, j])) for j, o in enumerate(outs)},
        "innovation_covariance": ev.flt.S,
        "kalman_gain": ev.flt.K,
        "kalman_gain_times_C": np.diag(ev.flt.K @ ev.flt.C),
        "process_noise_states": list(prob.noise_states),
        "R2_per_output": r2,
        "R2": float(np.nanmean(list(r2.values()))),
        "fixed": {n: float(v) for n, v in {**prob.fixed, **prob.fixed_noise}.items()},
        "cramer_rao_std": dict(zip(names, standard_errors(crb).tolist(), strict=True)),
        "condition_correction": (None if departure is None else
                                 dict(zip(names, correction.tolist(), strict=True))),
        "samples": int(d.z.shape[0]),
        "high_correlations": ident.high_correlations(names, cov, 0.9) if names else [],
        "output_error": oe_fit.fit["output_error"] if oe_fit.method == ID else
        {"cost": oe_fit.fit["cost"], "converged": oe_fit.fit["converged"]},
    }
    return Estimate(
        method=ID,
        names=list(names),
        values=values,
        std=std,
        covariance=cov,
        fit=fit_stats,
        unidentifiable=dict(unidentifiable),
        outputs=outputs,
        time=d.time.copy(),
        std_kind=kind,
    )
