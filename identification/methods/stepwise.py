"""Stepwise regression: model structure determination for one force or moment coefficient.

As in Batterson & O'Mara, NASA TM-4099 (1989), the longitudinal derivatives of the Twin
Otter icing research aircraft, after Klein, Batterson & Murphy, NASA TP-1916
(1981), and Morelli & Klein (2016) section 5.4:

* candidates: linear terms, squares and products of the explanatory variables, each a
  perturbation from the reference value (equation_error.parse_term);
* forward entry: of the candidates not in the model, the one with the largest partial
  correlation with the coefficient (after removing the part explained by the regressors
  already in) is the one with the largest partial F; it enters when F > F_in;
* backward removal: every regressor in the model is re-examined after each entry, and
  the one with the smallest partial F leaves when F < F_out;
* stopping: the predicted square error (Morelli & Klein 2016, sec. 5.4)

      PSE = (1/N) (z - y)'(z - y) + sigma_max^2 p / N,   sigma_max^2 = (1/N) sum (z - mean z)^2

  penalises each added parameter by sigma_max^2 / N; entry also stops when the best
  candidate raises R^2 by less than ``min_r2_gain`` percentage points (default 0.5: a
  practical rule for flight data, R^2 being one of the adequacy criteria of Morelli &
  Klein 5.4; on real data the residuals are colored, partial F values are inflated, and
  F_in alone lets small nonlinear terms in; set 0 for the pure F_in / PSE rules).
  The model returned is the one of least PSE met on the way.

The result is an equation-error Estimate of the chosen structure; ``fit['steps']`` lists
each entry and removal with its partial F, R^2 and PSE, ``fit['candidates']`` the set
searched.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from itertools import combinations_with_replacement

import numpy as np

from flightid.identification.data.coefficients import channel_values
from flightid.identification.engine.metrics import determination
from flightid.identification.estimate import Estimate, merge
from flightid.identification.methods import equation_error as ee
from flightid.identification.methods.equation_error.estimation import identifiability
from flightid.identification.methods.equation_error.terms import (
    derivative_name,
    parse_term,
    reference_values,
    regressor_matrix,
)
from flightid.identification.methods.protocol import Method, RegressionOptions, option
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

ID = "swr"


def candidate_terms(variables: Sequence[str], order: int = 2) -> list[str]:
    """Linear terms of ``variables`` plus their squares and pairwise products (order 2).

    Parameters
    ----------
    variables : sequence of str
        Explanatory variables (record channels or derivative variables).
    order : int, optional
        1 (linear terms only) or 2 (default: also squares and products).

    Returns
    -------
    list of str
        Term texts for ``equation_error.parse_term``, e.g. 'alpha', 'alpha^2', 'alpha*de'.

    Raises
    ------
    ValueError
        ``order`` is not 1 or 2.
    """
    if order not in (1, 2):
        raise ValueError(f"order must be 1 (linear) or 2 (squares and products), got {order}")
    terms = list(variables)
    if order == 2:
        for a, b in combinations_with_replacement(variables, 2):
            terms.append(f"{a}^2" if a == b else f"{a}*{b}")
    return terms


def _sse(x: np.ndarray, y: np.ndarray) -> float:
    theta, *_ = np.linalg.lstsq(x, y, rcond=None)
    v = y - x @ theta
    return float(v @ v)


def _stats(x: np.ndarray, y: np.ndarray, sse: float) -> tuple[float, float]:
    n, p = x.shape
    sst = float(np.sum((y - y.mean()) ** 2))
    r2 = determination(sse, sst)
    pse = sse / n + (sst / n) * p / n
    return r2, pse


def select(
    y: np.ndarray,
    x: np.ndarray,
    names: Sequence[str],
    *,
    f_in: float = 4.0,
    f_out: float = 4.0,
    min_r2_gain: float = 0.5,
    max_steps: int | None = None,
) -> tuple[list[int], list[dict]]:
    """Stepwise selection of columns of x for y (a bias is always in).

    Parameters
    ----------
    y : numpy.ndarray
        Dependent variable (the coefficient), shape (N,).
    x : numpy.ndarray
        Candidate regressors, shape (N, m).
    names : sequence of str
        Name of each column, used in the steps.
    f_in : float, optional
        Partial F a candidate must exceed to enter. Default 4.
    f_out : float, optional
        Partial F below which a regressor leaves. Default 4.
    min_r2_gain : float, optional
        Smallest R^2 gain of an entry, percentage points. Default 0.5.
    max_steps : int or None, optional
        Limit of entry steps; None takes 4 m + 4.

    Returns
    -------
    chosen : list of int
        Column indices of the model of least PSE along the path.
    steps : list of dict
        Each with action ('enter', 'remove', 'stop' or 'select'), term, F, R2 (percent),
        PSE and why.
    """
    n, m = x.shape
    ones = np.ones((n, 1))
    chosen: list[int] = []
    steps: list[dict] = []
    sse_now = _sse(ones, y)
    r2_now, pse_now = _stats(ones, y, sse_now)
    path = [(pse_now, list(chosen))]
    seen = {frozenset()}
    max_steps = max_steps if max_steps is not None else 4 * m + 4
    for _ in range(max_steps):
        # forward: the candidate with the largest partial F
        best = None
        for j in range(m):
            if j in chosen:
                continue
            xs = np.column_stack([x[:, chosen + [j]], ones])
            sse_j = _sse(xs, y)
            dof = n - xs.shape[1]
            if dof <= 0:
                continue
            f = (sse_now - sse_j) / (sse_j / dof) if sse_j > 0 else np.inf
            if best is None or f > best[1]:
                best = (j, f, sse_j, xs)
        if best is None:
            break
        j, f, sse_j, xs = best
        r2_j, pse_j = _stats(xs, y, sse_j)
        gain = 100.0 * (r2_j - r2_now)
        if f <= f_in or gain < min_r2_gain or frozenset(chosen + [j]) in seen:
            steps.append({
                "action": "stop", "term": names[j], "F": f, "R2": 100.0 * r2_now,
                "PSE": pse_now,
                "why": (f"best remaining candidate {names[j]} has partial F {f:.2f} "
                        + (f"<= F_in {f_in}" if f <= f_in else
                           f"but raises R^2 by only {gain:.3f} % (< {min_r2_gain} %)"
                           if gain < min_r2_gain else "but would revisit a model already seen")),
            })
            break
        chosen.append(j)
        seen.add(frozenset(chosen))
        sse_now, r2_now, pse_now = sse_j, r2_j, pse_j
        steps.append({
            "action": "enter", "term": names[j], "F": f, "R2": 100.0 * r2_now, "PSE": pse_now,
            "why": f"largest partial F ({f:.2f} > F_in {f_in}); R^2 {100 * r2_now:.3f} %, "
                   f"PSE {pse_now:.4g}",
        })
        path.append((pse_now, list(chosen)))
        # backward: remove regressors that are no longer significant
        while len(chosen) > 1:
            xs = np.column_stack([x[:, chosen], ones])
            dof = n - xs.shape[1]
            s2 = sse_now / dof
            worst = None
            for k in chosen:
                rest = [c for c in chosen if c != k]
                sse_k = _sse(np.column_stack([x[:, rest], ones]), y)
                f_k = (sse_k - sse_now) / s2 if s2 > 0 else np.inf
                if worst is None or f_k < worst[1]:
                    worst = (k, f_k, sse_k)
            k, f_k, sse_k = worst
            if f_k >= f_out:
                break
            chosen.remove(k)
            seen.add(frozenset(chosen))
            xr = np.column_stack([x[:, chosen], ones])
            sse_now = sse_k
            r2_now, pse_now = _stats(xr, y, sse_now)
            steps.append({
                "action": "remove", "term": names[k], "F": f_k, "R2": 100.0 * r2_now,
                "PSE": pse_now,
                "why": f"partial F fell to {f_k:.2f} < F_out {f_out} after later entries",
            })
            path.append((pse_now, list(chosen)))
    best_pse, best_set = min(path, key=lambda item: item[0])
    if sorted(best_set) != sorted(chosen):
        steps.append({
            "action": "select", "term": ", ".join(names[i] for i in best_set), "F": float("nan"),
            "R2": float("nan"), "PSE": best_pse,
            "why": f"the model of least PSE ({best_pse:.4g}) on the path is kept; the "
                   f"regressors after it lowered the fit error by less than their PSE penalty",
        })
    return best_set, steps


def estimate(
    record: FlightRecord,
    coefficient: str,
    candidates: Iterable[str],
    *,
    f_in: float = 4.0,
    f_out: float = 4.0,
    min_r2_gain: float = 0.5,
    reference: str = "mean",
    colored: bool = True,
) -> Estimate:
    """Stepwise regression of ``coefficient`` over candidate terms; Estimate of the chosen model.

    Candidates the data cannot determine (constant or collinear) are left out before the
    search and reported in ``unidentifiable``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    coefficient : str
        Coefficient to model (e.g. 'Cl').
    candidates : iterable of str
        Candidate terms (``candidate_terms``).
    f_in : float, optional
        Partial F to enter. Default 4.
    f_out : float, optional
        Partial F to leave. Default 4.
    min_r2_gain : float, optional
        Smallest R^2 gain of an entry, percentage points. Default 0.5.
    reference : str, optional
        Perturbation reference: 'mean' (default), 'initial' or 'none'.
    colored : bool, optional
        Standard errors corrected for colored residuals (default) or plain OLS.

    Returns
    -------
    Estimate
        Equation-error estimate of the chosen structure; ``fit['steps']`` explains every
        entry and removal, ``fit['candidates']`` lists the terms searched, with
        ``fit['f_in']`` and ``fit['f_out']``.

    Raises
    ------
    ValueError
        Invalid thresholds, an unknown coefficient or a malformed term.
    """
    check_thresholds(f_in, f_out)
    terms = [parse_term(t) for t in candidates]
    y = channel_values(record, coefficient)
    refs = reference_values(record, terms, reference)
    x = regressor_matrix(record, terms, refs)
    names = [derivative_name(coefficient, t) for t in terms]
    unident = identifiability(x, names, terms, record)
    usable = [j for j, nm in enumerate(names) if nm not in unident]
    chosen, steps = select(
        y, x[:, usable], [terms[j].text for j in usable],
        f_in=f_in, f_out=f_out, min_r2_gain=min_r2_gain,
    )
    selected = [terms[usable[i]].text for i in sorted(chosen)]
    est = ee.estimate(record, coefficient, selected, reference=reference, colored=colored)
    est.method = ID
    est.unidentifiable = {**unident, **est.unidentifiable}
    est.fit["steps"] = steps
    est.fit["candidates"] = [t.text for t in terms]
    est.fit["f_in"] = f_in
    est.fit["f_out"] = f_out
    return est


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(RegressionOptions):
    """Options of ``--method swr``."""

    order: int = option(2, "candidates: 1 linear terms, 2 also squares and products")
    f_in: float = option(4.0, "partial F a candidate must exceed to enter")
    f_out: float = option(4.0, "partial F below which a regressor leaves")
    min_r2_gain: float = option(0.5, "smallest R^2 gain (percentage points) of an entry")
    reference: str = option("mean", "regressors as perturbations from the record's 'mean', "
                                    "its 'initial' value, or 'none'")
    colored: bool = option(True, "standard errors corrected for colored residuals")

    def __post_init__(self) -> None:
        check_thresholds(self.f_in, self.f_out, "option {} of method swr")


def check_thresholds(f_in: float, f_out: float, name: str = "{}") -> None:
    """Check that F_in and F_out are positive with F_out <= F_in.

    Otherwise a regressor can enter and leave in turn (Klein, Batterson & Murphy 1981).

    Parameters
    ----------
    f_in : float
        Partial F to enter.
    f_out : float
        Partial F to leave.
    name : str, optional
        Format of the option's name in the message ('{}' is replaced by f_in or f_out).

    Raises
    ------
    ValueError
        Naming the threshold that is not valid.
    """
    for key, value in (("f_in", f_in), ("f_out", f_out)):
        if not value > 0:
            raise ValueError(f"{name.format(key)} must be > 0 (a partial F), got {value:g}")
    if f_out > f_in:
        raise ValueError(f"{name.format('f_out')} {f_out:g} must not exceed f_in {f_in:g}: a "
                         "regressor could then enter and leave in turn")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """Stepwise regression for every coefficient of ``model``.

    The candidates are its variables' linear terms, squares and products (``order``).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : str, optional
        A regression preset or an explicit structure 'Cn=beta+rhat; ...'. Default
        'lateral'.
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        One estimate; the searches under ``fit['coefficients']``.
    """
    options = options or Options()
    structure = model_structure.regression(model, options.coefficients)
    return merge(ID, [
        estimate(record, c, candidate_terms(t, options.order), f_in=options.f_in,
                 f_out=options.f_out, min_r2_gain=options.min_r2_gain,
                 reference=options.reference, colored=options.colored)
        for c, t in structure.items()])


METHOD = Method(
    id=ID, name="stepwise regression",
    summary="model structure determination: forward entry and backward removal by partial "
            "F, stopped by the predicted square error",
    reference="Klein, Batterson & Murphy, Determination of Airplane Model Structure from "
              "Flight Data by Using Modified Stepwise Regression, NASA TP-1916, 1981; "
              "Morelli & Klein 2016 sec. 5.4",
    options=Options, models=(*model_structure.REGRESSION, "structure"),
    default_model="lateral", channels=model_structure.regression_channels, run=run,
    contract_model="lateral",
)
