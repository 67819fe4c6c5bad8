"""A candidate effect as the gap fits it (``Candidate``), and the edits of a linear model
that the candidate families share: new parameters (``extended``) and a new state fed from
an output row or an input column (``lagged_output``, ``lagged_input``).

A wrapped model's ``build`` uses arithmetic only, so the complex-step sensitivities of
``linear_models.matrix_sensitivities`` stay exact (Martins et al. 2003).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.models.linear import LinearModel, Matrices


@dataclass(frozen=True)
class Candidate:
    """One catalogue effect as the gap fits it.

    ``entry`` and ``options`` are the catalogue entry's name and options; ``free`` the
    linear-model parameters a fit frees and ``catalogue`` the entry's parameter each one
    is (same order, catalogue units; empty: ``factor``)."""

    entry: str  # catalogue name ("pair": a group of ``parts``)
    options: dict[str, str]
    free: tuple[str, ...]  # linear-model parameters the fit frees
    wrap: Callable[[LinearModel], LinearModel] = field(compare=False, repr=False)
    parts: tuple[Candidate, ...] = ()  # the single effects of a pair
    catalogue: tuple[str, ...] = ()  # the catalogue parameter of each free one

    @property
    def label(self) -> str:
        if self.parts:
            inner = " + ".join(p.label for p in self.parts)
            return inner if self.entry == "pair" else f"{self.entry}[{inner}]"
        opts = ",".join(f"{v}" for v in self.options.values())
        return f"{self.entry}({opts})"

    def parameters(self, values: Mapping[str, float], std: Mapping[str, float],
                   base: LinearModel) -> dict[str, dict[str, float]]:
        """The effect's parameters in catalogue units: {name: {"value", "std"}}; a
        ``derivative_delta``'s delta is the fitted value minus ``base``'s."""
        if self.parts:
            out: dict[str, dict[str, float]] = {}
            for p in self.parts:
                for k, v in p.parameters(values, std, base).items():
                    out[f"{p.label}.{k}"] = v
            return out
        if self.entry == "derivative_delta":
            (name,) = self.free
            return {"delta": {"value": float(values[name]) - base.start[name],
                              "std": float(std[name])}}
        names = self.catalogue or ("factor",) * len(self.free)
        return {c: {"value": float(values[f]), "std": float(std[f])}
                for c, f in zip(names, self.free, strict=True)}


def identity(model: LinearModel) -> LinearModel:
    """The model unchanged (a candidate that only frees a parameter of it).

    Parameters
    ----------
    model : LinearModel

    Returns
    -------
    LinearModel
        ``model`` itself.
    """
    return model


def extended(model: LinearModel, start: Mapping[str, float],
             build: Callable[[Mapping[str, complex]], Matrices],
             states: tuple[str, ...] = (), channel: str = "") -> LinearModel:
    """``model`` with the parameters ``start`` (name -> start value) added, the new
    ``build`` and the new ``states`` appended to its states.

    Parameters
    ----------
    model : LinearModel
        The model edited.
    start : mapping of str to float
        The new parameters and their start values.
    build : callable
        The new (A, B, C, D) from the parameter values.
    states : tuple of str
        The new states' names.
    channel : str
        The record's channel the new states start from (a lag's state is the lagged
        signal: its measured initial value, ``initial_state='measured'``); "" for none.

    Returns
    -------
    LinearModel
    """
    channels = {**model.state_channels, **(dict.fromkeys(states, channel) if channel else {})}
    return LinearModel(model.name, (*model.states, *states), model.inputs, model.outputs,
                       (*model.parameters, *start), {**model.start, **start}, build,
                       model.condition, model.description, channels)


def _dtype(*arrays: np.ndarray, extra: complex | float = 0.0) -> np.dtype:
    return np.result_type(*(a.dtype for a in arrays), type(extra))


def grown(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
          extra: complex | float) -> Matrices:
    """(A, B, C, D) with one zero state appended (dtype wide enough for ``extra``).

    Parameters
    ----------
    A, B, C, D : ndarray
        The state-space matrices.
    extra : complex or float
        A value the new state's entries will hold (sets the dtype).

    Returns
    -------
    tuple of ndarray
        (A, B, C, D) with one more state.
    """
    dtype = _dtype(A, B, C, D, extra=extra)
    n = A.shape[0]
    A2 = np.zeros((n + 1, n + 1), dtype=dtype)
    A2[:n, :n] = A
    B2 = np.zeros((n + 1, B.shape[1]), dtype=dtype)
    B2[:n] = B
    C2 = np.zeros((C.shape[0], n + 1), dtype=dtype)
    C2[:, :n] = C
    return A2, B2, C2, D.astype(dtype)


def lagged_output(mats: Matrices, row: int, tau: complex | float, pade: bool) -> Matrices:
    """Output ``row`` passed through a first-order lag 1/(tau s + 1) (``pade`` False) or a
    first-order Pade delay (1 - tau s/2)/(1 + tau s/2) (True; Franklin, Powell &
    Emami-Naeini 2015, ch. 5, time delay), a state w appended:

        lag:   w' = (y - w)/tau,        y_measured = w
        delay: w' = (y - w)/(tau/2),    y_measured = 2 w - y

    with y = C_row x + D_row u the output before (its direct input terms included).

    Parameters
    ----------
    mats : tuple of ndarray
        (A, B, C, D).
    row : int
        The output's row.
    tau : complex or float
        Time constant, s.
    pade : bool
        A Pade delay (True) or a lag.

    Returns
    -------
    tuple of ndarray
        (A, B, C, D) with the state w appended.
    """
    A, B, C, D = mats
    A2, B2, C2, D2 = grown(A, B, C, D, tau)
    n = A.shape[0]
    a = (2.0 if pade else 1.0) / tau
    A2[n, :n] = a * C[row]
    A2[n, n] = -a
    B2[n] = a * D[row]
    if pade:
        C2[row, :n] = -C[row]
        C2[row, n] = 2.0
        D2[row] = -D[row]
    else:
        C2[row] = 0.0
        C2[row, n] = 1.0
        D2[row] = 0.0
    return A2, B2, C2, D2


def lagged_input(mats: Matrices, column: int, tau: complex | float) -> Matrices:
    """Input ``column`` passed through a first-order lag 1/(tau s + 1) before the model
    (an actuator: x_s' = (u - x_s)/tau, the model reading x_s where it read u).

    Parameters
    ----------
    mats : tuple of ndarray
        (A, B, C, D).
    column : int
        The input's column.
    tau : complex or float
        Time constant, s.

    Returns
    -------
    tuple of ndarray
        (A, B, C, D) with the state x_s appended.
    """
    A, B, C, D = mats
    A2, B2, C2, D2 = grown(A, B, C, D, tau)
    n = A.shape[0]
    A2[:n, n] = B[:, column]
    A2[n, n] = -1.0 / tau
    B2[:n, column] = 0.0
    B2[n, column] = 1.0 / tau
    C2[:, n] = D[:, column]
    D2[:, column] = 0.0
    return A2, B2, C2, D2
