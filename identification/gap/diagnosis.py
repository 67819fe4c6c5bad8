"""The sim-to-real gap diagnosis: is there a gap, where it lies, which effect causes it,
how far it shrinks (``diagnose``), and its result (``GapResult``: verdict, json form, heat
map).

Each axis the records excite (``data.axes.excited_axes``: elevator -> longitudinal, aileron
or rudder -> lateral) is diagnosed on its own model and windows, and has its own verdict
(``verdict``): first the model as is is tested against the null level of noise and
turbulence; only where it fails are candidates ranked and named, in sequence until the
model with the named effects passes. With both axes, ``by_axis`` holds each axis's full
result, the verdict is the more severe one, the ranking holds both axes' effects, the gap
map both axes' channels, and the model, ``named`` and ``pairs`` are those of the axis whose
named effect has the stronger evidence (the lower delta BIC)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from flightid.files import json_safe
from flightid.identification.data.axes import AXIS_INPUTS, AXIS_NAMES, excited_axes
from flightid.identification.engine.threads import one_blas_thread
from flightid.identification.gap.candidates.build import catalogue_candidates
from flightid.identification.gap.candidates.classes import class_text
from flightid.identification.gap.candidates.compatibility import sensor_lag, undone
from flightid.identification.gap.candidates.gyro_scale import gyro_scale
from flightid.identification.gap.candidates.identifiable import not_identifiable
from flightid.identification.gap.candidates.linkage import is_linkage, transformed
from flightid.identification.gap.fit import fit
from flightid.identification.gap.jsbsim.refine import NotRefined, Refined
from flightid.identification.gap.jsbsim.refine import refine as refit
from flightid.identification.gap.jsbsim.symmetry import even_terms
from flightid.identification.gap.lines import Line, spectral_line, with_line, without_line
from flightid.identification.gap.model.linearise import Linearised, linearise
from flightid.identification.gap.model.surfaces import actuated
from flightid.identification.gap.nonlinearity import (
    NonlinearTest,
    named_sensor,
    nonlinear_test,
)
from flightid.identification.gap.rank import Folds, Ranker, rank_key
from flightid.identification.gap.ranked import Ranked, mean_gap
from flightid.identification.gap.residual_map import GapMap, gap_map, heat_map
from flightid.identification.gap.segments import Segment, segments, split
from flightid.identification.gap.sequence import STEPS, fixed, following, shrinkage
from flightid.identification.gap.trim_level import TrimOffset, trim_offsets
from flightid.identification.gap.turbulence.leading import judged_ranking
from flightid.identification.gap.verdict import (
    EXPLAINED,
    NO_GAP,
    PARTLY,
    UNEXPLAINED,
    NullTest,
    axis_verdict,
    null_test,
    worst,
)
from flightid.record import FlightRecord, read

TOP = 10  # effects listed in the json form
# share of the held-out gap above the noise floor the named effects may leave and still
# explain it. Measured on 25 cases of the blind check (docs/gap_benchmark.md): a quadratic
# sideslip vane named as a beta scale leaves 0.21-0.46; right attributions 0.001-0.22 (the
# floor is the white noise only, so the linearised model's own misfit counts as left)
PARTIAL = 0.2


@dataclass
class GapResult:
    """The diagnosis of records against a model."""

    aircraft: str
    linearised: Linearised
    where: GapMap
    effects: list[Ranked]  # ranked singles
    pairs: list[Ranked] = field(default_factory=list)
    # the named effects in sequence (named[0] the top effect or pair; each next one fitted
    # with the ones before it fixed), or [] when unexplained
    named: list[Ranked] = field(default_factory=list)
    windows: dict[str, list[str]] = field(default_factory=dict)  # fit / held out
    # each diagnosed axis's own result when the records excite both (else empty)
    by_axis: dict[str, GapResult] = field(default_factory=dict)
    # per channel: the white-noise part of the held-out gap (``ranked.pooled_noise``)
    floor: dict[str, float] = field(default_factory=dict)
    # the top named airframe effect refitted with the JSBSim aircraft (``refine``), or None
    refined: Refined | None = None
    refine_note: str = ""  # why a refit asked for was not made
    verdict: str = ""  # verdict.VERDICTS: no_gap, explained, partly_unexplained, unexplained
    # the null-level test of the model as is, and of the model with the named effects
    null_before: NullTest | None = None
    null_after: NullTest | None = None
    # how the named effects were checked: "held-out maneuvers", "validation records", or
    # "time split" (one maneuver cut in halves: the weaker evidence of the same maneuver)
    evidence: str = ""
    undiagnosed: dict[str, str] = field(default_factory=dict)  # axis -> why not diagnosed
    # catalogue entries that are no candidate for this record: entry -> why, and what
    # would make it identifiable (``identifiable.not_identifiable``)
    not_identifiable: dict[str, str] = field(default_factory=dict)
    # the trim-level check of this axis's channels (``trim_level``): the steady segment
    # against the model's trim; ``trim_note`` says why it was not made ("" when it was)
    trim: list[TrimOffset] = field(default_factory=list)
    trim_note: str = ""
    # the nonlinear-structure test of the model as is (``nonlinearity``): structure the
    # linear test and the catalogue cannot express; when found, the axis is not explained
    structure: NonlinearTest | None = None
    line: Line | None = None  # the spectral-line check (``lines``): engine vibration

    @property
    def trim_named(self) -> list[TrimOffset]:
        """The trim-level offsets named (significant and material), every axis's."""
        return [o for g in self.axes().values() for o in g.trim if o.named]

    def unexplained_share(self) -> float | None:
        """The share of the held-out gap above the noise floor that the named effects leave,
        (after - floor) / (before - floor) summed over channels; None when nothing is named
        or there is no gap above the floor."""
        if not self.named or not self.floor or not self.named[-1].heldout_after:
            return None
        before, after = self.named[0].heldout_before, self.named[-1].heldout_after
        chans = [c for c in before if c in self.floor and math.isfinite(self.floor[c])
                 and math.isfinite(before[c]) and math.isfinite(after.get(c, math.nan))]
        den = sum(max(before[c] - self.floor[c], 0.0) for c in chans)
        num = sum(max(after[c] - self.floor[c], 0.0) for c in chans)
        return num / den if den > 0 else None

    @property
    def partly_unexplained(self) -> bool:
        """The named effects leave more than ``PARTIAL`` of the gap above the noise floor:
        an effect outside the catalogue, of which the named ones express only a part."""
        share = self.unexplained_share()
        return share is not None and share > PARTIAL

    @property
    def axis(self) -> str:
        """The axis of the model (and of ``named``)."""
        return self.linearised.axis

    @property
    def unexplained(self) -> bool:
        """A gap above the null level and nothing named for it."""
        return self.verdict == "unexplained" if self.verdict else not self.named

    @property
    def top(self) -> Ranked | None:
        return self.named[0] if self.named else (self.effects[0] if self.effects else None)

    def shrinkage(self) -> dict:
        """Held-out gap of the model as is and with every named effect (the sequence);
        the top ranked effect's when nothing is named."""
        return shrinkage(self.named or ([self.top] if self.top else []))

    def remaining(self) -> dict[str, float]:
        """Where the residual stays (held-out, after the named effects or of the model)."""
        if self.named and self.named[-1].heldout_after:
            return self.named[-1].heldout_after
        t = self.top
        if t is not None and t.heldout_before:
            return t.heldout_before
        return {c: d["total"] for c, d in self.where.by_channel().items()}

    def to_json(self, top: int = TOP) -> dict[str, Any]:
        return json_safe({
            "aircraft": self.aircraft,
            "verdict": self.verdict,
            "axis": self.axis,
            "axes": {a: g.axis_json() for a, g in (self.by_axis or {self.axis: self}).items()},
            "undiagnosed": self.undiagnosed,
            "trim_named": [o.to_json() for o in self.trim_named],
            "model": {"axes": self.linearised.axes, "axis": self.axis,
                      "derivatives": self.linearised.derivatives,
                      "trim": {"altitude_m": self.linearised.trim.altitude_m,
                               "speed_m_s": self.linearised.trim.speed_m_s,
                               "alpha": self.linearised.trim.alpha}},
            "windows": self.windows,
            "where": self.where.to_json(),
            "effects": [r.to_json() for r in self.effects[:top]],
            "pairs": [r.to_json() for r in self.pairs],
            "named": [r.to_json() for r in self.named],
            "shrinkage": self.shrinkage(),
            "unexplained": ({"remaining": self.remaining(),
                             "overall": mean_gap(self.remaining())} if self.unexplained else None),
            "noise_floor": self.floor,
            "partly_unexplained": ({"share": self.unexplained_share(),
                                    "remaining_above_floor": self.remaining_above_floor()}
                                   if self.partly_unexplained else None),
            "refined": self.refined.to_json() if self.refined else None,
            "refine_note": self.refine_note or None,
            "by_axis": {a: {"named": [r.to_json() for r in g.named],
                            "shrinkage": g.shrinkage(), "unexplained": g.unexplained}
                        for a, g in self.by_axis.items()},
        })

    def axis_json(self) -> dict[str, Any]:
        """This axis's verdict, its null-level tests and what it named."""
        return {"verdict": self.verdict, "evidence": self.evidence,
                "not_identifiable": self.not_identifiable,
                "trim": [o.to_json() for o in self.trim], "trim_note": self.trim_note or None,
                "trim_named": [o.text() for o in self.trim if o.named],
                "even_terms": [{"derivative": e.derivative, "minus": e.minus, "plus": e.plus,
                                "even": e.even, "axes": e.axes, "note": e.text()}
                               for e in even_terms(self.linearised.kinks, self.linearised.axes)],
                "null_before": self.null_before.to_json() if self.null_before else None,
                "null_after": self.null_after.to_json() if self.null_after else None,
                "structure": self.structure.to_json() if self.structure else None,
                "line": self.line.to_json() if self.line else None,
                "named": [r.candidate.label for r in self.named]}

    def axes(self) -> dict[str, GapResult]:
        """Each diagnosed axis's own result (this one when a single axis was diagnosed)."""
        return self.by_axis or {self.axis: self}

    def named_all(self) -> list[Ranked]:
        """The named effects of every diagnosed axis."""
        return [r for g in self.axes().values() for r in g.named]

    def remaining_above_floor(self) -> dict[str, float]:
        """Per channel: the held-out gap left above the noise floor."""
        return {c: max(v - self.floor.get(c, 0.0), 0.0) for c, v in self.remaining().items()}

    def figure(self) -> Figure:
        return heat_map(self.where, f"gap map: {self.aircraft} (the model as is)")


