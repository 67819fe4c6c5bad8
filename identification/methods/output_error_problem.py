"""A record as a linear output-error problem: its outputs and their exact sensitivities.

``Problem`` (the data and model of one fit), ``problem_from_record`` (a record's inputs
and outputs checked and arranged for a linear model), and the simulated outputs with
their sensitivities to the parameters, initial states and multistep input levels and
edges, from the exact derivative of the discretisation (``models.discrete``; Morelli &
Klein 2016 ch. 6, Jategaonkar 2015 ch. 4).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.data.multistep_input import MultistepParameters, from_measurement
from flightid.identification.engine import problem as problem_skeleton
from flightid.identification.models.discrete import (
    HOLDS,
    discretize,
    hold_inputs,
    propagate,
    simulate_matrices,
    stacked_product,
)
from flightid.identification.models.linear import LinearModel, matrix_sensitivities
from flightid.record import FlightRecord


@dataclass(kw_only=True)
class Problem(problem_skeleton.Problem):
    """The data and model of one output-error fit, arranged for fast evaluation (the
    skeleton's time, outputs, fixed parameters, initial states and noise floor, and:)."""

    model: LinearModel
    u: np.ndarray  # (N, m + 1): inputs and the constant 1
    w: np.ndarray  # per-step input of the discrete model (see hold_inputs)
    hold: str  # 'foh', 'zoh' or 'cubic' (models.discrete.HOLDS)
    x0: np.ndarray  # (n,) initial state when it is not estimated
    # multistep inputs estimated as levels and edges (multistep_input): channel -> start
    multistep: dict[str, MultistepParameters] = field(default_factory=dict)

    @property
    def input_names(self) -> list[str]:
        """Names of the estimated-input parameters (levels and edges), all channels."""
        return [n for c, ms in self.multistep.items() for n in ms.parameter_names(c)]

    @property
    def output_names(self) -> tuple[str, ...]:
        """The model's outputs, then the measured multistep inputs."""
        return (*self.model.outputs, *self.multistep)


def problem_from_record(
    record: FlightRecord, model: LinearModel, initial_state: str = "measured",
    hold: str = "foh", multistep_inputs: Sequence[str] = (),
) -> Problem:
    """Arrange a record's inputs and outputs for ``model`` (checks channels and sampling).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval, at least 10 samples.
    model : LinearModel
        The linear model; the record needs its inputs and outputs.
    initial_state : str, optional
        'measured' (default: x0 from the first sample of the state channels, 0 where the
        record has none), 'estimate' (x0_<state> parameters) or 'zero'.
    hold : str, optional
        Inputs between samples: 'foh' (default, linear) or 'zoh' (held).
    multistep_inputs : sequence of str, optional
        Input channels estimated as levels and edge times (see ``multistep_input``); their
        measurements join the outputs.

    Returns
    -------
    Problem
        Time (s), inputs with the constant 1, held inputs, measured outputs, initial state
        (SI), x0 parameter names, noise floor and multistep parameters.

    Raises
    ------
    ValueError
        A channel is missing or not finite, the sampling is not uniform, or
        ``initial_state``, ``hold`` or a multistep input is invalid.
    """
    missing = [c for c in (*model.inputs, *model.outputs) if c not in record]
    if missing:
        raise ValueError(
            f"record lacks channel(s) {', '.join(missing)} needed by the {model.name} model "
            f"(inputs {', '.join(model.inputs)}; outputs {', '.join(model.outputs)})"
        )
    time = record.time
    dt = record.uniform_step("output error", min_samples=10)
    u = np.column_stack([*(record[c] for c in model.inputs), np.ones(time.size)])
    z = np.column_stack([record[c] for c in model.outputs])
    bad = [c for c in (*model.inputs, *model.outputs) if not np.all(np.isfinite(record[c]))]
    if bad:
        raise ValueError(f"channel(s) {', '.join(bad)} contain NaN or inf values")
    if initial_state not in ("measured", "estimate", "zero"):
        raise ValueError(
            f"initial_state must be 'measured', 'estimate' or 'zero', got {initial_state!r}"
        )
    x0 = np.zeros(len(model.states))
    if initial_state == "measured":
        for j, state in enumerate(model.states):
            channel = model.state_channels.get(state, state)
            if channel in record:
                x0[j] = record[channel][0]
    x0_names = tuple(f"x0_{s}" for s in model.states) if initial_state == "estimate" else ()
    if hold not in HOLDS:
        raise ValueError(f"hold must be one of {', '.join(HOLDS)}, got {hold!r}")
    not_inputs = [c for c in multistep_inputs if c not in model.inputs]
    if not_inputs:
        raise ValueError(f"multistep input(s) {', '.join(not_inputs)} not input(s) of the "
                         f"{model.name} model ({', '.join(model.inputs)})")
    multistep = {c: from_measurement(time, record[c], hold=hold) for c in multistep_inputs}
    for c, ms in multistep.items():
        u[:, model.inputs.index(c)] = ms.samples(time, hold)
    z = np.column_stack([z, *(record[c] for c in multistep)])
    return Problem(model=model, time=time, dt=dt, u=u, w=hold_inputs(u, hold), hold=hold, z=z,
                   x0=x0, fixed={}, x0_names=x0_names,
                   noise_floor=problem_skeleton.noise_floor(z), multistep=multistep)


def _outputs(problem: Problem, values: Mapping[str, float]) -> np.ndarray:
    A, B, C, D = problem.model.build({**problem.model.start, **problem.fixed,
                                      **_model_values(problem, values)})
    u, w = _inputs(problem, values)
    y = simulate_matrices(A, B, C, D, problem.dt, u, w, _x0_of(problem, values), problem.hold)
    return np.column_stack([y, u[:, _multistep_columns(problem)]])


def _multistep_columns(problem: Problem) -> list[int]:
    return [problem.model.inputs.index(c) for c in problem.multistep]


def _inputs(problem: Problem, values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Inputs u (N, m + 1) and the held inputs w at ``values`` (multistep levels and edges)."""
    if not problem.multistep:
        return problem.u, problem.w
    u = problem.u.copy()
    current = {**problem.fixed, **values}
    for c, ms in problem.multistep.items():
        u[:, problem.model.inputs.index(c)] = (
            ms.with_parameters(c, current).samples(problem.time, problem.hold))
    return u, hold_inputs(u, problem.hold)


def _input_sensitivities(problem: Problem, values: Mapping[str, float],
                         names: Sequence[str]) -> np.ndarray:
    """du/dtheta (N, m + 1, len(names)) for the named multistep levels and edges."""
    du = np.zeros((problem.u.shape[0], problem.u.shape[1], len(names)))
    current = {**problem.fixed, **values}
    for c, ms in problem.multistep.items():
        own = ms.parameter_names(c)
        cols = [(k, own.index(n)) for k, n in enumerate(names) if n in own]
        if cols:
            d = ms.with_parameters(c, current).sensitivities(problem.time, problem.hold)
            k, j = (list(x) for x in zip(*cols, strict=True))
            du[:, problem.model.inputs.index(c), k] = d[:, j]
    return du


def _outputs_and_sensitivities(
    problem: Problem, values: Mapping[str, float], names: Sequence[str]
) -> tuple[np.ndarray, np.ndarray]:
    """Outputs (N, ny) and their sensitivities (N, ny, len(names)) to the named parameters."""
    estimated_inputs = set(problem.input_names)
    input_names = [n for n in names if n in estimated_inputs]
    model_names = [n for n in names if n not in problem.x0_names and n not in input_names]
    (A, B, C, D), (dA, dB, dC, dD) = matrix_sensitivities(
        problem.model, {**problem.fixed, **_model_values(problem, values)}, model_names
    )
    phi, gam, dphi, dgam = discretize(A, B, problem.dt, dA, dB, problem.hold)
    u, w = _inputs(problem, values)
    x = propagate(phi, w @ gam.T, _x0_of(problem, values))
    n = A.shape[0]
    columns = {name: k for k, name in enumerate(model_names)}
    x0_cols = [n_ for n_ in names if n_ in problem.x0_names]
    # forcing of the sensitivity equations: dPhi_k x_i + dGamma_k w_i, shape (N, n, np);
    # an input parameter forces them through Gamma dw/dtheta, an initial state not at all
    forcing = stacked_product(dphi, x) + stacked_product(dgam, w)
    du = _input_sensitivities(problem, values, input_names)
    dw = np.stack([hold_inputs(du[:, :, k], problem.hold) for k in range(len(input_names))],
                  axis=2) if input_names else np.zeros((len(u), w.shape[1], 0))
    nm = len(model_names)
    forcing = np.concatenate([forcing, np.einsum("ab,ibk->iak", gam, dw),
                              np.zeros((len(u), n, len(x0_cols)))], axis=2)
    start = np.zeros((n, forcing.shape[2]))
    for j, name in enumerate(input_names):
        columns[name] = nm + j
    for j, name in enumerate(x0_cols):
        columns[name] = nm + len(input_names) + j
        start[problem.x0_names.index(name), nm + len(input_names) + j] = 1.0
    xs = propagate(phi, forcing, start)
    y = x @ C.T + u @ D.T
    sens = np.matmul(C, xs)
    if model_names:
        sens[:, :, :nm] += stacked_product(dC, x) + stacked_product(dD, u)
    sens[:, :, nm:nm + len(input_names)] += np.einsum("ab,ibk->iak", D, du)
    # the measured multistep inputs are outputs too: u, sensitive to its levels and edges
    ms_cols = _multistep_columns(problem)
    ms_sens = np.zeros((len(u), len(ms_cols), sens.shape[2]))
    ms_sens[:, :, nm:nm + len(input_names)] = du[:, ms_cols, :]
    y = np.column_stack([y, u[:, ms_cols]])
    sens = np.concatenate([sens, ms_sens], axis=1)
    order = [columns[name] for name in names]
    return y, sens[:, :, order]


def _x0_of(problem: Problem, values: Mapping[str, float]) -> np.ndarray:
    if not problem.x0_names:
        return problem.x0
    return np.array([values.get(n, problem.fixed.get(n, problem.x0[j]))
                     for j, n in enumerate(problem.x0_names)])


def _model_values(problem: Problem, values: Mapping[str, float]) -> dict[str, float]:
    nuisance = {*problem.x0_names, *problem.input_names}
    return {k: v for k, v in values.items() if k not in nuisance}
