"""The simulation of a six-degree-of-freedom output-error problem (``problem``): the
rigid-body equations (``models.rigid_body``) driven by the measured controls (linear,
cubic or held between samples) and the propulsive terms, integrated by RK4 for many
parameter sets at once; the outputs and their complex-step sensitivities.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from flightid.identification.methods.nonlinear_6dof.problem import Problem, problem_from_record
from flightid.identification.models import rigid_body as rb
from flightid.identification.models.six_dof import (
    COLUMNS,
    ROTOR,
    TORQUE,
    VARIABLES,
    SixDofModel,
)
from flightid.record import FlightRecord


def aero(model: SixDofModel, x, controls: tuple, thrust, rho, combine, xp=np) -> tuple:
    """Aerodynamic state of states x[9, ...] (an array, or Python floats with xp=SCALAR).

    Parameters
    ----------
    model : SixDofModel
        The model (reference geometry, references, axes).
    x : numpy.ndarray or list
        States, shape (9, ...), SI units.
    controls : tuple
        (de, da, dr) minus their references, rad, broadcast against x[0].
    thrust : float or numpy.ndarray
        Thrust along body x, N.
    rho : float or numpy.ndarray
        Air density, kg/m^3.
    combine : callable
        ``combine(rows)`` maps the regressor rows (alpha, beta, phat, qhat, rhat, de, da, dr
        as perturbations) to the six coefficients, without the alphadot terms
        (``batch_combination``, ``scalar_combination``).
    xp : module or namespace, optional
        numpy (default) or ``rigid_body.SCALAR``.

    Returns
    -------
    tuple
        Body forces fx, fy, fz (N, thrust included), the six coefficients, qbar S (N),
        V (m/s), alpha and beta (rad), and 1/(2V) (s/m).
    """
    ref, refs = model.reference, model.references
    u, v, w = x[0], x[1], x[2]
    uw2 = u * u + w * w
    speed2 = uw2 + v * v
    speed = xp.sqrt(speed2)
    alpha = xp.arctan(w / u)
    beta = xp.arcsin(v / speed)
    inv2v = 0.5 / speed
    uw = xp.sqrt(uw2)
    ca, sa = u / uw, w / uw  # cos(alpha), sin(alpha)
    p, r = x[3], x[5]
    stability_moments = model.moment_axes == "stability"
    if stability_moments:
        p, r = p * ca + r * sa, r * ca - p * sa
    coef = combine((alpha - refs.get("alpha", 0.0), beta - refs.get("beta", 0.0),
                    p * (ref.span * inv2v) - refs.get("p", 0.0),
                    x[4] * (ref.chord * inv2v) - refs.get("q", 0.0),
                    r * (ref.span * inv2v) - refs.get("r", 0.0), *controls))
    if stability_moments:
        cl, cn = coef[3], coef[5]
        coef = (coef[0], coef[1], coef[2], cl * ca - cn * sa, coef[4], cl * sa + cn * ca)
    qs = (0.5 * ref.area) * rho * speed2
    if model.force_axes == "body":
        cx, cz = coef[0], coef[2]
    else:
        # lift and drag in the local stability axes (rotation by alpha)
        cx = coef[2] * sa - coef[0] * ca
        cz = -coef[2] * ca - coef[0] * sa
    return qs * cx + thrust, qs * coef[1], qs * cz, coef, qs, speed, alpha, beta, inv2v


def batch_combination(model: SixDofModel, theta: np.ndarray, shape: tuple[int, ...]):
    """combine(rows) for arrays: one einsum of theta (6, 10, K) with the regressors.

    Parameters
    ----------
    model : SixDofModel
        The model (its alphadot reference).
    theta : numpy.ndarray
        Coefficient tensors, shape (6, 10, K), real or complex.
    shape : tuple of int
        Trailing shape of the states, ending in K.

    Returns
    -------
    callable
        ``combine(rows)`` returning the six coefficients, shape (6, *shape).
    """
    reg = np.empty((1 + len(VARIABLES), *shape), dtype=theta.dtype)
    reg[0] = 1.0
    reg[9] = -model.references.get("alphadot", 0.0)

    def combine(rows: tuple) -> np.ndarray:
        for j, row in enumerate(rows, start=1):
            reg[j] = row
        return np.einsum("jrk,r...k->j...k", theta, reg)

    return combine


def scalar_combination(model: SixDofModel, theta: np.ndarray):
    """combine(rows) for Python floats: sums over the nonzero terms of theta (6, 10, 1).

    Parameters
    ----------
    model : SixDofModel
        The model (its alphadot reference).
    theta : numpy.ndarray
        Coefficient tensor, shape (6, 10, 1), real.

    Returns
    -------
    callable
        ``combine(rows)`` returning the six coefficients as a list of float.
    """
    t = theta[..., 0].tolist()
    adot_ref = model.references.get("alphadot", 0.0)
    const = [t[j][0] - t[j][9] * adot_ref for j in range(6)]
    terms = [[(c - 1, t[j][c]) for c in range(1, 9) if t[j][c] != 0.0] for j in range(6)]

    def combine(rows: tuple) -> list[float]:
        out = []
        for j in range(6):
            value = const[j]
            for c, k in terms[j]:
                value += k * rows[c]
            out.append(value)
        return out

    return combine


def integrate(problem: Problem, theta: np.ndarray, engine: np.ndarray, x0: np.ndarray
               ) -> np.ndarray:
    """States for a batch of K coefficient tensors, by RK4 at the record rate.

    One real trajectory (K = 1) runs on Python floats, a batch on numpy arrays.

    Parameters
    ----------
    problem : Problem
        The 6-DOF problem.
    theta : numpy.ndarray
        Coefficient tensors, shape (6, 10, K).
    engine : numpy.ndarray
        Rotor angular momentum (N m s) and engine rolling moment (N m), shape (2, K).
    x0 : numpy.ndarray
        Initial states, shape (9, K), SI units.

    Returns
    -------
    numpy.ndarray
        States, shape (N, 9, K): m/s, rad/s, rad.
    """
    model = problem.model
    ref, mp = model.reference, model.mass
    stages = problem.stage_inputs.tolist()
    has_adot = "alphadot" in model.variables
    scalar = x0.shape[1] == 1 and not np.iscomplexobj(theta)
    if scalar:
        xp, combine = rb.SCALAR, scalar_combination(model, theta)
        adot = theta[3:, COLUMNS["alphadot"], 0].tolist()
        rotor, torque = engine[:, 0].tolist()
        x0 = x0[:, 0]
    else:
        xp, combine = np, batch_combination(model, theta, x0.shape[1:])
        adot = theta[3:, COLUMNS["alphadot"]]  # (3, K): Cl, Cm, Cn per alphadot_hat
        rotor, torque = engine
    span, chord = ref.span, ref.chord

    def rhs(state: np.ndarray, i: int, stage: int) -> np.ndarray:
        x = state.tolist() if scalar else state
        de, da, dr, thrust, rho, mass, l_prop, m_prop, n_prop = stages[stage][i]
        fx, fy, fz, coef, qs, _, _, _, inv2v = aero(model, x, (de, da, dr), thrust, rho,
                                                    combine, xp)
        trig = rb.euler_trig(x, xp)
        udot, vdot, wdot = rb.translational(x, fx / mass, fy / mass, fz / mass, mp.g, trig)
        cl, cm, cn = coef[3], coef[4], coef[5]
        if has_adot:
            u, w = x[0], x[2]
            adot_hat = (u * wdot - w * udot) / (u * u + w * w) * (chord * inv2v)
            cl, cm, cn = cl + adot[0] * adot_hat, cm + adot[1] * adot_hat, cn + adot[2] * adot_hat
        pdot, qdot, rdot = rb.rotational(x, qs * span * cl + torque + l_prop,
                                         qs * chord * cm + m_prop, qs * span * cn + n_prop,
                                         mp, rotor)
        out = (udot, vdot, wdot, pdot, qdot, rdot, *rb.kinematic(x, trig))
        return np.array(out) if scalar else np.stack(out)

    states = rb.rk4(rhs, x0, problem.time.size - 1, problem.dt)
    return states[:, :, None] if scalar else states


def outputs_of_states(problem: Problem, states: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """The model outputs of integrated states.

    Parameters
    ----------
    problem : Problem
        The 6-DOF problem (inputs and output names).
    states : numpy.ndarray
        States, shape (N, 9, K).
    theta : numpy.ndarray
        Coefficient tensors, shape (6, 10, K).

    Returns
    -------
    numpy.ndarray
        Outputs, shape (N, K, ny), SI units (ax, ay, az specific forces, m/s^2).
    """
    model = problem.model
    x = states.transpose(1, 0, 2)
    inp = problem.inputs.T[:, :, None]  # (9, N, 1)
    combine = batch_combination(model, theta, x.shape[1:])
    fx, fy, fz, _, _, speed, alpha, beta, _ = aero(model, x, tuple(inp[:3]), inp[3], inp[4],
                                                   combine)
    m = inp[5]
    columns = {"V": speed, "alpha": alpha, "beta": beta, "ax": fx / m, "ay": fy / m,
               "az": fz / m}
    for j, s in enumerate(rb.STATES[3:], start=3):
        columns[s] = x[j]
    return np.stack([columns[o] for o in model.outputs], axis=-1)


def batch_outputs(problem: Problem, values: Mapping[str, float],
           columns: Mapping[str, np.ndarray], k: int, dtype: type
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coefficient tensors, engine terms and initial states of a batch of parameter sets.

    Parameters
    ----------
    problem : Problem
        The 6-DOF problem.
    values : mapping of str to float
        Parameter values common to the batch (the others at the model's start values).
    columns : mapping of str to numpy.ndarray
        Arrays (k,) that override ``values`` per batch member.
    k : int
        Batch size.
    dtype : type
        float, or complex for the complex step.

    Returns
    -------
    theta : numpy.ndarray
        Coefficient tensors, shape (6, 10, k).
    engine : numpy.ndarray
        h_engine (N m s) and L_engine (N m), shape (2, k).
    x0 : numpy.ndarray
        Initial states, shape (9, k).
    """
    model = problem.model
    index = model.index()
    theta = np.zeros((6, 1 + len(VARIABLES), k), dtype=dtype)
    engine = np.zeros((2, k), dtype=dtype)
    x0 = np.repeat(problem.x0.astype(dtype)[:, None], k, axis=1)
    for name, value in {**model.start, **values, **columns}.items():
        if name in index:
            theta[index[name][0], index[name][1]] = value
        elif name == ROTOR:
            engine[0] = value
        elif name == TORQUE:
            engine[1] = value
        elif name in problem.x0_names:
            x0[rb.STATES.index(name[3:])] = value
    return theta, engine, x0