Records = FlightRecord | str | Path | Sequence[FlightRecord | str | Path]


def _records(x: Records) -> tuple[list[FlightRecord], list[str]]:
    items = [x] if isinstance(x, FlightRecord | str | Path) else list(x)
    recs = [i if isinstance(i, FlightRecord) else read(i) for i in items]
    names = [Path(i).stem if not isinstance(i, FlightRecord) else f"record {k + 1}"
             for k, i in enumerate(items)]
    return recs, names


@one_blas_thread
def diagnose(records: Records, aircraft: str, validate: Records | None = None,
             names: Sequence[str] | None = None,
             validate_names: Sequence[str] | None = None, try_pairs: bool = True,
             steps: int = STEPS, axis: str = "both", refine: bool = False,
             surfaces: str | None = None) -> GapResult:
    """Diagnose ``records`` against the JSBSim ``aircraft``: per excited axis, is there a
    gap above the null level of noise and turbulence, where it lies, which catalogue
    effects explain it and how far the held-out gap shrinks (module docstring).

    Held out: each maneuver window in turn (windows of the records' maneuver lists, or the
    halves of a record without one); an axis with a single window is cut in two halves in
    time (``evidence`` says so: the weaker evidence of one maneuver).

    Parameters
    ----------
    records : FlightRecord, path, or a sequence of them
        Flight records of one aircraft at one condition (``envelope`` takes several).
    aircraft : str
        JSBSim aircraft: a project name, a stock JSBSim name or an XML path.
    validate : FlightRecord, path, a sequence of them, or None
        Records held out of every fit; None: each window held out in turn.
    names, validate_names : sequence of str, or None
        Labels of the records and of the validation records in the windows' names
        (default: the file stems, or "record k").
    try_pairs : bool
        Try pairs of the top effect with the next ones when it alone leaves a gap.
    steps : int
        Effects named at most per axis (``sequence.following``), fewer when the model
        with the named ones reaches the null level.
    axis : str
        "lateral", "longitudinal", or "both" (default; "auto" is the same): each axis the
        records excite, each with its own verdict; an axis they do not excite is listed in
        ``undiagnosed`` with the reason.
    refine : bool
        Refit the top named airframe effect with the JSBSim aircraft flown on the
        longest record (``gap.jsbsim.refine``; 10-30 s more): its values are then the ones
        ``write_aircraft`` writes.
    surfaces : str or None
        What the records' surface channels hold, "position" or "command" (None: their
        ``meta.extra["surfaces"]``, default "position"); commands are passed through the
        aircraft's own actuators first (``model.surfaces.actuated``), and the
        actuator lags are candidates too.

    Returns
    -------
    GapResult
        The verdict (``no_gap``, ``explained``, ``partly_unexplained``, ``unexplained``;
        the worst axis), the gap map, the ranked effects with their parameters in
        catalogue units, the named ones and the held-out shrink; ``axes()`` per axis.
    """
    records, found = _records(records)
    names = names or found
    if validate is not None:
        validate, found_val = _records(validate)
        validate_names = validate_names or [f"validate {n}" for n in found_val]
    if not records:
        raise ValueError("gap: no record to diagnose")
    _one_aircraft([*records, *(validate or [])], aircraft)
    # the trim-level check, on the surface channels as recorded (commands or positions)
    offsets, trim_note = trim_offsets(records, aircraft)
    # records of commands: through the aircraft's own actuators (lag, rate limit) first
    records = actuated(records, aircraft, surfaces)
    validate = actuated(validate, aircraft, surfaces) if validate is not None else None
    excited = excited_axes(records)
    if axis in ("both", "auto"):
        axes = excited or ["lateral"]
    elif axis in AXIS_NAMES:
        axes = [axis]
    else:
        raise ValueError(f"gap: axis must be both, {', '.join(AXIS_NAMES)}; got {axis!r}")
    lines = {a: spectral_line(records, a) for a in axes}  # named: the others run without it
    results = {a: with_line(_with_trim(_diagnose_axis(
        a, without_line(records, lines[a]), aircraft, without_line(validate, lines[a]), names,
        validate_names, try_pairs, steps, surfaces), [o for o in offsets if o.axis == a],
        trim_note), lines[a]) for a in axes}
    result = next(iter(results.values())) if len(results) == 1 else _merged(results)
    result.undiagnosed = {
        a: (f"not asked for (--axis {axis})" if a in excited else
            f"the records do not excite it (no {', '.join(AXIS_INPUTS[a])} maneuver)")
        for a in AXIS_NAMES if a not in axes}
    if refine:
        try:
            result.refined = refit(result, records)
        except NotRefined as exc:
            result.refine_note = f"not refined: {exc}"
    return result


