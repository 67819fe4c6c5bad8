"""Orthogonal-function selection of multivariate orthogonal functions (``--method mof``).

Gram-Schmidt orthogonalisation of the candidates in simple-first order, ranking by error
reduction, the stop at the least predicted square error and the regeneration of the
functions with the chosen candidates first (Morelli 1995 sec. 3; Morelli & Klein 2016
sec. 5.5), with an optional backward elimination by the PSE.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flightid.identification.engine.metrics import determination
from flightid.identification.methods.equation_error.estimation import COLLINEAR_R, VIF_LIMIT

# an orthogonalised candidate with less than this share of its squared norm left is
# (nearly) a linear combination of the functions in: R_j^2 > 0.99^2, the threshold of the
# equation-error estimate's identifiability check (VIF above 1/(1 - 0.99^2))
DEPENDENT = 1.0 - COLLINEAR_R**2
# the functions are generated again with the chosen candidates first at most this often
REGENERATIONS = 10


def select(y: np.ndarray, x: np.ndarray, names: Sequence[str], max_terms: int | None = None,
           backward: bool = False) -> tuple[list[int], list[dict]]:
    """Multivariate orthogonal functions of the columns of x for y (a bias always in).

    Morelli (1995) sec. 3; Morelli & Klein (2016) sec. 5.5: the candidates, ordered
    from simple to complex (``candidate_terms`` gives every linear term before any
    square, every square before any cube), are made orthogonal by Gram-Schmidt in that
    order, so each function holds only what the candidates before it do not. A
    candidate left with less than ``DEPENDENT`` of its norm never enters: a cube of a
    doublet input, whose levels are only +-A and 0, after its linear term. The functions
    are ranked by their error reduction (p_j' z)^2 / (p_j' p_j), entered in that order (a
    candidate the estimate could not separate from those in is skipped), and the model
    of least PSE is kept.

    A chosen function expands into its own candidate and every candidate before it
    (p_j = xi_j - sum_k gamma_kj p_k): a function of the elevator chosen alone carries
    the parts of alpha and the pitch rate it was made orthogonal to. So the functions are
    generated again with the chosen candidates first (in their order of entry) and the
    others after them in the simple-first order, and the search repeated until the chosen
    candidates are the first ones of the order (the chosen functions then span exactly
    the chosen candidates, and the model expands back into them without loss), until a
    chosen set repeats, or ``REGENERATIONS`` times. Of the searches, the chosen set whose
    own least-squares fit has the least PSE is kept. Without this regeneration the
    selection path on the Twin Otter card claims R^2 0.999 for Cm while its chosen terms
    fit 0.63.

    Parameters
    ----------
    y : numpy.ndarray
        Dependent variable (the coefficient), shape (N,).
    x : numpy.ndarray
        Candidate regressors in simple-first order, shape (N, m).
    names : sequence of str
        Name of each column, used in the steps.
    max_terms : int or None, optional
        At most this many terms enter; None: no limit beyond m and N - 2.
    backward : bool, optional
        If True, then remove, one at a time, the chosen term whose removal lowers the PSE
        of the least-squares fit most, while one does (the backward step of stepwise
        regression, Morelli & Klein 2016 ch. 5, with the PSE as the criterion): a term that
        entered to carry part of another's and is left near zero once the other is in.
        Default False.

    Returns
    -------
    chosen : list of int
        Column indices chosen, in their order of entry.
    steps : list of dict
        Each entry (in order of entry, with the R^2 in percent and PSE of the least-squares
        fit of the terms in so far), each removal, and the final 'select' step.
    """
    n, m = x.shape
    z = y - y.mean()
    sst = float(z @ z)
    q = x - x.mean(axis=0)  # orthogonal to the bias
    limit = min(m, max_terms or m, n - 2)
    order = list(range(m))
    kept: tuple[float, list[int]] | None = None
    seen: set[frozenset[int]] = set()
    for _ in range(REGENERATIONS):
        chosen = _search(z, q, x, order, limit)
        # the PSE of the least-squares fit of the chosen terms themselves
        pse = _pse(_sse(z, q[:, chosen]), sst, n, len(chosen))
        if kept is None or pse < kept[0]:
            kept = (pse, chosen)
        if set(chosen) == set(order[:len(chosen)]) or frozenset(chosen) in seen:
            break  # the chosen functions span the chosen candidates; or a cycle
        seen.add(frozenset(chosen))
        order = [*chosen, *(j for j in range(m) if j not in chosen)]
    assert kept is not None
    best = kept[1]
    steps = []
    for k in range(1, len(best) + 1):
        sse = _sse(z, q[:, best[:k]])
        r2 = 100.0 * determination(sse, sst) if sst > 0 else 100.0
        pse = _pse(sse, sst, n, k)
        steps.append({"action": "enter", "term": names[best[k - 1]], "R2": r2, "PSE": pse,
                      "why": f"largest error reduction of the orthogonal functions left; "
                             f"R^2 {r2:.3f} %, PSE {pse:.4g}"})
    pse = kept[0]
    if backward:
        best, pse, removals = _eliminate(z, q, best, pse)
        steps += [{**r, "term": names[r["term"]]} for r in removals]
    steps.append({"action": "select", "term": ", ".join(names[i] for i in best),
                  "R2": float("nan"), "PSE": pse,
                  "why": f"the model of least PSE ({pse:.4g}): {len(best)} terms"})
    return best, steps


def _eliminate(z: np.ndarray, q: np.ndarray, chosen: Sequence[int], pse: float
               ) -> tuple[list[int], float, list[dict]]:
    """Backward elimination by the PSE: (the columns left, their PSE, the removals with
    the R^2 in percent and PSE after each; ``term`` the column)."""
    n, sst = len(z), float(z @ z)
    left, removals = list(chosen), []
    while left:
        sses = {j: _sse(z, q[:, [i for i in left if i != j]]) for j in left}
        trial, j = min((_pse(sse, sst, n, len(left) - 1), j) for j, sse in sses.items())
        if trial >= pse:
            break
        left.remove(j)
        pse = trial
        r2 = 100.0 * determination(sses[j], sst) if sst > 0 else 100.0
        removals.append({"action": "remove", "term": j, "R2": r2, "PSE": pse,
                         "why": f"its removal lowers the PSE most, to {pse:.4g}"})
    return left, pse, removals


def _pse(sse: float, sst: float, n: int, k: int) -> float:
    """The predicted square error of a k-term model (Morelli & Klein 2016 ch. 5):
    sse / N + sigma_max^2 k / N with sigma_max^2 = sst / N."""
    return sse / n + (sst / n) * k / n


def _sse(z: np.ndarray, x: np.ndarray) -> float:
    """Residual sum of squares of the least-squares fit of z (mean removed) on x."""
    if x.shape[1] == 0:
        return float(z @ z)
    theta, *_ = np.linalg.lstsq(x, z, rcond=None)
    r = z - x @ theta
    return float(r @ r)


def _search(z: np.ndarray, q: np.ndarray, x: np.ndarray, order: Sequence[int], limit: int
            ) -> list[int]:
    """One orthogonal-function search over the columns of q generated in ``order``: the
    chosen columns, in their order of entry, up to the least PSE along the path."""
    n = len(z)
    sst = float(z @ z)
    functions: list[np.ndarray] = []
    columns: list[int] = []
    for j in order:
        p = q[:, j].copy()
        norm0 = float(p @ p)
        for f in functions:
            p -= f * ((f @ p) / (f @ f))
        if float(p @ p) > DEPENDENT * max(norm0, 1e-300):
            functions.append(p)
            columns.append(j)
    gains = np.array([(f @ z) ** 2 / (f @ f) for f in functions])
    chosen: list[int] = []
    sse = sst
    path = [(_pse(sse, sst, n, 0), 0)]
    for k in np.argsort(-gains, kind="stable"):
        if len(chosen) >= limit:
            break
        j = columns[int(k)]
        if not _separable(x, [*chosen, j]):
            continue
        chosen.append(j)
        sse -= float(gains[k])
        path.append((_pse(sse, sst, n, len(chosen)), len(chosen)))
    _, size = min(path, key=lambda item: item[0])
    return chosen[:size]


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
    return bool(np.all(np.isfinite(vif)) and np.max(vif) <= VIF_LIMIT)
