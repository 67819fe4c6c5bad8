"""Leads for the next rules of the gap blind check, measured on development cases re-flown
from their seeds (docs/gap_benchmark.md, "Leads for the seed-10 rules" and "Leads for the
seed-11 rules"). Changes no rule.

``backlash``: for each case (a lateral backlash), the play's own signal on the axis's outputs
(the case flown in calm air less the plain aircraft in calm air, same seed) against light
turbulence's (the plain aircraft light less calm), its spectrum against the window test's
high-pass corner and high band, how much of it the test's input regressors explain, the
window test's shares on the light record with and without the play, and the backlash
candidate evaluated as the ranking would (on the record with the play and without).

``ranking``: for each case, the listed candidates (and the inertia scale) screened and
evaluated in full on the light record: screening rank, delta BIC, held-out cost change and
gain against the confirmation level, the fitted value, and whether the held-out data tell
each from the inertia scale (``rank.tied``); beside them the top of the ranking.

``detect``: for each case (a single), the effect's visibility per channel of its axis (its
energy in calm air, less the plain aircraft's, over light turbulence's, as ``backlash``),
the window test per channel on the light record with the effect and on the same flight
without it, and the injected entry's own candidate evaluated in full on the light record
(held-out gain against the confirmation level). ``--grow g``: a sensor scale's offset
from 1 times g (the case otherwise as drawn).

    E="control_effectiveness(de);derivative_delta(Cm_de,stability);actuator_lag(de)"
    .venv/bin/python benchmarks/gap_leads.py backlash --seed 9 \
        --cases 1,27,32,112,114,121,131,148 -o benchmarks/results/gap_leads/backlash_seed9.jsonl
    .venv/bin/python benchmarks/gap_leads.py ranking --seed 9 --cases 0,12,58,79,102,126,137,138 \
        --labels "$E;tail_ice();rate_limit(dr)" -o benchmarks/results/gap_leads/inertia_seed9.jsonl
    .venv/bin/python benchmarks/gap_leads.py ranking --seed 9 --cases 38,42,62,99,132 \
        --labels "scale(q);scale(az)" -o benchmarks/results/gap_leads/scale_seed9.jsonl
    S0=4,19,24,29,30,35,38,39,45,47,52,56,58,67,72,88,95,111,115,120,124,125,134,141,142
    S10=0,1,6,11,12,22,23,35,36,37,38,39,41,44,51,59,64,67,71,73,79,86,90,96,97,105,112
    S10=$S10,119,123,124,129,132,134,135,139,145,147
    .venv/bin/python benchmarks/gap_leads.py detect --seed 0 --cases $S0 \
        -o benchmarks/results/gap_leads/detect_seed0.jsonl
    .venv/bin/python benchmarks/gap_leads.py detect --seed 10 --cases $S10 \
        -o benchmarks/results/gap_leads/detect_seed10.jsonl
    for g in 1.5 2; do
      .venv/bin/python benchmarks/gap_leads.py detect --seed 0 --cases 67,111,134 --grow $g \
          -o benchmarks/results/gap_leads/detect_scale_grown_seed0.jsonl
      .venv/bin/python benchmarks/gap_leads.py detect --seed 10 --cases 39,41,79,96,124,134 \
          --grow $g -o benchmarks/results/gap_leads/detect_scale_grown_seed10.jsonl
    done
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.gap.candidates.build import catalogue_candidates
from flightid.identification.gap.candidates.linkage import is_linkage, linkage
from flightid.identification.gap.model.linearise import linearise
from flightid.identification.gap.model.surfaces import actuated
from flightid.identification.gap.nonlinearity import play
from flightid.identification.gap.rank import (
    MIN_EXCESS_SHRINK,
    SCREEN_KEEP,
    UNSCREENED,
    Folds,
    Ranker,
    rank,
    tied,
)
from flightid.identification.gap.ranked import mean_gap
from flightid.identification.gap.segments import segments
from flightid.identification.gap.verdict import null_test
from flightid.identification.gap.window.regressors import (
    HIGHPASS_RAD_S,
    highpass,
    independent_columns,
    regressors,
    unit_columns,
)
from flightid.scenarios.gap_benchmark.cases import draw
from flightid.scenarios.gap_benchmark.run import fly_case, truths

LATERAL = ("beta", "p", "r", "ay")


def axis_of(effect) -> str:
    """The axis an effect is diagnosed on (a surface's, else the entry's)."""
    surface = effect.options.get("surface")
    if surface:
        return "longitudinal" if surface == "de" else "lateral"
    return "longitudinal" if effect.axis == "both" else effect.axis


def ranker_of(record, aircraft: str, axis: str):
    """The diagnosis's ranker on ``record``'s windows, its null test and windows."""
    records = actuated([record], aircraft, None)
    inputs = AXIS_INPUTS[axis]
    lin = linearise(aircraft, records, axis, None)
    windows = segments(records, None, inputs)
    ranker = Ranker(lin, Folds.make(windows, None))
    before = null_test(ranker.base, {s.label: s.record for s in windows}, inputs)
    ranker.above = before.above()
    return ranker, before, windows, lin


def figures(ranker: Ranker, r) -> dict:
    """A ranked candidate's figures: evidence, held-out gain against the confirmation
    level, value, confirmation."""
    gain = (mean_gap(r.heldout_before) - mean_gap(r.heldout_after)
            if r.heldout_after else math.nan)
    return {"free": len(r.candidate.free), "values": r.values, "delta_bic": r.delta_bic,
            "heldout_cost_change": r.heldout_cost_change, "gain": gain,
            "level": MIN_EXCESS_SHRINK * mean_gap(ranker.above) if ranker.above else None,
            "heldout_changes": r.heldout_changes, "confirmed": bool(r.confirmed),
            "note": r.note}


def band_shares(d: np.ndarray, dt: float) -> dict[str, float]:
    """Shares of ``d``'s energy (mean removed) below the window test's high-pass corner,
    between it and 1 Hz, and above 1 Hz (the high band)."""
    f = np.fft.rfftfreq(len(d), dt)
    power = np.abs(np.fft.rfft(d - d.mean())) ** 2
    corner, total = HIGHPASS_RAD_S / (2 * math.pi), float(power[1:].sum())
    return {"below_corner": float(power[1:][f[1:] < corner].sum()) / total,
            "corner_to_1hz": float(power[(f >= corner) & (f < 1.0)].sum()) / total,
            "above_1hz": float(power[f >= 1.0].sum()) / total}


def linear_part(play_signal, calm, fits, recs, inputs, channel: str, dt: float):
    """The play's high-passed signal on the test's windows: its energy over the channel's
    measured energy, and the fraction of it the input regressors explain."""
    dd, xx, spread = [], [], 0.0
    for label, f in fits.items():
        d = np.interp(f.time, calm.time, play_signal)
        dd.append(highpass(d, dt))
        xx.append(highpass(regressors(f, recs[label], inputs), dt))
        spread += float(np.sum((f.measured[channel] - f.measured[channel].mean()) ** 2))
    d, x = np.concatenate(dd), independent_columns(unit_columns(np.vstack(xx)))
    theta, *_ = np.linalg.lstsq(x, d, rcond=None)
    return float(np.sum(d ** 2)) / spread, float(np.sum((x @ theta) ** 2) / np.sum(d ** 2))


def backlash_row(case, truth) -> dict:
    """The backlash measurement of one case (module docstring)."""
    e = case.effects[0]
    surface, plain = e.options["surface"], replace(case, category="null", effects=())
    light, calm = fly_case(case, "light", truth), fly_case(case, "calm", truth)
    plain_light, plain_calm = fly_case(plain, "light", truth), fly_case(plain, "calm", truth)
    dt = float(np.median(np.diff(calm.time)))
    u = np.asarray(plain_calm[surface])
    err = play(u, e.magnitude["width"]) - u
    row = {"index": case.index, "aircraft": case.aircraft, "surface": surface,
           "width_deg": math.degrees(e.magnitude["width"]),
           "surface_std_deg": math.degrees(float(np.std(u))),
           "surface_gain": 1 + float(err @ (u - u.mean()) / np.sum((u - u.mean()) ** 2)),
           "channels": {}}
    ranker, _, windows, _ = ranker_of(light, case.aircraft, "lateral")
    fits, recs = ranker.base, {s.label: s.record for s in windows}
    for ch in LATERAL:
        d, gust = effect_and_gust(ch, calm, plain_calm, plain_light)
        over, linear = linear_part(d, calm, fits, recs, AXIS_INPUTS["lateral"], ch, dt)
        row["channels"][ch] = {
            "visibility": visibility(d, gust),
            "visibility_highpassed": float(np.sum(highpass(d, dt) ** 2)
                                           / np.sum(highpass(gust, dt) ** 2)),
            "bands": band_shares(d, dt), "highpassed_over_measured": over,
            "linear_fraction": linear}
    for tag, rec in (("with_play", light), ("without", plain_light)):
        ranker, before, _, _ = ranker_of(rec, case.aircraft, "lateral")
        row[tag] = {"gap": before.gap, "test": {
            ch: window_figures(t) for ch, t in before.channels.items()}}
        found = ranker.evaluate_linkage(linkage("backlash", surface))
        row[tag]["backlash_candidate"] = None if found is None else figures(ranker, found)
    return row


def ranking_row(case, truth, labels: list[str]) -> dict:
    """The ranking measurement of one case (module docstring)."""
    axis = axis_of(case.effects[0])
    ranker, before, windows, lin = ranker_of(fly_case(case, "light", truth), case.aircraft, axis)
    cands = catalogue_candidates(lin.model, lin.axes, surfaces=lin.surfaces)
    screened = [c for c in cands if not is_linkage(c) and c.entry not in UNSCREENED]
    scores = {c.label: ranker.screen(c) for c in screened}
    order = sorted(scores, key=scores.__getitem__)
    full = {}
    for c in cands:
        if c.label in labels or c.entry == "inertia_scale":
            r = ranker.evaluate_linkage(c) if is_linkage(c) else ranker.evaluate(c)
            if r is not None:
                full[c.label] = r
    inertia = next((r for k, r in full.items() if k.startswith("inertia_scale")), None)
    out = {"index": case.index, "aircraft": case.aircraft, "label": case.effects[0].label,
           "axis": axis, "windows": len(windows), "gap_channels": before.gap_channels(),
           "screened": len(screened), "screen_keep": SCREEN_KEEP, "candidates": {}}
    for k, r in full.items():
        out["candidates"][k] = {
            "screen_rank": order.index(k) + 1 if k in order else None,
            "screen_delta_bic": scores.get(k), **figures(ranker, r),
            "tied_with_inertia_scale": (tied(r, inertia) if inertia is not None
                                        and r is not inertia else None)}
    out["ranking_top"] = [(r.candidate.label, bool(r.confirmed), r.heldout_cost_change)
                          for r in rank(ranker, cands)[:3]]
    return out


def window_figures(t) -> dict:
    """One channel's window test: p-values and shares of the main, plain (without the other
    outputs' residuals) and high-band tests."""
    return {"p": t.p_value, "share": t.share,
            "plain_p": t.plain.p_value if t.plain else None,
            "plain_share": t.plain.share if t.plain else None,
            "high_p": t.high.p_value if t.high else None,
            "high_share": t.high.explained if t.high else None}


