"""Which effect: every candidate fitted with the rest of the model held, ranked by
evidence and confirmed on held-out windows.

Evidence on the fitted windows is the Bayesian information criterion (Schwarz 1978):
delta BIC = sum over windows of 2 (J_effect - J_model) + k ln N, with J = N/2 ln det R the
concentrated output-error cost (Morelli & Klein 2016 eq. 6.27) and k the parameters the
effect adds; negative favours the effect. Each window is fitted on its own; the effect's
parameters are the inverse-variance mean over the windows. Held out: each window in turn
is predicted with the parameters of the other windows (or every fitted window predicts
the ``validate`` records): an effect is confirmed when it lowers the held-out cost and
shrinks the held-out gap (mean over channels of residual / measured energy) by at least
``MIN_GAIN`` (absolute: a model that already reproduces the data to a fraction of a
percent has no gap to name) and by ``MIN_EXCESS_SHRINK`` of the gap above the null level
(``Ranker.above``: the input-explained share of the null test; turbulence and noise are
no part of what an effect can close), or ``MIN_SHRINK`` of the whole held-out gap when
that level is not known. Confirmed effects rank first, by their held-out cost change
(``rank_key``), the others by delta BIC. Effects whose held-out costs cannot be told apart
(``tied``) are listed beside the one named (``Ranked.alternatives``), and the one that frees
fewest parameters is named (``simplest``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flightid.identification.gap.candidates.build import Candidate, pair
from flightid.identification.gap.candidates.classes import (
    prefer_model_terms,
    surface_before_inertia,
)
from flightid.identification.gap.candidates.linkage import (
    GRIDS,
    is_linkage,
    refined_minimum,
    scan,
    transformed,
)
from flightid.identification.gap.candidates.ranges import out_of_range
from flightid.identification.gap.fit import WindowFit, fit, held
from flightid.identification.gap.model.linearise import Linearised
from flightid.identification.gap.ranked import (
    Ranked,
    combine,
    mean_gap,
    pooled_fractions,
    pooled_noise,
)
from flightid.identification.gap.segments import Segment
from flightid.record import FlightRecord

MIN_SHRINK = 0.10  # relative shrink of the held-out gap that confirms an effect
# with the null level known (``Ranker.above``): the held-out gain that confirms an effect,
# relative to the gap above the null level (turbulence and noise do not count)
MIN_EXCESS_SHRINK = 0.25
# and absolute: this fraction of the measured energy explained. Above what the
# linearisation's own misfit gives on null flights (the plain model on its own flight):
# 0.0013 for Cn_beta on navion-demo without turbulence, below 0 on the blind check's cards
# (docs/gap_benchmark.md); 0.005 before 2026-11-27 missed four right effects of 0.002-0.005
MIN_GAIN = 0.002
# screening: every candidate fitted with this many Gauss-Newton steps, the best SCREEN_KEEP
# by delta BIC then fitted to convergence and checked on held-out data
SCREEN_ITERATIONS = 2
SCREEN_KEEP = 12
# entries evaluated in full beside the screened ones, never screened out: a lag between a
# recorded command and its surface (offered on records of commands only, one per surface)
# is nonlinear in its time constant, and two Gauss-Newton steps from its start leave the fit
# worse than the model as is (seed 0 of the blind check: a Navion elevator lag of 0.12 s
# screened at delta BIC +431, 18th, an aileron lag of 0.079 s and a c172p elevator lag of
# 0.13 s likewise out of the twelve kept; docs/gap_benchmark.md, the rules for the seed-8 run).
# A sensor's scale too (the seed-10 rules): seed 9's c172p q scale of 1.38 screened 19th of 32
UNSCREENED = ("actuator_lag", "scale")
PAIR_LEVEL = 0.05  # held-out gap (mean fraction) above which pairs of effects are tried
PAIR_TOP = 4  # pairs: the top effect with the next ones of the ranking
# with the null level known: pairs are tried when the top effect closes less than this
# share of the gap above it
PAIR_SHARE = 0.7
# two confirmed effects are not told apart when the sum over held-out windows of the
# difference of their cost changes is within this many of its standard errors (``tied``)
TIE_Z = 2.0



@dataclass
class Folds:
    """Which windows fit and which are held out: [(fit indices, held-out windows)]."""

    fit: list[Segment]
    folds: list[tuple[list[int], list[Segment]]]

    @classmethod
    def make(cls, fit_windows: list[Segment], validate: list[Segment] | None) -> Folds:
        if validate:
            return cls(fit_windows, [(list(range(len(fit_windows))), validate)])
        if len(fit_windows) < 2:
            return cls(fit_windows, [])
        n = len(fit_windows)
        return cls(fit_windows, [([i for i in range(n) if i != j], [fit_windows[j]])
                                 for j in range(n)])


class Ranker:
    """Fits candidates on the windows and checks them on the held-out ones (cached)."""

    def __init__(self, lin: Linearised, folds: Folds,
                 above: dict[str, float] | None = None) -> None:
        self.lin, self.folds = lin, folds
        # per channel: the gap above the null level (the input-explained share of the null
        # test, ``verdict.null_test``), against which an effect's shrink is judged; None:
        # the whole held-out gap
        self.above = above
        self.base = {s.label: fit(lin.model, s.record) for s in folds.fit}
        self.base_held: dict[str, WindowFit] = {}
        for _, test in folds.folds:
            for s in test:
                if s.label not in self.base_held:
                    self.base_held[s.label] = self.base.get(s.label) or fit(lin.model, s.record)
        # the noise floor of the held-out windows (the model as is: differencing removes its
        # slowly varying misfit)
        self.floor = pooled_noise(list(self.base_held.values())) if self.base_held else {}

    def screen(self, cand: Candidate) -> float:
        """The candidate's delta BIC on the fitted windows after ``SCREEN_ITERATIONS``
        Gauss-Newton steps from the model's values, no held-out check: the cheap first
        look at the whole catalogue (inf when no window can be fitted)."""
        model = cand.wrap(self.lin.model)
        dbic, fitted = 0.0, False
        for s in self.folds.fit:
            try:
                f = fit(model, s.record, cand.free, SCREEN_ITERATIONS)
            except (ValueError, np.linalg.LinAlgError):
                continue
            fitted = True
            dbic += 2 * (f.cost - self.base[s.label].cost) + len(cand.free) * math.log(f.samples)
        return dbic if fitted else math.inf

    def evaluate(self, cand: Candidate) -> Ranked | None:
        model = cand.wrap(self.lin.model)
        fits = []
        for s in self.folds.fit:
            try:
                fits.append(fit(model, s.record, cand.free))
            except (ValueError, np.linalg.LinAlgError):
                fits.append(None)
        ok = [f for f in fits if f is not None]
        both = combine(ok, cand.free) if ok else None
        if both is None:
            return None
        values, std = both
        dbic, dcost = 0.0, 0.0
        for s, f in zip(self.folds.fit, fits, strict=True):
            if f is None:
                continue
            d = f.cost - self.base[s.label].cost
            dcost += d
            dbic += 2 * d + len(cand.free) * math.log(f.samples)
        r = Ranked(cand, values, std, cand.parameters(values, std, self.lin.model), dbic, dcost)
        self.judge(r, *self.held_out(
            lambda train: combine([fits[i] for i in train if fits[i] is not None], cand.free),
            lambda part, record: held(model, part[0], record)))
        if family := out_of_range(cand, r.parameters, self.lin.model):
            r.confirmed, r.family = False, family
            r.note = f"outside its physical range: {family}"
        return r

    def held_out(self, trained: Callable[[Sequence[int]], Any],
                 tested: Callable[[Any, FlightRecord], WindowFit]
                 ) -> tuple[list[WindowFit], list[WindowFit], float, list[str]]:
        """The held-out windows' fits of the model as is and with an effect: for each fold,
        ``trained(train)`` the effect fitted on the fold's windows (None: skipped) and
        ``tested(part, record)`` the fit of a held-out window with it; returns the fits
        before and after, the summed cost change and the windows' labels."""
        before, after, dheld, labels = [], [], 0.0, []
        for train, test in self.folds.folds:
            part = trained(train)
            if part is None:
                continue
            for s in test:
                try:
                    h = tested(part, s.record)
                except (ValueError, np.linalg.LinAlgError):
                    continue
                b = self.base_held[s.label]
                before.append(b)
                after.append(h)
                dheld += h.cost - b.cost
                labels.append(s.label)
        return before, after, dheld, labels

    def judge(self, r: Ranked, before: list[WindowFit], after: list[WindowFit],
              dheld: float, labels: list[str]) -> None:
        """Set ``r``'s held-out figures from the held-out windows' fits ``before`` (the
        model as is) and ``after`` (with the effect) and confirm it (module note)."""
        if not before:
            r.note = "no held-out window: not confirmed"
            return
        r.heldout_before, r.heldout_after = pooled_fractions(before), pooled_fractions(after)
        r.heldout_cost_change, r.heldout_windows = dheld, labels
        r.heldout_changes = {}
        for label, b, a in zip(labels, before, after, strict=True):
            r.heldout_changes[label] = r.heldout_changes.get(label, 0.0) + a.cost - b.cost
        gain = mean_gap(r.heldout_before) - mean_gap(r.heldout_after)
        level = (MIN_EXCESS_SHRINK * mean_gap(self.above) if self.above
                 else MIN_SHRINK * mean_gap(r.heldout_before))
        r.confirmed = bool(r.delta_bic < 0 and dheld < 0 and gain >= MIN_GAIN
                           and gain >= level)

    def held_at(self, cand: Candidate, values: dict[str, float], std: dict[str, float],
                delta_bic: float) -> Ranked:
        """``cand`` held at ``values`` estimated elsewhere (``candidates.compatibility``): its
        held-out figures on the held-out windows (``judge``), not confirmed here.

        Parameters
        ----------
        cand : Candidate
            A candidate of the linear model.
        values, std : dict of str to float
            Its freed parameters' values and standard errors (the model's units).
        delta_bic : float
            The evidence of the estimate (negative favours the effect).

        Returns
        -------
        Ranked
            The candidate with its held-out figures; ``confirmed`` left to the caller.
        """
        model = cand.wrap(self.lin.model)
        r = Ranked(cand, values, std, cand.parameters(values, std, self.lin.model),
                   delta_bic, 0.0)
        self.judge(r, *self.held_out(lambda train: values,
                                     lambda part, record: held(model, part, record)))
        r.confirmed = False
        return r

    def evaluate_linkage(self, cand: Candidate) -> Ranked | None:
        """A nonlinear actuator candidate (``candidates.linkage``): the model as is on the
        windows with the surface passed through the entry, its value found on the entry's
        grid over the fitted windows (over the other windows for each held-out one); None
        when the best value is at the grid's edge (no estimate)."""
        model, grid = self.lin.model, GRIDS[cand.entry]
        surface, (name,) = cand.options["surface"], cand.free
        fit_records = {s.label: s.record for s in self.folds.fit}
        table = scan(model, fit_records, cand)

        def best(labels: list[str]) -> tuple[float, float] | None:
            cost = [sum(table[k][i].cost if table[k][i] is not None else math.inf
                        for k in labels) for i in range(len(grid))]
            return refined_minimum(grid, cost)

        found = best(list(fit_records))
        if found is None:
            return None
        value, std = found
        dbic, dcost = 0.0, 0.0
        for label, rec in fit_records.items():
            try:
                f = fit(model, transformed(rec, cand.entry, surface, value))
            except (ValueError, np.linalg.LinAlgError):
                continue
            d = f.cost - self.base[label].cost
            dcost += d
            dbic += 2 * d + math.log(f.samples)
        r = Ranked(cand, {name: value}, {name: std},
                   cand.parameters({name: value}, {name: std}, model), dbic, dcost)
        self.judge(r, *self.held_out(
            lambda train: best([self.folds.fit[i].label for i in train]),
            lambda part, record: fit(model, transformed(record, cand.entry, surface, part[0]))))
        return r


