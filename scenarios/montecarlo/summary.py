"""Per-derivative statistics of a study's rows: is the estimator unbiased, and are its
standard errors (the bounds the method reports) the real scatter?

bias: mean of estimate - truth; scatter: standard deviation of estimate - truth (ddof 1;
the standard deviation of the estimates when the truth is one value, as it is without
dispersions); truth: the mean truth;
mean_bound: mean of the reported standard errors; ratio: scatter / mean_bound (1 when the
bounds are right, > 1 when they are optimistic); coverage: share of the realizations with
|error| <= 1.96 std (0.95 for a Gaussian estimator whose bounds are right);
coverage_low, coverage_high: its 95 % Clopper-Pearson interval (Clopper & Pearson 1934;
``intervals.binomial_interval``), what the n realizations can tell of the true coverage;
unidentifiable: share of the realizations (that did not fail) that found the derivative
unidentifiable; failures: realizations that produced no estimate at all;
coverage_warning: set when the coverage falls outside the 99 % band of a binomial share
of 0.95 for its n (``intervals.binomial_band``): the bounds are optimistic (below the
band) or pessimistic (above it), beyond what n realizations leave to chance.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from flightid.files import json_safe
from flightid.identification.evaluation.scoring import STATUS_ESTIMATED, STATUS_UNIDENTIFIABLE
from flightid.scenarios.montecarlo.intervals import binomial_band, binomial_interval
from flightid.scenarios.montecarlo.study import STATUS_FAILED

Z95 = 1.96
COVERAGE_LEVEL = 0.95  # the confidence of the coverage's interval
NOMINAL = 0.95  # the coverage of right 95 % intervals
BAND_LEVEL = 0.99  # the band around NOMINAL outside which a coverage is warned about


@dataclass
class DerivativeSummary:
    """The statistics of one derivative over a study (NaN where undefined)."""

    name: str
    truth: float
    estimated: int  # realizations that estimated it
    mean: float
    bias: float
    scatter: float
    mean_bound: float
    ratio: float
    coverage: float
    unidentifiable: float
    failures: int
    coverage_low: float = math.nan
    coverage_high: float = math.nan
    coverage_warning: str = ""


def coverage_warning(covered: int, n: int) -> str:
    """The warning of a coverage of ``covered`` in ``n`` outside the ``BAND_LEVEL`` band of
    ``NOMINAL`` (``intervals.binomial_band``); "" inside it or for n = 0.

    Parameters
    ----------
    covered : int
        Intervals that held the truth.
    n : int
        Intervals.

    Returns
    -------
    str
        The warning, or "".
    """
    if n <= 0:
        return ""
    low, high = binomial_band(n, NOMINAL, BAND_LEVEL)
    share = covered / n
    if low <= share <= high:
        return ""
    what = "optimistic: the scatter exceeds them" if share < low else \
        "pessimistic: wider than the scatter"
    return (f"coverage {share:.2f} is outside {low:.2f}-{high:.2f}, the {BAND_LEVEL:.0%} band "
            f"of {NOMINAL:.0%} intervals at n = {n}: the bounds are {what}")


@dataclass
class Summary:
    """A study's statistics: one row per derivative; realizations and failures counted."""

    realizations: int
    failures: int
    rows: list[DerivativeSummary] = field(default_factory=list)
    failure_reasons: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """Plain data (NaN as None), JSON-ready."""
        return {"realizations": self.realizations, "failures": self.failures,
                "failure_reasons": dict(self.failure_reasons),
                "rows": [json_safe(asdict(r)) for r in self.rows]}

    def frame(self) -> pd.DataFrame:
        """The rows as a DataFrame indexed by derivative name."""
        return pd.DataFrame([asdict(r) for r in self.rows]).set_index("name")

    def row(self, name: str) -> DerivativeSummary:
        for r in self.rows:
            if r.name == name:
                return r
        raise KeyError(f"{name} is not in the summary; it has {', '.join(self.names)}")

    @property
    def names(self) -> list[str]:
        return [r.name for r in self.rows]

    def warnings(self) -> list[str]:
        """"<derivative>: <coverage warning>" for each derivative that has one."""
        return [f"{r.name}: {r.coverage_warning}" for r in self.rows if r.coverage_warning]


def summarize(df: pd.DataFrame) -> Summary:
    """The Summary of a study's rows (``store.load``).

    Parameters
    ----------
    df : pandas.DataFrame
        The study's rows.

    Returns
    -------
    Summary
        Realizations, failures and per-derivative statistics.
    """
    if df.empty:
        return Summary(0, 0)
    realizations = int(df["index"].nunique())
    failed = df[df["status"] == STATUS_FAILED]
    failures = int(failed["index"].nunique())
    reasons = failed["reason"].str.split(":").str[0].value_counts()
    ok = df[df["status"] != STATUS_FAILED]
    survivors = realizations - failures
    rows = []
    for name, g in ok.groupby("name", sort=True, observed=True):
        est = g[g["status"] == STATUS_ESTIMATED]
        values, std, err = (est[c].to_numpy(float) for c in ("estimate", "std", "error"))
        truth = float(g["truth"].mean())  # one value unless the aircraft is dispersed
        n = len(est)
        mean = float(values.mean()) if n else math.nan
        # of the errors: with dispersions the truth differs from one realization to the
        # next, and the estimator's bias and scatter are those of estimate - truth
        scatter = float(err.std(ddof=1)) if n > 1 else math.nan
        bound = float(std.mean()) if n else math.nan
        covered = int(np.sum(np.abs(err) <= Z95 * std))
        low, high = binomial_interval(covered, n, COVERAGE_LEVEL)
        rows.append(DerivativeSummary(
            name=str(name), truth=truth, estimated=n, mean=mean,
            bias=float(err.mean()) if n else math.nan,
            scatter=scatter, mean_bound=bound,
            ratio=scatter / bound if n > 1 and bound > 0 else math.nan,
            coverage=covered / n if n else math.nan,
            unidentifiable=(float((g["status"] == STATUS_UNIDENTIFIABLE).sum()) / survivors
                            if survivors else math.nan),
            failures=failures, coverage_low=low, coverage_high=high,
            coverage_warning=coverage_warning(covered, n)))
    return Summary(realizations, failures, rows,
                   {str(k): int(v) for k, v in reasons.items()})