def tests_of(before) -> dict:
    """The window test's figures per channel (``window_figures``) and the gap above null."""
    return {ch: {**window_figures(t), "above_null": t.level, "gap": t.gap}
            for ch, t in before.channels.items()}


def effect_and_gust(ch: str, calm, plain_calm, plain_light) -> tuple[np.ndarray, np.ndarray]:
    """A channel's effect signal (the case in calm air less the plain aircraft in calm air)
    and light turbulence's (the plain aircraft in light turbulence less calm air)."""
    d = np.asarray(calm[ch]) - np.interp(calm.time, plain_calm.time, plain_calm[ch])
    gust = (np.asarray(plain_light[ch])
            - np.interp(plain_light.time, plain_calm.time, plain_calm[ch]))
    return d, gust


def visibility(d: np.ndarray, gust: np.ndarray) -> float:
    """The effect's energy over turbulence's, each about its mean."""
    return float(np.sum((d - d.mean()) ** 2) / np.sum((gust - gust.mean()) ** 2))


def detect_row(case, truth) -> dict:
    """The detection measurement of one case (module docstring)."""
    e = case.effects[0]
    axis, plain = axis_of(e), replace(case, category="null", effects=())
    light, calm = fly_case(case, "light", truth), fly_case(case, "calm", truth)
    plain_light, plain_calm = fly_case(plain, "light", truth), fly_case(plain, "calm", truth)
    ranker, before, _, lin = ranker_of(light, case.aircraft, axis)
    _, without, _, _ = ranker_of(plain_light, case.aircraft, axis)
    row = {"index": case.index, "aircraft": case.aircraft, "label": e.label, "axis": axis,
           "visibility": {}, "with_effect": tests_of(before), "without": tests_of(without)}
    for ch in before.channels:
        row["visibility"][ch] = visibility(*effect_and_gust(ch, calm, plain_calm, plain_light))
    want = e.label.split(" ")[0]
    cands = catalogue_candidates(lin.model, lin.axes, surfaces=lin.surfaces)
    found = next((c for c in cands if c.label == want), None)
    if found is not None:
        r = ranker.evaluate_linkage(found) if is_linkage(found) else ranker.evaluate(found)
        row["true_candidate"] = None if r is None else figures(ranker, r)
    return row