def rank(ranker: Ranker, candidates: list[Candidate],
         keep: int | None = SCREEN_KEEP) -> list[Ranked]:
    """The candidates screened, the best evaluated in full, and sorted.

    Screening (``Ranker.screen``: every one, a few Gauss-Newton steps) keeps the ``keep`` best
    by delta BIC for the full evaluation (converged fits, the held-out check, the physical
    range); the ``UNSCREENED`` entries' candidates are evaluated in full beside them, never
    screened out, and the nonlinear actuator candidates (``candidates.linkage``) scored in
    full too (``Ranker.evaluate_linkage``). Sorted by ``rank_key`` after the held-out Occam
    rule of ``prefer_fewer_parameters``.

    Parameters
    ----------
    ranker : Ranker
        The ranker of the record's windows.
    candidates : list of Candidate
        The candidates.
    keep : int or None, optional
        How many screened candidates are evaluated in full; all of them when None. Default
        ``SCREEN_KEEP``.

    Returns
    -------
    list of Ranked
        The evaluated candidates in ranking order.
    """
    linkage = [c for c in candidates if is_linkage(c)]
    unscreened = [c for c in candidates if not is_linkage(c) and c.entry in UNSCREENED]
    candidates = [c for c in candidates if not is_linkage(c) and c.entry not in UNSCREENED]
    if keep is not None and len(candidates) > keep:
        scores = [ranker.screen(c) for c in candidates]
        order = sorted(range(len(candidates)), key=scores.__getitem__)
        candidates = [candidates[i] for i in order[:keep]]
    candidates += unscreened
    out = [r for c in candidates if (r := ranker.evaluate(c)) is not None]
    out += [r for c in linkage if (r := ranker.evaluate_linkage(c)) is not None]
    prefer_fewer_parameters(out)
    prefer_model_terms(out, MIN_SHRINK)
    return simplest(sorted(out, key=rank_key))


