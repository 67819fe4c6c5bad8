"""Multivariate orthogonal functions: global nonlinear model structure for one coefficient.

After Morelli (1995), "Global nonlinear parametric modeling with application to F-16
aerodynamics", and Morelli & Klein (2016) section 5.5 (SIDPAC's ``mof``):

* candidates: every monomial of the explanatory variables (alpha, beta, the
  nondimensional rates, the surfaces) up to ``order`` (default 3: linear terms, squares,
  products, cubes and their cross products), each a perturbation from the reference;
* orthogonal functions: the candidates, simplest first, are made mutually orthogonal
  over the data by Gram-Schmidt in that order, so each function p_j holds only what the
  simpler ones do not; the functions are ranked by the squared error they remove,
  (p_j' z)^2 / (p_j' p_j), which with orthogonal functions is independent of the others;
* consistent smoothing: a moment coefficient computed from smoothed derivatives of the
  rates has its regressors passed through the same filter, in the search, the fit and
  the prediction (Morelli & Klein 2016 sec. 11.2);
* splines in alpha (option ``spline``): the candidates (alpha - alpha_k)^n_+, n = 1 to
  ``order``, with knots fixed a priori on a grid (Morelli 1995; Morelli & Klein 2016
  ch. 5 and 12), after the monomials: a polynomial cannot follow a slope break;
* stop: the predicted square error (Morelli 1995 eq. 24; M&K eq. 5.96)

      PSE = (1/N) (z - y)'(z - y) + sigma_max^2 p / N,   sigma_max^2 = (1/N) sum (z - mean z)^2

  is followed along the path and the model of least PSE kept.

The chosen functions are then expanded back into ordinary polynomial terms: the chosen
candidates are fitted by equation error (``equation_error.estimate``), so the result is
an Estimate of named terms (``C*_alpha``, ``C*_alpha^2``, ``C*_alpha*de``, ...) with their
standard errors; ``fit['steps']`` lists each entry with its R^2 and PSE.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from itertools import combinations_with_replacement
from math import ceil, floor

import numpy as np

from flightid.identification.data.coefficients import (
    HINGE,
    channel_values,
    differentiated,
    hinge_name,
)
from flightid.identification.estimate import Estimate, merge
from flightid.identification.methods import equation_error as ee
from flightid.identification.methods.equation_error.least_squares import least_squares
from flightid.identification.methods.equation_error.terms import (
    Term,
    bias_name,
    derivative_name,
    parse_term,
    reference_values,
    regressor_matrix,
    smooth_columns,
)
from flightid.identification.methods.mof_selection import select
from flightid.identification.methods.protocol import Method, RegressionOptions, option
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

ID = "mof"


def candidate_terms(variables: Sequence[str], order: int = 3) -> list[str]:
    """Every monomial of ``variables`` of degree 1..order, e.g. 'alpha', 'alpha^2*de'.

    Parameters
    ----------
    variables : sequence of str
        Explanatory variables (record channels or derivative variables).
    order : int, optional
        Highest degree, 1 to 4. Default 3.

    Returns
    -------
    list of str
        Term texts for ``equation_error.parse_term``, every degree-1 term before any of
        degree 2, and so on.

    Raises
    ------
    ValueError
        ``order`` is not 1 to 4.
    """
    if not 1 <= order <= 4:
        raise ValueError(f"order must be 1 to 4, got {order}")
    terms = []
    for degree in range(1, order + 1):
        for combo in combinations_with_replacement(variables, degree):
            parts = [f"{v}^{combo.count(v)}" if combo.count(v) > 1 else v
                     for v in dict.fromkeys(combo)]
            terms.append("*".join(parts))
    return terms


def spline_terms(records: Sequence[FlightRecord], spacing_deg: float, order: int = 3,
                 channel: str = "alpha") -> list[str]:
    """Spline candidates (channel - k)^n_+ with knots k at every multiple of
    ``spacing_deg`` strictly inside the records' range of ``channel``, n = 1 to ``order``.

    Morelli (1995) sec. 3; Morelli & Klein (2016) ch. 5 and 12: polynomial splines in
    alpha with knots fixed a priori join the candidate pool, so the selection can follow
    a slope break that no polynomial in alpha can. The knots depend on the training
    records' range only, never on a model's tables nor on the records predicted.

    Parameters
    ----------
    records : sequence of FlightRecord
        The training records, pooled (``channel`` in rad).
    spacing_deg : float
        The knots' spacing, deg; 0 gives no spline candidate.
    order : int
        The highest power n of each spline (1 to 4).
    channel : str
        The angle the splines are in.

    Returns
    -------
    list of str
        Terms such as '(alpha-8deg)+' and '(alpha-8deg)+^2', every power 1 before any
        power 2, each power's knots in increasing order.
    """
    if spacing_deg < 0:
        raise ValueError(f"the spline spacing must be positive (deg) or 0, got {spacing_deg}")
    if spacing_deg == 0 or not records:
        return []
    values = np.degrees(np.concatenate([channel_values(r, channel) for r in records]))
    lo, hi = float(np.min(values)), float(np.max(values))
    knots = [k * spacing_deg for k in range(ceil(lo / spacing_deg), floor(hi / spacing_deg) + 1)
             if lo < k * spacing_deg < hi]
    return [hinge_name(channel, k) + (f"^{n}" if n > 1 else "")
            for n in range(1, order + 1) for k in knots]


def estimate(records: FlightRecord | Sequence[FlightRecord], coefficient: str,
             candidates: Iterable[str], *, reference: str = "mean", colored: bool = True,
             max_terms: int | None = None, consistent_smoothing: bool = True,
             backward: bool = False) -> Estimate:
    """Multivariate orthogonal functions for ``coefficient`` over candidate terms.

    From one record or from several (maneuvers and conditions pooled, as a global model is
    identified: Morelli 1995). A candidate left with less than ``DEPENDENT`` of its squared
    norm after the simpler ones never enters.

    Parameters
    ----------
    records : FlightRecord or sequence of FlightRecord
        The flight or flights, SI channels.
    coefficient : str
        Coefficient to model (e.g. 'Cm').
    candidates : iterable of str
        Candidate terms, simple first (``candidate_terms``, ``spline_terms``).
    reference : str, optional
        Regressors as perturbations from the pooled 'mean' (default), the first record's
        'initial' value, or 'none'.
    colored : bool, optional
        Standard errors corrected for colored residuals (default) or plain OLS.
    max_terms : int or None, optional
        At most this many terms enter; None: no limit.
    consistent_smoothing : bool, optional
        Regressors of a coefficient from smoothed rate derivatives go through the same
        filter (``equation_error.estimate``), each record on its own. Default True.
    backward : bool, optional
        Remove the chosen terms whose removal lowers the PSE (``select``). Default False.

    Returns
    -------
    Estimate
        Least-squares estimate of the chosen terms and a bias; ``fit['steps']`` the
        selection path, ``fit['candidates']`` the terms searched, ``fit['records']`` the
        number of records.

    Raises
    ------
    ValueError
        No record, an unknown coefficient or a malformed term.
    """
    recs = [records] if isinstance(records, FlightRecord) else list(records)
    if not recs:
        raise ValueError("mof needs at least one record")
    terms = [parse_term(t) for t in candidates]
    y, x, refs = _stacked(recs, coefficient, terms, reference, consistent_smoothing)
    chosen, steps = select(y, x, [t.text for t in terms], max_terms, backward)
    selected = [terms[i].text for i in sorted(chosen)]
    if len(recs) == 1:
        est = ee.estimate(recs[0], coefficient, selected, reference=reference,
                          colored=colored, consistent_smoothing=consistent_smoothing)
        est.method = ID
    else:
        est = _pooled_fit(coefficient, [terms[i] for i in sorted(chosen)],
                          y, x[:, sorted(chosen)], refs, colored,
                          consistent_smoothing and differentiated(recs[0], coefficient))
    est.fit["steps"] = steps
    est.fit["candidates"] = [t.text for t in terms]
    est.fit["records"] = len(recs)
    return est


def _stacked(records: Sequence[FlightRecord], coefficient: str, terms: Sequence[Term],
             reference: str, consistent_smoothing: bool
             ) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """The coefficient (N) and the candidates' regressors (N x terms) of the records one
    after another, as perturbations from the pooled reference values."""
    if reference == "mean":
        # a spline factor's origin is its knot
        pooled = {ch: 0.0 if HINGE.match(ch) else
                  float(np.mean(np.concatenate([channel_values(r, ch) for r in records])))
                  for ch in dict.fromkeys(c for t in terms for c, _ in t.factors)}
        refs = pooled
    else:
        refs = reference_values(records[0], terms, reference)
    ys, xs = [], []
    for record in records:
        x = regressor_matrix(record, terms, refs)
        if consistent_smoothing and differentiated(record, coefficient):
            x = smooth_columns(x, terms, record.dt)
        ys.append(channel_values(record, coefficient))
        xs.append(x)
    return np.concatenate(ys), np.vstack(xs), refs


def _pooled_fit(coefficient: str, terms: Sequence[Term], y: np.ndarray, x: np.ndarray,
                refs: dict[str, float], colored: bool, smoothed_x: bool) -> Estimate:
    """Least squares of the chosen terms and a bias over pooled records (the fit
    ``equation_error.predict`` reads)."""
    result = least_squares(np.column_stack([x, np.ones(len(y))]), y, colored=colored)
    names = [*(derivative_name(coefficient, t) for t in terms), bias_name(coefficient)]
    fit = {"coefficient": coefficient, "regressors": [t.text for t in terms],
           "reference": "pooled", "reference_values": refs, "bias": True,
           "consistent_smoothing": smoothed_x, "fixed": {}, **result.statistics}
    return Estimate(method=ID, names=names, values=result.theta, std=result.std,
                    covariance=result.covariance, fit=fit,
                    outputs={coefficient: {"measured": y, "model": result.model,
                                           "residual": y - result.model}})


def fit_records(records: Sequence[FlightRecord], model: str = "global",
                options: Options | None = None) -> Estimate:
    """A global model of every coefficient of ``model`` from several records.

    Maneuvers and conditions are pooled; spline candidates in alpha (``options.spline``)
    join the candidates of the coefficients that depend on alpha.

    Parameters
    ----------
    records : sequence of FlightRecord
        The flights, SI channels.
    model : str, optional
        A regression preset or an explicit structure. Default 'global'.
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        One estimate, as ``run`` gives for one record; the coefficients' fits under
        ``fit['coefficients']``.
    """
    options = options or Options()
    structure = model_structure.regression(model, options.coefficients)
    in_alpha = any("alpha" in t for t in structure.values())
    splines = spline_terms(records, options.spline, options.order) if in_alpha else []
    return merge(ID, [
        estimate(records, c, candidate_terms(t, options.order)
                 + (splines if "alpha" in t else []), reference=options.reference,
                 colored=options.colored, max_terms=options.max_terms,
                 consistent_smoothing=options.consistent_smoothing,
                 backward=options.backward)
        for c, t in structure.items()])


def predict(est: Estimate, record: FlightRecord, coefficient: str) -> np.ndarray:
    """The time history of ``coefficient`` (dimensionless) that a global model
    (``fit_records`` or ``run``) predicts on another record, from that record's
    variables with the fit's reference values and smoothing (``equation_error.predict``).

    Parameters
    ----------
    est : Estimate
        A ``mof`` estimate with ``fit['coefficients'][coefficient]``.
    record : FlightRecord
        The record predicted (reduced as the training records were).
    coefficient : str
        One of the model's coefficients (CL, CD, Cm, CY, Cl, Cn).

    Returns
    -------
    numpy.ndarray
        The predicted coefficient at every sample of ``record``.
    """
    fits = est.fit.get("coefficients", {})
    if coefficient not in fits:
        raise ValueError(f"the model has no {coefficient} (it has {', '.join(fits)})")
    names = [n for n in est.names if n.startswith(coefficient + "_")]
    part = Estimate(est.method, names, [est[n] for n in names],
                    [est.std_of(n) for n in names], fit=dict(fits[coefficient]))
    return ee.predict(part, record)


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(RegressionOptions):
    """Options of ``--method mof``."""

    order: int = option(3, "highest degree of the candidate monomials (1 to 4)")
    max_terms: int | None = option(None, "at most this many functions enter (default: all)")
    reference: str = option("mean", "regressors as perturbations from the record's 'mean', "
                                    "its 'initial' value, or 'none'")
    colored: bool = option(True, "standard errors corrected for colored residuals")
    consistent_smoothing: bool = option(
        True, "pass the regressors of a moment coefficient computed from smoothed rate "
              "derivatives through the same filter (search, fit and prediction)")
    backward: bool = option(False, "then remove the chosen terms whose removal lowers the "
                                   "predicted square error (backward elimination)")
    spline: float = option(0.0, "spline candidates in alpha, (alpha - k)^n_+ for n = 1 to "
                                "order, with knots k every this many deg inside the "
                                "training alpha range (0: none)")

    def __post_init__(self) -> None:
        if not 1 <= self.order <= 4:
            raise ValueError(f"option order of method mof must be 1 to 4, got {self.order}")
        if self.spline < 0:
            raise ValueError(f"option spline of method mof must be 0 (none) or a positive "
                             f"knot spacing in deg, got {self.spline}")


def run(record: FlightRecord, model: str = "global", options: Options | None = None
        ) -> Estimate:
    """Multivariate orthogonal functions for every coefficient of ``model``.

    The candidates are its variables' monomials up to ``options.order``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : str, optional
        A regression preset or an explicit structure. Default 'global'.
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        One estimate; the coefficients' fits under ``fit['coefficients']``.
    """
    return fit_records([record], model, options)


METHOD = Method(
    id=ID, name="multivariate orthogonal functions",
    summary="global nonlinear model structure: polynomial candidates made orthogonal, "
            "entered by error reduction, stopped by the predicted square error",
    reference="Morelli, Global Nonlinear Parametric Modeling with Application to F-16 "
              "Aerodynamics, ACC 1995; Morelli & Klein 2016 sec. 5.5",
    options=Options, models=(*model_structure.REGRESSION, "structure"),
    default_model="global", channels=model_structure.regression_channels, run=run,
    contract_model="lateral",
)
