"""How visible each catalogue entry of the blind check is, measured without the diagnosis:
per aircraft and entry, the energy the effect adds to its axis's outputs on the exact JSBSim
aircraft (the case flown in calm air, less the plain aircraft flown in calm air with the
same seed: the same sensor noise), against the energy light turbulence adds (the plain
aircraft in light turbulence less calm), both over the card's 64 s with the means removed,
averaged over the axis's outputs (beta, p, r, ay / alpha, q, az) (docs/gap_benchmark.md,
the rules for the seed-8 run).

    .venv/bin/python benchmarks/gap_visibility.py --k 1.0 -o study/visibility.jsonl

Each entry is flown at ``k`` times its drawn base (``cases.K_RANGE`` pinned to k, derivative
deltas at the middle of ``cases.DELTA_FRACTION``), every option of its row; the base is the
one the draw uses, sizing by visibility included (``cases.size_multiple``), or with
``--unsized`` the bases it starts from (the files of seeds 11 and 12 it was measured on).
The check of that sizing, on a seed it was not measured on, at k = 1 and at the largest
draw (k = 1.5: a departure or a failed trim is listed as an error):

    E=backlash,cg_offset,control_effectiveness,deadband,delay,engine_vibration,\
inertia_scale,lag,misalignment,scale,tail_ice,thrust_moment
    .venv/bin/python benchmarks/gap_visibility.py --seed 13 --k 1.0 --entries $E \
        -o benchmarks/results/gap_visibility/k1_seed13_sized.jsonl
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from gap_leads import ranker_of
from threadpoolctl import threadpool_limits

from flightid.scenarios.gap_benchmark import cases as drawn
from flightid.scenarios.gap_benchmark.cases import AIRCRAFT, KINDS, Case, _effect
from flightid.scenarios.gap_benchmark.run import fly_case, truths

OUTPUTS = {"lateral": ("beta", "p", "r", "ay"), "longitudinal": ("alpha", "q", "az")}


def energy(a, b, channel: str) -> float:
    """Energy (mean removed) of ``a - b`` on ``channel``, on ``a``'s time base."""
    d = np.asarray(a[channel]) - np.interp(a.time, b.time, b[channel])
    return float(np.sum((d - d.mean()) ** 2))


def visibility(case: Case, axis: str, calm, light, truth) -> float:
    """Mean over the axis's outputs of the effect's energy over the turbulence's."""
    rec = fly_case(case, "calm", truth)
    ratios = [energy(rec, calm, c) / energy(light, calm, c) for c in OUTPUTS[axis]
              if c in rec and c in calm]
    return float(np.mean(ratios))


def test_shares(record, aircraft: str, axis: str) -> dict[str, float]:
    """The main window test's share per tested channel of ``axis`` (input-explained energy
    less chance, over the measured energy; ``verdict.ChannelTest.share``) on ``record``,
    as the diagnosis's null test computes it; the slow channels (high band only) left out."""
    _, before, _, _ = ranker_of(record, aircraft, axis)
    return {ch: float(t.share) for ch, t in before.channels.items() if not t.slow}


def share_added(case: Case, axis: str, plain: dict[str, float], truth) -> float:
    """The largest share the effect adds over the plain flight's on a tested channel of
    ``axis``, both in light turbulence with the same seed."""
    shares = test_shares(fly_case(case, "light", truth), case.aircraft, axis)
    return max(v - plain.get(ch, 0.0) for ch, v in shares.items())


def turbulence_share(calm, light) -> dict[str, dict[str, float]]:
    """Per axis and output, the energy light turbulence adds (light less calm) over the light
    flight's own energy, means removed: how much of a measured record is turbulence."""
    def own(c: str) -> float:
        x = np.asarray(light[c])
        return float(np.sum((x - x.mean()) ** 2))
    return {ax: {c: energy(light, calm, c) / own(c) for c in chans}
            for ax, chans in OUTPUTS.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--k", type=float, default=1.0)
    ap.add_argument("--entries", default="")
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--unsized", action="store_true",
                    help="the bases before sizing by visibility (cases.VISIBILITY emptied)")
    ap.add_argument("--test-share", action="store_true",
                    help="the window test's share the effect adds (light turbulence), "
                         "not the energy over turbulence's")
    ap.add_argument("--shares", action="store_true",
                    help="only the plain aircraft's turbulence share of the measured energy")
    ap.add_argument("-o", "--output", type=Path, required=True)
    a = ap.parse_args()
    if a.unsized:
        drawn.VISIBILITY = {}
    drawn.K_RANGE = (a.k, a.k)
    mid = 0.5 * sum(drawn.DELTA_FRACTION)
    drawn.DELTA_FRACTION = (mid, mid)
    t = truths()
    want = set(a.entries.split(",")) - {""}
    with threadpool_limits(1), open(a.output, "a") as f:
        for name in AIRCRAFT:
            plain = Case(0, a.seed, name, "null")
            calm, light = fly_case(plain, "calm", t[name]), fly_case(plain, "light", t[name])
            plain_shares = {ax: test_shares(light, name, ax) for ax in OUTPUTS} \
                if a.test_share else {}
            if a.shares:
                f.write(json.dumps({"aircraft": name, "seed": a.seed,
                                    "turbulence_share": turbulence_share(calm, light)}) + "\n")
                continue
            for kind in KINDS:
                if want and kind.entry not in want:
                    continue
                options = [dict(zip(kind.choices, vals, strict=True)) for vals in
                           np.array(np.meshgrid(*kind.choices.values())).T.reshape(
                               -1, len(kind.choices))] if kind.choices else [{}]
                for opts in options:
                    for which in (kind.sized if kind.one_of else (None,)):
                        rng = np.random.default_rng(0)
                        e = _effect(kind, rng, name, t[name])
                        e.options.update({k: str(v) for k, v in opts.items()})
                        if which is not None:
                            base = drawn.SIZED_BASE.get(kind.entry)
                            e.magnitude.clear()
                            k = a.k * drawn.size_multiple(kind.name, name)
                            e.magnitude[which] = drawn._scaled(kind.entry, which, k, base)
                        case = Case(1, a.seed, name, "single", (e,))
                        axes = ("lateral", "longitudinal") if kind.axis == "both" \
                            else (kind.axis,)
                        t0 = time.process_time()
                        try:
                            vis = {ax: share_added(case, ax, plain_shares[ax], t[name])
                                   if a.test_share else
                                   visibility(case, ax, calm, light, t[name]) for ax in axes}
                        except Exception as exc:  # noqa: BLE001  (a departure: listed)
                            vis = {"error": f"{type(exc).__name__}: {exc}"}
                        f.write(json.dumps({"aircraft": name, "kind": kind.name,
                                            "label": e.label, "k": a.k, "visibility": vis,
                                            "cpu": time.process_time() - t0}) + "\n")
                        f.flush()


if __name__ == "__main__":
    main()