def tied(a: Ranked, b: Ranked) -> bool:
    """Whether the held-out data cannot tell ``a`` from ``b``: per held-out window the
    difference of their cost changes, its sum within ``TIE_Z`` standard errors (the
    windows' spread; a paired test of non-nested models on held-out blocks, Vuong 1989).
    False with fewer than two common windows (no spread to judge by).

    Parameters
    ----------
    a, b : Ranked
        Two evaluated effects.

    Returns
    -------
    bool
    """
    common = [w for w in a.heldout_changes if w in b.heldout_changes]
    if len(common) < 2:
        return False
    d = np.array([a.heldout_changes[w] - b.heldout_changes[w] for w in common])
    spread = math.sqrt(len(d)) * float(np.std(d, ddof=1))
    return bool(abs(float(np.sum(d))) <= TIE_Z * spread)


def simplest(ranked: list[Ranked]) -> list[Ranked]:
    """``ranked`` (sorted by ``rank_key``) with the confirmed effects that the held-out data
    cannot tell from the top one (``tied``) listed in its ``alternatives``, and the one that
    frees fewest parameters among them put first (a tie kept in order): an extra parameter
    that buys no held-out evidence is not named (Occam, as ``prefer_fewer_parameters``). A
    nonlinear actuator effect (``candidates.linkage``) tied with a linear effect of the same
    surface (a rate limit with the surface's lag) gives way to it: the nonlinear one adds a
    law of amplitude that the held-out data do not support.

    Parameters
    ----------
    ranked : list of Ranked
        The ranking, sorted by ``rank_key``.

    Returns
    -------
    list of Ranked
        The ranking, its top effect possibly replaced by a simpler tied one.
    """
    if not ranked or not ranked[0].confirmed:
        return ranked
    top = ranked[0]
    group = [top] + [r for r in ranked[1:] if r.confirmed and tied(top, r)]
    if len(group) == 1:
        return ranked
    first = min(group, key=lambda r: len(r.candidate.free))
    first = surface_before_inertia(first, group)
    if is_linkage(first.candidate):  # the same surface's linear effect: no amplitude law
        first = next((r for r in group if not is_linkage(r.candidate)
                      and r.candidate.options.get("surface") == first.candidate.options[
                          "surface"] and len(r.candidate.free) <= len(first.candidate.free)),
                     first)
    first.alternatives = [r for r in group if r is not first]
    if first is top:
        return ranked
    why = ("fewer parameters" if len(first.candidate.free) < len(top.candidate.free)
           else "a surface's effect before an inertia scale")
    first.note = f"named before {top.candidate.label}: not told apart on held-out data, {why}"
    return [first, *(r for r in ranked if r is not first)]


