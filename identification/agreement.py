"""Whether several methods' estimates of one record agree within their bounds, and when
they do not, the reasons the fits themselves give.

Two estimates of a derivative agree when they differ by at most ``AGREE_SIGMAS`` standard
errors of the difference, sqrt(s_a^2 + s_b^2) (the estimates taken as independent: the
methods weigh the same data differently, so this is a screen, not an exact test). The
coefficients at the reference (C_0) and the nuisance parameters are not compared: each
method defines them differently.

A disagreement is listed with every reason found in the fits:

- a method that did not converge (its values are not at the optimum);
- nuisance biases beyond an instrument (``nuisance``): the model or its reference does not
  fit the data;
- different models: a derivative one method estimates and the other holds (at zero or a
  priori) moves the derivatives correlated with it;
- bounds that assume white residuals next to ones corrected for colored residuals (the
  white ones are too small when the residuals are colored: Morelli & Klein 2016 eqs. 5.71
  and 6.54 correct them);
- equation error takes the measured states as exact regressors: their noise and
  filtering bias its estimates (Morelli & Klein 2016 sec. 11.2 for the filtering).

When none applies, it says that no reason was found in the fits.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from flightid.derivatives import is_derivative
from flightid.identification import nuisance
from flightid.identification.engine import convergence
from flightid.identification.estimate import Estimate, StdKind

AGREE_SIGMAS = 3.0  # a difference beyond 3 sigma: 0.27 % by chance for Gaussian estimates
# methods that take the measured states as exact regressors (equation error, stepwise
# regression, frequency-domain equation error)
REGRESSION = ("ee", "swr", "fdee")


@dataclass(frozen=True)
class Comparison:
    """One derivative as two methods estimate it: values, standard errors, and the
    difference in standard errors of the difference."""

    parameter: str
    methods: tuple[str, str]
    values: tuple[float, float]
    std: tuple[float, float]
    sigmas: float

    @property
    def agree(self) -> bool:
        """Whether the difference is within ``AGREE_SIGMAS``."""
        return abs(self.sigmas) <= AGREE_SIGMAS


@dataclass
class Agreement:
    """Every compared derivative of every pair of methods, and the reasons for the
    disagreements."""

    comparisons: list[Comparison] = field(default_factory=list)
    reasons: list[str] = field(default_factory=list)

    @property
    def disagreements(self) -> list[Comparison]:
        """The comparisons beyond ``AGREE_SIGMAS``."""
        return [c for c in self.comparisons if not c.agree]

    @property
    def verdict(self) -> str:
        """"agree", "disagree", or "nothing compared" (no derivative in common)."""
        if not self.comparisons:
            return "nothing compared"
        return "disagree" if self.disagreements else "agree"

    def lines(self) -> list[str]:
        """The verdict, each disagreement and each reason, one line each."""
        out = [f"methods {self.verdict} (within {AGREE_SIGMAS:g} sigma of the difference)"]
        for c in self.disagreements:
            (a, b), (va, vb), (sa, sb) = c.methods, c.values, c.std
            out.append(f"  {c.parameter}: {a} {va:.4g} +- {sa:.2g}, {b} {vb:.4g} +- {sb:.2g} "
                       f"({c.sigmas:+.1f} sigma)")
        out += [f"  why: {r}" for r in self.reasons]
        return out

    def to_json(self) -> dict[str, object]:
        """Plain data: verdict, comparisons (with ``agree``) and reasons."""
        return {"verdict": self.verdict, "sigmas": AGREE_SIGMAS,
                "comparisons": [{"parameter": c.parameter, "methods": list(c.methods),
                                 "values": list(c.values), "std": list(c.std),
                                 "sigmas": c.sigmas, "agree": c.agree}
                                for c in self.comparisons],
                "reasons": list(self.reasons)}


def _derivatives(est: Estimate) -> dict[str, tuple[float, float]]:
    return {n: (float(v), float(s)) for n, v, s in zip(est.names, est.values, est.std,
                                                       strict=True)
            if is_derivative(n) and not n.endswith("_0") and np.isfinite(v)}


def compare(estimates: Sequence[Estimate]) -> Agreement:
    """Compare every pair of ``estimates`` on the derivatives both estimate.

    The estimates are one per method, for the same record and window; the reasons for any
    disagreement follow the module note.

    Parameters
    ----------
    estimates : sequence of Estimate
        One estimate per method.

    Returns
    -------
    Agreement
        Each pair's comparison per shared derivative (difference in combined standard errors)
        and, when any disagree, the reasons.
    """
    result = Agreement()
    for a, b in combinations(estimates, 2):
        da, db = _derivatives(a), _derivatives(b)
        for name in (n for n in da if n in db):
            (va, sa), (vb, sb) = da[name], db[name]
            scale = float(np.hypot(sa, sb))
            sigmas = (va - vb) / scale if scale > 0 else float("inf") * np.sign(va - vb)
            result.comparisons.append(Comparison(name, (a.method, b.method), (va, vb),
                                                 (sa, sb), float(sigmas)))
    if result.disagreements:
        result.reasons = _reasons(estimates, result.disagreements)
    return result


def _reasons(estimates: Sequence[Estimate], bad: Sequence[Comparison]) -> list[str]:
    involved = {m for c in bad for m in c.methods}
    by_method = {e.method: e for e in estimates if e.method in involved}
    reasons = []
    for m, est in by_method.items():
        if not convergence.converged(est):
            reasons.append(f"{m} did not converge: its values are not at the optimum and "
                           "its std are not bounds")
        wild = [t.name for t in nuisance.from_fit(est) if t.implausible]
        if wild:
            reasons.append(f"{m}'s nuisance bias(es) {', '.join(wild)} are beyond any "
                           "instrument: the model or its reference condition does not fit "
                           "the data")
    for a, b in combinations(by_method.values(), 2):
        only_a = sorted(set(_derivatives(a)) - set(_derivatives(b)))
        only_b = sorted(set(_derivatives(b)) - set(_derivatives(a)))
        for est, only, other in ((a, only_a, b), (b, only_b, a)):
            if only:
                reasons.append(f"different models: {', '.join(only)} estimated by "
                               f"{est.method}, held by {other.method}; a held derivative "
                               "moves the ones correlated with it")
    white = [m for m, e in by_method.items() if e.std_kind == StdKind.CRAMER_RAO]
    colored = [m for m, e in by_method.items() if e.std_kind == StdKind.CRAMER_RAO_COLORED]
    if white and colored:
        reasons.append(f"the std of {', '.join(white)} assume white residuals, those of "
                       f"{', '.join(colored)} are corrected for colored ones: white-residual "
                       "bounds are too small when the residuals are colored")
    regression = [m for m in by_method if m in REGRESSION]
    if regression:
        reasons.append(f"{', '.join(regression)} take(s) the measured states as exact "
                       "regressors: their noise and filtering bias the estimates")
    return reasons or ["no reason found in the fits: check the model structure and the "
                       "data's consistency (flightid compatibility)"]