def _with_trim(result: GapResult, offsets: list[TrimOffset], note: str) -> GapResult:
    """``result`` with its axis's trim-level check: an offset named makes an axis at the
    null level ``explained`` (the constant the window fits absorb is named at trim)."""
    result.trim, result.trim_note = offsets, note
    if result.verdict == NO_GAP and any(o.named for o in offsets):
        result.verdict = EXPLAINED
    return result


def _one_aircraft(records: list[FlightRecord], aircraft: str) -> None:
    """Refuse records that say they come from different aircraft."""
    said = {r.meta.aircraft for r in records if r.meta.aircraft}
    if len(said) > 1:
        raise ValueError(f"gap: the records come from different aircraft "
                         f"({', '.join(sorted(said))}); diagnose one aircraft's records "
                         f"against --model {aircraft} at a time")


def _diagnose_axis(axis: str, records: list[FlightRecord], aircraft: str,
                   validate: list[FlightRecord] | None, names: Sequence[str] | None,
                   validate_names: Sequence[str] | None, try_pairs: bool,
                   steps: int, surfaces: str | None = None) -> GapResult:
    inputs = AXIS_INPUTS[axis]
    lin = linearise(aircraft, records, axis, surfaces)
    fit_windows = segments(records, list(names) if names else None, inputs)
    if not fit_windows:
        raise ValueError(f"gap: the records have no {axis} maneuver window "
                         f"(inputs {', '.join(inputs)})")
    val = segments(list(validate), list(validate_names) if validate_names else
                   [f"validate {k + 1}" for k in range(len(validate))], inputs
                   ) if validate else None
    evidence = "validation records" if val else "held-out maneuvers"
    if not val and len(fit_windows) == 1 and len(halves := split(fit_windows[0])) == 2:
        fit_windows, evidence = halves, "time split"
    folds = Folds.make(fit_windows, val)
    ranker = Ranker(lin, folds)
    where = gap_map(ranker.base | {k: v for k, v in ranker.base_held.items()
                                   if k not in ranker.base},
                    records={s.label: s.record for s in [*fit_windows, *(val or [])]})
    windows = {"fit": [s.label for s in fit_windows],
               "held_out": sorted({w for _, t in folds.folds for w in (s.label for s in t)})}
    before = null_test(ranker.base, _by_label(fit_windows), inputs)
    # an accelerometer lag or delay, or a gyro's scale, seen in a relation between measured
    # channels (the output-error fit loses them in the gusts or takes them for the
    # aerodynamics): named first, the other tests on the record with it undone
    found = next((f for f in (sensor_lag(ranker.base, _by_label(fit_windows), inputs, axis),
                              gyro_scale(_by_label(fit_windows), axis))
                  if f is not None and f.found), None)
    structure = nonlinear_test(undone(ranker.base, found) if found else ranker.base,
                               _by_label(fit_windows), inputs, axis)
    unseen = not_identifiable(lin.model, records, surfaces=lin.surfaces)
    if not before.gap and found is None:  # at the null level of the linear test
        return GapResult(str(aircraft), lin, where, [], [], [], windows, floor=ranker.floor,
                         verdict=UNEXPLAINED if structure.gap else NO_GAP,
                         null_before=before, evidence=evidence, not_identifiable=unseen,
                         structure=structure)
    ranker.above = before.above()
    named: list[Ranked] = []
    if found is not None:
        samples = sum(f.samples for f in ranker.base.values())
        ranked = [ranker.held_at(*found.candidate(),
                                 -found.test.statistic + math.log(max(samples, 2)))]
        ranked[0].confirmed, ranked[0].note, both = True, found.note, []
    else:
        ranked, both = judged_ranking(ranker, catalogue_candidates(
            lin.model, lin.axes, surfaces=lin.surfaces), try_pairs)
    if both and both[0].confirmed:
        named = [both[0]]
    elif ranked and ranked[0].confirmed:
        named = [ranked[0]]

    def tested(current: Linearised) -> NullTest:
        return null_test({s.label: fit(current.model, s.record) for s in fit_windows},
                         _by_label(fit_windows), inputs)

    after = None
    if named and is_linkage(named[0].candidate):  # on the surface, not in the model
        after = _linkage_tested(lin, named[0], fit_windows, inputs)
    elif named:
        tests: dict[int, tuple[Linearised, NullTest]] = {}  # the model kept: its id stays

        def cached(current: Linearised) -> NullTest:
            if id(current) not in tests:
                tests[id(current)] = (current, tested(current))
            return tests[id(current)][1]

        named += following(lin, folds, named[0], steps - 1,
                           at_null=lambda current: not cached(current).gap,
                           above=lambda current: cached(current).above())
        corrected = lin
        for effect in named:
            corrected = fixed(corrected, effect)
        after = tested(corrected)
    for effect in named:
        effect.equivalent = class_text(effect, lin.model.start)
    verdict = axis_verdict(before, bool(named), after)
    if found is not None and verdict == NO_GAP:  # named from the relation alone
        verdict = EXPLAINED
    structure.sensor = named_sensor(structure, named)
    if structure.gap or structure.sensor:  # a structure no catalogue effect expresses
        verdict = PARTLY if named else UNEXPLAINED
    return GapResult(str(aircraft), lin, where, ranked, both, named, windows,
                     floor=ranker.floor, verdict=verdict,
                     null_before=before, null_after=after, evidence=evidence,
                     not_identifiable=unseen, structure=structure)