def rank_key(r: Ranked) -> tuple[bool, float]:
    """The ranking's sort key: confirmed effects first, by their held-out cost change, the
    others by delta BIC.

    The held-out cost change is the cross-validated evidence (Stone 1974): an effect that fits
    the fitted windows a little better by fitting their turbulence does no better on held-out
    ones.

    Parameters
    ----------
    r : Ranked
        A ranked candidate.

    Returns
    -------
    tuple of (bool, float)
        (not confirmed, held-out cost change or delta BIC).
    """
    return (not r.confirmed, r.heldout_cost_change if r.confirmed else r.delta_bic)


def prefer_fewer_parameters(ranked: list[Ranked]) -> None:
    """Unconfirm each confirmed effect that frees more parameters than another confirmed
    one and is not ``MIN_SHRINK`` better than it on held-out data (Occam's razor on
    held-out evidence): the simpler effect is named when the extra parameters only fit the
    linearisation's small misfit.

    Parameters
    ----------
    ranked : list of Ranked
        The ranked effects; changed in place (``confirmed`` and ``note``).
    """
    confirmed = [r for r in ranked if r.confirmed and r.heldout_after]
    for r in confirmed:
        after = mean_gap(r.heldout_after)
        for s in confirmed:
            if (len(s.candidate.free) < len(r.candidate.free)
                    and after > (1 - MIN_SHRINK) * mean_gap(s.heldout_after)):
                r.confirmed = False
                r.note = (f"no better on held-out data than {s.candidate.label}, which "
                          "frees fewer parameters")
                break