def grown(case, times: float):
    """``case`` (a sensor scale single) with its factor's offset from 1 times ``times``."""
    e = case.effects[0]
    if e.entry != "scale":
        raise SystemExit(f"--grow: case {case.index} is {e.entry}, not a sensor scale")
    factor = 1.0 + (e.magnitude["factor"] - 1.0) * times
    return replace(case, effects=(replace(e, magnitude={"factor": factor}),))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("part", choices=("backlash", "ranking", "detect"))
    ap.add_argument("--seed", type=int, required=True, help="a development seed (0-10)")
    ap.add_argument("--cases", required=True, help="case indices, comma-separated")
    ap.add_argument("--labels", default="", help="candidate labels, ';'-separated")
    ap.add_argument("--grow", type=float, default=1.0,
                    help="detect: a sensor scale's offset from 1 times this")
    ap.add_argument("-o", "--output", type=Path, required=True)
    a = ap.parse_args()
    idx = [int(k) for k in a.cases.split(",")]
    t = truths()
    drawn = {c.index: c for c in draw(max(idx) + 1, a.seed, t, 0)}
    a.output.parent.mkdir(parents=True, exist_ok=True)
    with threadpool_limits(1), open(a.output, "a") as f:
        for k in idx:
            case = drawn[k] if a.grow == 1.0 else grown(drawn[k], a.grow)
            row = (backlash_row(case, t[case.aircraft]) if a.part == "backlash" else
                   detect_row(case, t[case.aircraft]) if a.part == "detect" else
                   ranking_row(case, t[case.aircraft], a.labels.split(";")))
            f.write(json.dumps({"seed": a.seed, **row}, default=float) + "\n")
            f.flush()


if __name__ == "__main__":
    main()