def outputs(problem: Problem, values: Mapping[str, float]) -> np.ndarray:
    """Model outputs at parameter values (the others at their fixed or start values).

    A trajectory that leaves the domain of the equations (a trial step of the optimiser
    that makes the model diverge) gives NaN outputs, which the optimiser rejects.

    Parameters
    ----------
    problem : Problem
        The 6-DOF problem.
    values : mapping of str to float
        Parameter values.

    Returns
    -------
    numpy.ndarray
        Outputs, shape (N, ny), SI units.
    """
    theta, engine, x0 = batch_outputs(problem, {**problem.fixed, **values}, {}, 1, float)
    try:
        with np.errstate(all="ignore"):
            states = integrate(problem, theta, engine, x0)
            return outputs_of_states(problem, states, theta)[:, 0]
    except (ValueError, OverflowError, ZeroDivisionError):
        return np.full(problem.z.shape, np.nan)


def outputs_and_sensitivities(problem: Problem, values: Mapping[str, float],
                               names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Outputs and complex-step sensitivities, one batched run.

    Parameters
    ----------
    problem : Problem
        The 6-DOF problem.
    values : mapping of str to float
        Parameter values.
    names : sequence of str
        Parameters to differentiate with respect to.

    Returns
    -------
    y : numpy.ndarray
        Outputs, shape (N, ny).
    sensitivities : numpy.ndarray
        dy/dtheta, shape (N, ny, len(names)).
    """
    if not names:
        return outputs(problem, values), np.zeros((problem.z.shape[0], problem.z.shape[1], 0))
    base = {**problem.fixed, **values}
    k = len(names)
    steps = np.array([1e-20 * max(1.0, abs(base[n])) for n in names])
    columns = {}
    for j, name in enumerate(names):
        col = np.full(k, base[name], dtype=complex)
        col[j] += 1j * steps[j]
        columns[name] = col
    theta, engine, x0 = batch_outputs(problem, base, columns, k, complex)
    states = integrate(problem, theta, engine, x0)
    y = outputs_of_states(problem, states, theta)  # (N, k, ny)
    sens = np.ascontiguousarray((y.imag / steps[None, :, None]).transpose(0, 2, 1))
    return y[:, 0].real.copy(), sens


def simulate(record: FlightRecord, model: SixDofModel, values: Mapping[str, float] | None = None,
             controls: str = "cubic", x0: Mapping[str, float] | None = None
             ) -> dict[str, np.ndarray]:
    """Model outputs for a record's inputs at parameter ``values``.

    Use it to predict a maneuver not used in the fit.

    Parameters
    ----------
    record : FlightRecord
        The flight whose inputs drive the model, SI channels.
    model : SixDofModel
        The 6-DOF model.
    values : mapping of str to float or None, optional
        Parameter values; those not given take the model's start values.
    controls : str, optional
        Inputs at the RK4 half steps: 'cubic' (default), 'linear' or 'zoh'.
    x0 : mapping of str to float or None, optional
        {"x0_<state>": value} applied to the record's first sample, SI units.

    Returns
    -------
    dict of str to numpy.ndarray
        {output: time history}, SI units.
    """
    problem = problem_from_record(record, model, "estimate" if x0 else "measured", controls)
    problem.fixed = dict(x0 or {})
    y = outputs(problem, dict(values or {}))
    return {o: y[:, j] for j, o in enumerate(model.outputs)}