def ranked_pairs(ranker: Ranker, ranked: list[Ranked]) -> list[Ranked]:
    """The top effect paired with the next ``PAIR_TOP`` ones.

    Tried when the top effect alone leaves a held-out gap above ``PAIR_LEVEL`` (with the null
    level known, ``Ranker.above``: when it closes less than ``PAIR_SHARE`` of the gap above
    that level); a pair is confirmed when it improves the top effect's BIC and shrinks its
    held-out gap by ``MIN_SHRINK`` more (of that gap; with the null level known, of the gap
    above it).

    Parameters
    ----------
    ranker : Ranker
        The ranker that scored ``ranked``.
    ranked : list of Ranked
        The single effects, in ranking order.

    Returns
    -------
    list of Ranked
        The pairs, sorted by ``rank_key``; [] when no pair is tried.
    """
    if not ranked or not ranked[0].confirmed:
        return []
    if ranker.above is None and mean_gap(ranked[0].heldout_after) < PAIR_LEVEL:
        return []
    gain = mean_gap(ranked[0].heldout_before) - mean_gap(ranked[0].heldout_after)
    if ranker.above is not None and gain >= PAIR_SHARE * mean_gap(ranker.above):
        return []
    top = ranked[0]
    if is_linkage(top.candidate):  # not a model edit: a pair cannot carry it
        return []
    out = []
    for other in [r for r in ranked[1:] if not is_linkage(r.candidate)][:PAIR_TOP]:
        c = pair(top.candidate, other.candidate)
        if c is None or (r := ranker.evaluate(c)) is None:
            continue
        single_after = mean_gap(top.heldout_after)
        pair_after = mean_gap(r.heldout_after) if r.heldout_after else float("nan")
        better = (single_after - pair_after >= MIN_SHRINK * mean_gap(ranker.above)
                  if ranker.above else pair_after <= (1 - MIN_SHRINK) * single_after)
        r.confirmed = bool(r.confirmed and r.delta_bic < top.delta_bic and better)
        out.append(r)
    return sorted(out, key=rank_key)