def _linkage_tested(lin: Linearised, effect: Ranked, windows: list[Segment],
                    inputs: Sequence[str]) -> NullTest:
    """The null test of the model as is on ``windows`` with the surface passed through the
    named nonlinear actuator ``effect`` at its fitted value (``candidates.linkage``)."""
    c = effect.candidate
    (name,) = c.free
    records = {s.label: transformed(s.record, c.entry, c.options["surface"],
                                    effect.values[name]) for s in windows}
    return null_test({k: fit(lin.model, r) for k, r in records.items()}, records, inputs)


def _by_label(windows: list[Segment]) -> dict[str, FlightRecord]:
    return {s.label: s.record for s in windows}


def _merged(results: dict[str, GapResult]) -> GapResult:
    """One result of several axes: the axis with the strongest named effect (lowest delta
    BIC; the first axis when none is named) gives the model, ``named`` and ``pairs``."""
    named = [g for g in results.values() if g.named]
    main = (min(named, key=lambda g: g.named[0].delta_bic) if named
            else next(iter(results.values())))
    where = GapMap(main.where.bands, [row for g in results.values() for row in g.where.rows],
                   [row for g in results.values() for row in g.where.regimes])
    effects = sorted((r for g in results.values() for r in g.effects),
                     key=rank_key)
    windows = {k: list(dict.fromkeys(w for g in results.values() for w in g.windows[k]))
               for k in ("fit", "held_out")}
    return GapResult(main.aircraft, main.linearised, where, effects, main.pairs, main.named,
                     windows, dict(results), main.floor,
                     verdict=worst([g.verdict for g in results.values()]),
                     null_before=main.null_before, null_after=main.null_after,
                     evidence=main.evidence)


def injected(records: Sequence[FlightRecord]) -> list[str]:
    """The airframe and actuator effects a simulated record's card injected (its
    metadata's ``[[effect]]``), as "name(option=value, ...)" with a derivative delta's
    axes always said (the catalogue's default is stability axes; the lateral diagnosis
    fits body axes); [] for a real record.

    Parameters
    ----------
    records : sequence of FlightRecord
        The records.

    Returns
    -------
    list of str
    """
    out: list[str] = []
    for r in records:
        card = (r.meta.scenario or {}).get("card") or {}
        for e in card.get("effect", []) or []:
            e = dict(e)
            name = e.pop("name", "?")
            if name == "derivative_delta":  # the catalogue's default axes, said
                e.setdefault("axes", "stability")
            out.append(f"{name}(" + ", ".join(f"{k}={v}" for k, v in e.items()) + ")")
    return list(dict.fromkeys(out))
