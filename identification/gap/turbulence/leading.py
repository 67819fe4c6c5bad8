"""The leading candidates judged by filter error: turbulence as process noise.

Output error (``fit.fit``) takes every residual for measurement noise. In turbulence the
gust-driven response is a colored residual that biases its estimates (light turbulence:
an inertia scale of 1.3 fitted 1.11 +- 0.015, 13 standard errors off; docs/gap_benchmark.md)
and lets an effect that fits the gusts, such as a slow lag of V, win. The filter-error
method gives the model process noise and scores the innovations (Jategaonkar 2015 ch. 5;
Maine & Iliff 1985; ``fit.filter_fit``).

The ``LEAD`` candidates of the output-error ranking with the strongest evidence on the
fitted windows (lowest delta BIC, negative; the top confirmed effect always among them)
are fitted by filter error on every fitted window. Their evidence is the delta BIC of
filter error, sum over windows 2 (J_effect - J_model) + k ln N with J the innovations'
negative log-likelihood. Output error's values may be outside the physical range where
filter error's are not (a pitch inertia of 1.3 fitted 1.53 +- 0.15 in light turbulence),
so the range is checked on filter error's. The one with the lowest delta BIC, negative,
within its range, is named when output error confirmed nothing or when it beats the
effect output error named by ``MARGIN`` and frees no more parameters than it (Occam, as
``rank.prefer_fewer_parameters``: tail ice's three factors fit a calm flight's Cm_alpha
delta better by filter error, delta BIC -567 against -373), provided it is better than
the model on the held-out windows under filter error too (each filtered with the
effect's parameters from the other windows, its biases and noise fitted as the model's
are: ``held_out``). An effect so named takes its filter-error values (output error's
choice, when kept, its own). An effect output error named that filter error finds no
better than the model (nor any other leading candidate) is not named. A pair output error
confirmed is named only when its second effect lowers the filter-error delta BIC of the
first by ``PAIR_SHARE`` of the first's. Only the first named effect and its pairs are
judged (``diagnosis``): a judgement per step of the sequence would cost as much again.

Time constants (lags, delays) are held at their output-error values: Gauss-Newton on a
time constant under process noise leaves for far worse points (a lag of V started at
0.01 s: J -9890, the model as is -11776, held at 0.01 s -11800). A nonlinear actuator
candidate (``candidates.linkage``) is scored at its grid value, with the record's surface
passed through it.

A candidate contains the model as is, so its optimum is at or below the model's; a window
fit from output error's values that ends above it (a worse local optimum of the noise) is
fitted again from the model's end point (``fit.filter_fit(warm=...)``), the lower J kept.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from flightid.identification.gap.candidates.classes import surface_before_inertia
from flightid.identification.gap.candidates.linkage import is_linkage, transformed
from flightid.identification.gap.candidates.ranges import out_of_range
from flightid.identification.gap.fit import FilterFit, filter_fit
from flightid.identification.gap.model.edits import Candidate
from flightid.identification.gap.rank import Ranker, rank, rank_key, ranked_pairs
from flightid.identification.gap.ranked import Ranked, combine
from flightid.identification.gap.segments import Segment
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

LEAD = 4  # candidates judged by filter error (by output-error delta BIC)
# filter-error delta BIC (1) by which the filter's choice must beat the effect output
# error confirmed to replace it
MARGIN = 20.0
# the share of the first effect's filter-error delta BIC that the second of a pair must add
PAIR_SHARE = 0.5


@dataclass
class FilterEvidence:
    """A candidate's filter-error evidence: its delta BIC on the fitted windows and its
    parameters combined over them (inverse-variance mean, the model's units)."""

    delta_bic: float
    values: dict[str, float]
    std: dict[str, float]


def leading(ranked: list[Ranked]) -> list[Ranked]:
    """The candidates judged by filter error: the ``LEAD`` single effects with the lowest
    negative delta BIC, and the top effect when confirmed.

    Parameters
    ----------
    ranked : list of Ranked
        The output-error ranking (``rank.rank``).

    Returns
    -------
    list of Ranked
    """
    single = [r for r in ranked if not r.candidate.parts
              and math.isfinite(r.delta_bic) and r.delta_bic < 0]
    out = sorted(single, key=lambda r: r.delta_bic)[:LEAD]
    if ranked and ranked[0].confirmed and ranked[0] not in out and not ranked[0].candidate.parts:
        out.append(ranked[0])
    return out


def judged_ranking(ranker: Ranker, candidates: list[Candidate], try_pairs: bool = True
                   ) -> tuple[list[Ranked], list[Ranked]]:
    """The candidates ranked by output error (``rank.rank``) and judged by filter error
    (``FilterJudge.judged``), and the top effect's pairs (``rank.ranked_pairs``, judged
    by ``FilterJudge.pairs``; none without ``try_pairs``).

    Parameters
    ----------
    ranker : Ranker
        The ranker of the record's windows.
    candidates : list of Candidate
        The candidates (``candidates.build.catalogue_candidates``).
    try_pairs : bool, optional
        Try pairs of effects. Default True.

    Returns
    -------
    tuple of (list of Ranked, list of Ranked)
        The single effects and the pairs, each in ranking order.
    """
    judge = FilterJudge(ranker)
    ranked = judge.judged(rank(ranker, candidates))
    if not (try_pairs and ranked):
        return ranked, []
    return ranked, judge.pairs(ranked[0], ranked_pairs(ranker, ranked))


def _time_constants(cand: Candidate) -> set[str]:
    """The freed parameters of ``cand`` (or its parts) that are time constants."""
    return {n for c in (cand.parts or (cand,)) if c.catalogue == ("tau",) for n in c.free}


def _fitter(model: LinearModel, r: Ranked, from_model: bool = False
            ) -> Callable[[FlightRecord, dict[str, float] | None, FilterFit | None],
                          FilterFit]:
    """fit(record, held values or None, warm start or None): the candidate's filter-error
    fit of a window, its parameters free or held at the given values (module note);
    started from output error's values, or with ``from_model`` from the model as is (the
    time constants at output error's values) and the given fit of the model's end point."""
    cand = r.candidate
    if is_linkage(cand):
        surface, value = cand.options["surface"], next(iter(r.values.values()))

        def linkage(record: FlightRecord, _: dict[str, float] | None = None,
                    __: FilterFit | None = None) -> FilterFit:
            f = filter_fit(model, transformed(record, cand.entry, surface, value))
            return FilterFit(dict(r.values), dict(r.std), {}, f.cost, f.samples)

        return linkage
    taus = _time_constants(cand)
    # output error's estimate (near the optimum), or the model as is
    start = cand.wrap(model).with_start(**(
        {n: r.values[n] for n in taus} if from_model else r.values))
    free = tuple(n for n in cand.free if n not in taus)

    def edit(record: FlightRecord, values: dict[str, float] | None = None,
             warm: FilterFit | None = None) -> FilterFit:
        if values is not None:
            return filter_fit(start.with_start(**values), record, (), model.states)
        f = filter_fit(start, record, free, model.states, warm)
        for n in taus:
            f.values[n], f.std[n] = r.values[n], r.std[n]
        return f

    return edit


def _fit_or_none(fitted: Callable[..., FilterFit], record: FlightRecord,
                 warm: FilterFit | None = None) -> FilterFit | None:
    try:
        return fitted(record, None, warm)
    except (ValueError, np.linalg.LinAlgError):
        return None


class FilterJudge:
    """The filter-error evidence of a ranking's candidates on one record's fitted windows
    (the model as is fitted once, each candidate's evidence cached)."""

    def __init__(self, ranker: Ranker) -> None:
        self.ranker = ranker
        self._base: dict[str, FilterFit] | None = None
        self._evidence: dict[int, FilterEvidence | None] = {}
        self._fits: dict[int, list[FilterFit | None]] = {}

    def base(self) -> dict[str, FilterFit]:
        """The model as is on every fitted and held-out window ({} when one cannot be
        fitted)."""
        if self._base is None:
            folds = self.ranker.folds
            windows = {s.label: s.record for s in folds.fit}
            windows |= {s.label: s.record for _, test in folds.folds for s in test}
            try:
                self._base = {k: filter_fit(self.ranker.lin.model, rec)
                              for k, rec in windows.items()}
            except (ValueError, np.linalg.LinAlgError):
                self._base = {}
        return self._base

    def evidence(self, r: Ranked) -> FilterEvidence | None:
        """``r``'s filter-error evidence (module note); None when no window can be fitted.

        Parameters
        ----------
        r : Ranked
            A candidate of the output-error ranking (a single effect or a pair).

        Returns
        -------
        FilterEvidence or None
        """
        if id(r) not in self._evidence:
            base = self.base()
            fitted = _fitter(self.ranker.lin.model, r)
            fits = [_fit_or_none(fitted, s.record) if base else None
                    for s in self.ranker.folds.fit]
            if base and not is_linkage(r.candidate):
                # a fit from output error's values that ends above the model it contains
                # is on a worse local optimum of the noise: again from the model's end point
                again = _fitter(self.ranker.lin.model, r, from_model=True)
                for i, s in enumerate(self.ranker.folds.fit):
                    f = fits[i]
                    if f is None or f.cost > base[s.label].cost:
                        g = _fit_or_none(again, s.record, base[s.label])
                        if g is not None and (f is None or g.cost < f.cost):
                            fits[i] = g
            self._fits[id(r)] = fits
            self._evidence[id(r)] = _evidence(self.ranker.folds.fit, fits, r, base)
        return self._evidence[id(r)]

    def held_out(self, r: Ranked) -> float:
        """The summed held-out cost change of ``r`` under filter error: each held-out
        window filtered with ``r``'s parameters from the other windows (its biases and
        noise fitted, as the model's are); inf when no window is scored.

        Parameters
        ----------
        r : Ranked
            A candidate of the output-error ranking.

        Returns
        -------
        float
            Negative log-likelihood change (1).
        """
        if self.evidence(r) is None:
            return math.inf
        fitted, fits, base = _fitter(self.ranker.lin.model, r), self._fits[id(r)], self.base()
        change, scored = 0.0, 0
        for train, test in self.ranker.folds.folds:
            part = combine([f for i in train if (f := fits[i]) is not None], r.candidate.free)
            if part is None:
                continue
            for s in test:
                if s.label not in base:
                    continue
                try:
                    change += fitted(s.record, part[0]).cost - base[s.label].cost
                except (ValueError, np.linalg.LinAlgError):
                    continue
                scored += 1
        return change if scored else math.inf

    def judged(self, ranked: list[Ranked]) -> list[Ranked]:
        """``ranked`` with its top effect the one filter error favours among the leading
        candidates (module note).

        Parameters
        ----------
        ranked : list of Ranked
            The output-error ranking (``rank.rank``).

        Returns
        -------
        list of Ranked
            The ranking: its top effect replaced (confirmed, with a note), or unconfirmed
            when filter error supports none; the named effect's values those of filter
            error. Unchanged without a leading candidate or a filter-error fit.
        """
        lead = leading(ranked)
        if not lead or not self.base():
            return ranked
        top = ranked[0] if ranked[0].confirmed else None
        eligible = [r for r in lead if self._bic(r) < 0 and self._in_range(r)]
        if not eligible:
            if top is not None and self.evidence(top) is not None:
                top.confirmed = False
                top.note = ("no better than the model under filter error (the turbulence "
                            "as process noise): not named")
            return ranked
        if top is not None:  # Occam: no more parameters than output error's choice
            eligible = [r for r in eligible if len(r.candidate.free) <= len(top.candidate.free)]
        if not eligible:
            return ranked
        best = min(eligible, key=self._bic)
        if top is not None and (self.evidence(top) is None
                                or self._bic(top) - self._bic(best) < MARGIN):
            best = top
        if top is not None:  # a surface's effect before an inertia scale, as in ``rank``
            best = surface_before_inertia(best, [best, top])
        if best is top:  # output error's choice kept, with its values
            return ranked
        held = self.held_out(best)
        if not held < 0:  # filter error's choice no better on held-out windows
            return ranked
        e = self.evidence(best)
        if e is not None and not is_linkage(best.candidate):
            # the larger bound of the two methods: filter error's sandwich leaves out the
            # linearisation's misfit (a Twin Otter elevator of 0.709 in light turbulence:
            # 0.690 +- 0.0014 by filter error, 0.656 +- 0.027 by output error)
            std = {n: max(v, best.std.get(n, 0.0)) for n, v in e.std.items()}
            best.values, best.std = e.values, std
            best.parameters = best.candidate.parameters(e.values, std, self.ranker.lin.model)
        best.confirmed, best.family = True, ""
        best.note = (f"named by filter error (the turbulence as process noise): delta BIC "
                     f"{self._bic(best):+.0f}" + (f" against {self._bic(top):+.0f} for "
                                                  f"{top.candidate.label}" if top else "")
                     + f", held-out cost change {held:+.0f}")
        return [best, *(r for r in ranked if r is not best)]

    def pairs(self, single: Ranked, pairs: list[Ranked]) -> list[Ranked]:
        """``pairs`` with the confirmed ones whose second effect does not lower the
        filter-error delta BIC of ``single`` by ``PAIR_SHARE`` of it unconfirmed.

        Parameters
        ----------
        single : Ranked
            The top single effect.
        pairs : list of Ranked
            Its pairs (``rank.ranked_pairs``).

        Returns
        -------
        list of Ranked
            ``pairs``, re-sorted (``rank.rank_key``).
        """
        for p in pairs:
            if p.confirmed and not (self._bic(single) < 0 and self._bic(p) <= (
                    1 + PAIR_SHARE) * self._bic(single)):
                p.confirmed = False
                p.note = "its second effect adds too little under filter error"
        return sorted(pairs, key=rank_key)

    def _in_range(self, r: Ranked) -> bool:
        """Whether filter error's values of ``r`` are in the catalogue's physical range."""
        e = self.evidence(r)
        if e is None or is_linkage(r.candidate):
            return e is not None
        model = self.ranker.lin.model
        return out_of_range(r.candidate, r.candidate.parameters(e.values, e.std, model),
                            model) is None

    def _bic(self, r: Ranked) -> float:
        e = self.evidence(r)
        return math.inf if e is None else e.delta_bic


def _evidence(windows: list[Segment], fits: list[FilterFit | None], r: Ranked,
              base: dict[str, FilterFit]) -> FilterEvidence | None:
    k = len(r.candidate.free)
    ok = [(s, f) for s, f in zip(windows, fits, strict=True) if f is not None]
    both = combine([f for _, f in ok], r.candidate.free) if ok else None
    if both is None:
        return None
    dbic = sum(2 * (f.cost - base[s.label].cost) + k * math.log(f.samples) for s, f in ok)
    return FilterEvidence(dbic, *both)
