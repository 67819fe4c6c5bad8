"""Output-error and filter-error fits of the linearised model on one window (the only
fitting the gap uses).

``fit`` estimates the given parameters with the nuisance ones (the biases, which take the
trim offsets, and the initial state) by output error (``methods.output_error``: Gauss-Newton,
Cramer-Rao bounds corrected for colored residuals; Morelli & Klein 2016 ch. 6; Jategaonkar
2015 ch. 4); every other parameter is held at its value in the model. With no parameter
given it is the model as is (only the nuisance fitted): the baseline of the diagnosis and
the evaluation of a held-out window. ``filter_fit`` is the same fit by filter error
(``methods.filter_error``: the model given process noise, the turbulence; Jategaonkar 2015
ch. 5), which the leading candidates are judged by (``turbulence.leading``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.estimate import Estimate
from flightid.identification.gap.model.linearise import nuisance
from flightid.identification.methods import filter_error, output_error
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

MAX_ITERATIONS = 15  # from the model's values a window converges in a few steps


@dataclass
class WindowFit:
    """One window's fit: the freed parameters and the residual of every output."""

    values: dict[str, float]  # the freed parameters (not the nuisance ones)
    std: dict[str, float]
    unidentifiable: dict[str, str]
    cost: float  # N/2 ln det R
    samples: int
    time: np.ndarray
    measured: dict[str, np.ndarray]
    residual: dict[str, np.ndarray]
    model: dict[str, np.ndarray]

    def fractions(self) -> dict[str, float]:
        """Residual energy of each output as a fraction of its measured variation's."""
        return {c: energy_fraction(self.residual[c], self.measured[c]) for c in self.residual}


def noise_energy(residual: np.ndarray) -> float:
    """The white-noise part of sum(residual^2): N sigma^2 with sigma^2 = mean(diff^2) / 2.

    Differencing removes what varies slowly (a model's misfit of the rigid-body response)
    and keeps white measurement noise, whose differences have twice its variance (the
    difference-based noise estimate of the residual; Morelli & Klein 2016 ch. 11 estimate
    noise from the high-frequency part of a residual the same way).

    Parameters
    ----------
    residual : ndarray
        One output's residual on one window.

    Returns
    -------
    float
        In the residual's units squared (nan under two samples).
    """
    if residual.size < 2:
        return float("nan")
    return residual.size * float(np.mean(np.diff(residual) ** 2)) / 2.0


def energy_fraction(residual: np.ndarray, measured: np.ndarray) -> float:
    """sum(residual^2) / sum((measured - mean)^2); nan for a constant signal.

    Parameters
    ----------
    residual, measured : ndarray
        One output's residual and measured signal.

    Returns
    -------
    float
    """
    spread = float(np.sum((measured - np.mean(measured)) ** 2))
    return float(np.sum(residual**2) / spread) if spread > 0 else float("nan")


def fit(model: LinearModel, record: FlightRecord, free: Sequence[str] = (),
        max_iterations: int = MAX_ITERATIONS) -> WindowFit:
    """Fit ``free`` (and the nuisance parameters) of ``model`` on ``record``, in at most
    ``max_iterations`` Gauss-Newton steps.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft (with a candidate's edits).
    record : FlightRecord
        One window.
    free : sequence of str
        The model's parameters fitted besides the nuisance ones (none: the model as is).
    max_iterations : int
        Gauss-Newton steps at most.

    Returns
    -------
    WindowFit
        The freed parameters with their bounds (colored-residual corrected), the cost
        N/2 ln det R, and each output's measured, model and residual time history.
    """
    est = output_error.estimate(
        record, model, free=[*free, *nuisance(model)], initial_state="estimate", hold="foh",
        colored=True, check_identifiability=True, max_iterations=max_iterations)
    values = {n: float(est.values[est.names.index(n)]) if n in est.names else model.start[n]
              for n in free}
    std = {n: float(est.std[est.names.index(n)]) if n in est.names else float("nan")
           for n in free}
    unident = {n: r for n, r in est.unidentifiable.items() if n in free}
    return WindowFit(
        values=values, std=std, unidentifiable=unident, cost=float(est.fit["cost"]),
        samples=int(est.fit["samples"]), time=np.asarray(est.time),
        measured={c: o["measured"] for c, o in est.outputs.items()},
        residual={c: o["residual"] for c, o in est.outputs.items()},
        model={c: o["model"] for c, o in est.outputs.items()})


def held(model: LinearModel, values: dict[str, float], record: FlightRecord) -> WindowFit:
    """``model`` with ``values`` held, on ``record`` (only the nuisance fitted).

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft (with a candidate's edits).
    values : dict of str to float
        Parameters held at these values (fitted on other windows).
    record : FlightRecord
        The held-out window.

    Returns
    -------
    WindowFit
        As ``fit`` with no parameter freed.
    """
    return fit(model.with_start(**values) if values else model, record, ())


@dataclass
class FilterFit:
    """One window's filter-error fit: the freed parameters and the negative log-likelihood
    of the innovations (Jategaonkar 2015 eq. 5.23)."""

    values: dict[str, float]  # the freed parameters (not the nuisance or noise ones)
    std: dict[str, float]
    unidentifiable: dict[str, str]
    cost: float
    samples: int
    # the whole estimate (the noise, the biases): a warm start for a model containing this
    estimate: Estimate | None = field(default=None, compare=False, repr=False)


def filter_fit(model: LinearModel, record: FlightRecord, free: Sequence[str] = (),
               airframe: Sequence[str] | None = None, warm: FilterFit | None = None
               ) -> FilterFit:
    """Fit ``free`` (with the biases, the process noise and the measurement noise) of
    ``model`` on ``record`` by filter error.

    The relaxation between the Gauss-Newton passes and the closed-form measurement-noise
    update (Jategaonkar 2015 sec. 5.8; ``joint_noise=False``), about a third of the joint
    noise fit's time; no identifiability refit and no condition correction (a window is
    short and near its trim).

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft (with a candidate's edits).
    record : FlightRecord
        One window.
    free : sequence of str
        The model's parameters fitted besides the nuisance ones (none: the model as is).
    airframe : sequence of str or None
        The states of the aircraft's motion, whose equations the gusts drive (those but the
        Euler angles carry process noise); None: ``model``'s. A candidate's own states (a
        lag's or a delay's) carry none.
    warm : FilterFit or None
        A fit of the same record by a model that ``model`` contains (``model`` with
        ``free`` at their start values): started from its end point
        (``filter_error.estimate(warm_start=...)``) instead of from output error.

    Returns
    -------
    FilterFit
        The freed parameters with their bounds (the sandwich for colored innovations,
        ``filter_error.estimate(colored=True)``) and the cost J (1).
    """
    states = model.states if airframe is None else airframe
    est = filter_error.estimate(
        record, model, free=[*free, *nuisance(model)], initial_state="measured", hold="foh",
        process_noise=[s for s in states if s not in filter_error.KINEMATIC_STATES],
        joint_noise=False, check_identifiability=False, condition_correction=False,
        colored=True, warm_start=None if warm is None else warm.estimate)
    values = {n: float(est.values[est.names.index(n)]) for n in free}
    std = {n: float(est.std[est.names.index(n)]) for n in free}
    return FilterFit(values=values, std=std, unidentifiable={}, cost=float(est.fit["cost"]),
                     samples=int(est.fit["samples"]), estimate=est)
