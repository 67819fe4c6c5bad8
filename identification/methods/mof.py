"""Multivariate orthogonal functions: global nonlinear model structure for one coefficient.

After Morelli (1995), "Global nonlinear parametric modeling with application to F-16
aerodynamics", and Morelli & Klein (2016) section 5.5 (SIDPAC's ``mof``):

* candidates: every monomial of the explanatory variables (alpha, beta, the
  nondimensional rates, the surfaces) up to ``order`` (default 3: linear terms, squares,
  products, cubes and their cross products), each a perturbation from the reference;
* orthogonal functions: the candidates are made mutually orthogonal over the data by
  Gram-Schmidt, and at each step the candidate whose orthogonalised function p_j lowers
  the squared error most, (p_j' z)^2 / (p_j' p_j), enters (orthogonal least squares,
  Chen, Billings & Luo 1989): with orthogonal functions each entry's contribution is
  independent of the others, so ranking is exact and cheap;
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

import numpy as np

from flightid.identification.estimate import Estimate, merge
from flightid.identification.methods import equation_error as ee
from flightid.identification.methods.protocol import Method, RegressionOptions, option
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

ID = "mof"
# an orthogonalised candidate with less than this share of its squared norm left is
# (nearly) a linear combination of the functions in: R_j^2 > 0.99^2, the threshold of the
# equation-error estimate's identifiability check (VIF above 1/(1 - 0.99^2))
DEPENDENT = 1.0 - ee.COLLINEAR_R**2


def candidate_terms(variables: Sequence[str], order: int = 3) -> list[str]:
    """Every monomial of ``variables`` of degree 1..order, e.g. 'alpha', 'alpha^2*de'."""
    if not 1 <= order <= 4:
        raise ValueError(f"order must be 1 to 4, got {order}")
    terms = []
    for degree in range(1, order + 1):
        for combo in combinations_with_replacement(variables, degree):
            parts = [f"{v}^{combo.count(v)}" if combo.count(v) > 1 else v
                     for v in dict.fromkeys(combo)]
            terms.append("*".join(parts))
    return terms


def select(y: np.ndarray, x: np.ndarray, names: Sequence[str], max_terms: int | None = None
           ) -> tuple[list[int], list[dict]]:
    """Orthogonal forward selection of columns of x for y (a bias always in), stopped at
    the least PSE along the path. Returns the chosen columns and the steps (term, R^2 in
    percent, PSE, why)."""
    n, m = x.shape
    z = y - y.mean()
    sst = float(z @ z)
    sigma2 = sst / n
    q = x - x.mean(axis=0)  # orthogonal to the bias
    norms0 = np.einsum("ij,ij->j", q, q)
    basis: list[np.ndarray] = []
    chosen: list[int] = []
    steps: list[dict] = []
    sse = sst
    path = [(sse / n, [])]
    limit = min(m, max_terms or m, n - 2)
    while len(chosen) < limit:
        norms = np.einsum("ij,ij->j", q, q)
        ok = (norms > DEPENDENT * np.maximum(norms0, 1e-300))
        ok[chosen] = False
        if not ok.any():
            break
        gain = np.where(ok, (q.T @ z) ** 2 / np.where(ok, norms, 1.0), -np.inf)
        j = next((int(k) for k in np.argsort(-gain) if np.isfinite(gain[k])
                  and _separable(x, [*chosen, int(k)])), None)
        if j is None:
            break
        p = q[:, j].copy()
        chosen.append(j)
        basis.append(p)
        sse -= float(gain[j])
        pse = sse / n + sigma2 * len(chosen) / n
        path.append((pse, list(chosen)))
        steps.append({"action": "enter", "term": names[j], "R2": 100.0 * (1 - sse / sst),
                      "PSE": pse, "why": f"largest error reduction of the orthogonalised "
                                         f"candidates; R^2 {100 * (1 - sse / sst):.3f} %, "
                                         f"PSE {pse:.4g}"})
        # orthogonalise the remaining candidates against the new function (Gram-Schmidt)
        q = q - np.outer(p, (p @ q) / (p @ p))
    best_pse, best = min(path, key=lambda item: item[0])
    steps.append({"action": "select", "term": ", ".join(names[i] for i in best), "R2": float(
        "nan"), "PSE": best_pse, "why": f"the model of least PSE ({best_pse:.4g}): "
                                         f"{len(best)} of {len(chosen)} functions entered"})
    return best, steps


def _separable(x: np.ndarray, columns: list[int]) -> bool:
    """Whether every column of ``columns`` keeps its variance inflation factor at most
    ``equation_error.VIF_LIMIT`` among the others (the estimate can then separate them)."""
    if len(columns) < 2:
        return True
    c = np.corrcoef(x[:, columns], rowvar=False)
    try:
        vif = np.diag(np.linalg.inv(c))
    except np.linalg.LinAlgError:
        return False
    return bool(np.all(np.isfinite(vif)) and np.max(vif) <= ee.VIF_LIMIT)


def estimate(record: FlightRecord, coefficient: str, candidates: Iterable[str], *,
             reference: str = "mean", colored: bool = True, max_terms: int | None = None
             ) -> Estimate:
    """Multivariate orthogonal functions for ``coefficient`` over candidate terms: the
    Estimate of the chosen terms (equation error), ``fit['steps']`` the selection path,
    ``fit['candidates']`` the terms searched (a candidate left with less than
    ``DEPENDENT`` of its squared norm after orthogonalisation never enters)."""
    terms = [ee.parse_term(t) for t in candidates]
    y = ee.channel_values(record, coefficient)
    refs = ee.reference_values(record, terms, reference)
    x = ee.regressor_matrix(record, terms, refs)
    # no collinearity screen before the search: a doublet's surface and its cube are
    # collinear (r = 0.99), and the orthogonalisation keeps the one that explains more
    # (the other is then left with less than DEPENDENT of its norm and never enters)
    chosen, steps = select(y, x, [t.text for t in terms], max_terms)
    selected = [terms[i].text for i in sorted(chosen)]
    est = ee.estimate(record, coefficient, selected, reference=reference, colored=colored)
    est.method = ID
    est.fit["steps"] = steps
    est.fit["candidates"] = [t.text for t in terms]
    return est


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(RegressionOptions):
    """Options of ``--method mof``."""

    order: int = option(3, "highest degree of the candidate monomials (1 to 4)")
    max_terms: int | None = option(None, "at most this many functions enter (default: all)")
    reference: str = option("mean", "regressors as perturbations from the record's 'mean', "
                                    "its 'initial' value, or 'none'")
    colored: bool = option(True, "standard errors corrected for colored residuals")

    def __post_init__(self) -> None:
        if not 1 <= self.order <= 4:
            raise ValueError(f"option order of method mof must be 1 to 4, got {self.order}")


def run(record: FlightRecord, model: str = "longitudinal", options: Options | None = None
        ) -> Estimate:
    """Multivariate orthogonal functions for every coefficient of ``model`` over its
    variables' monomials up to ``options.order``; one Estimate."""
    options = options or Options()
    structure = model_structure.regression(model, options.coefficients)
    return merge(ID, [
        estimate(record, c, candidate_terms(t, options.order), reference=options.reference,
                 colored=options.colored, max_terms=options.max_terms)
        for c, t in structure.items()])


METHOD = Method(
    id=ID, name="multivariate orthogonal functions",
    summary="global nonlinear model structure: polynomial candidates made orthogonal, "
            "entered by error reduction, stopped by the predicted square error",
    reference="Morelli, Global Nonlinear Parametric Modeling with Application to F-16 "
              "Aerodynamics, ACC 1995; Morelli & Klein 2016 sec. 5.5",
    options=Options, models=(*model_structure.REGRESSION, "structure"),
    default_model="longitudinal", channels=model_structure.regression_channels, run=run,
    contract_model="lateral",
)
