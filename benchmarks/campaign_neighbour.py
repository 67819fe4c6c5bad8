"""Iterations and CPU seconds of a campaign point started from its nearest flown neighbour.

A/B of the campaign field ``start`` on test points of the 20-point campaign of
``campaign_speed.py`` (twinotter-id maneuvers, 6-DOF output error with the propulsive
moments). The anchors (``scenarios.campaign.neighbour.anchors``) the chosen points start
from are flown first with the method's start; then each chosen point runs
``scenarios.campaign.point.run_point`` with ``start = "method"`` (equation error's start
values) and ``run_point_from`` with ``start = "neighbour"`` (the nearest anchor's
estimates), in both orders (A B, then B A over all the points). Kept per point: the
Gauss-Newton iterations of the fit and the CPU seconds (``time.process_time``: the
flight, the data reduction and the fit); the estimates of both starts are compared in
their standard errors. Writes benchmarks/results/campaign_neighbour.txt and .json.

    .venv/bin/python benchmarks/campaign_neighbour.py [--points 1 5 9 13 17 19]
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import time
from pathlib import Path

import pandas as pd
from campaign_speed import card

from flightid.scenarios.campaign import neighbour
from flightid.scenarios.campaign.card import campaign_from_dict
from flightid.scenarios.campaign.point import run_point, run_point_from

RESULTS = Path(__file__).resolve().parent / "results"
STARTS = ("method", "neighbour")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, nargs="+", default=[1, 5, 9, 13, 17, 19])
    args = ap.parse_args()
    base = campaign_from_dict(card("oe6dof"), "bench-20")
    runs = {s: dataclasses.replace(base, start=s) for s in STARTS}
    anchors = neighbour.anchors(base)
    if set(args.points) & set(anchors):
        raise SystemExit(f"--points must leave out the anchors {anchors}")
    needed = sorted({neighbour.nearest(base, i, anchors) for i in args.points})
    anchor_rows = pd.DataFrame([r for j in needed for r in run_point(base, j)])
    starts = neighbour.neighbour_starts(base, anchor_rows, args.points)
    cpu: dict[str, dict[int, list[float]]] = {s: {i: [] for i in args.points} for s in STARTS}
    iterations: dict[str, dict[int, float]] = {s: {} for s in STARTS}
    worst: dict[int, float] = {}
    for order in (STARTS, STARTS[::-1]):
        for i in args.points:
            rows = {}
            for start in order:
                t = time.process_time()
                rows[start] = (run_point(runs[start], i) if start == "method"
                               else run_point_from(starts, runs[start], i))
                cpu[start][i].append(time.process_time() - t)
                iterations[start][i] = rows[start][0]["iterations"]
            ref = {r["name"]: r for r in rows["method"] if r["status"] == "estimated"}
            worst[i] = max(abs(r["estimate"] - ref[r["name"]]["estimate"]) / ref[r["name"]]["std"]
                           for r in rows["neighbour"] if r["name"] in ref)
    mean = {s: sum(sum(v) for v in cpu[s].values()) / sum(len(v) for v in cpu[s].values())
            for s in STARTS}
    out = {"date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
           "points": args.points, "neighbours": {str(i): starts[i][0] for i in args.points},
           "cpu_s": {s: {str(i): [round(x, 2) for x in v] for i, v in cpu[s].items()}
                     for s in STARTS},
           "iterations": {s: {str(i): v for i, v in iterations[s].items()} for s in STARTS},
           "mean_cpu_s": {s: round(v, 2) for s, v in mean.items()},
           "neighbour_over_method": round(mean["neighbour"] / mean["method"], 3),
           "max_difference_in_std": max(worst.values()),
           "load_average_after": [round(x, 2) for x in os.getloadavg()],
           "machine": platform.machine(), "python": platform.python_version()}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "campaign_neighbour.json").write_text(json.dumps(out, indent=2) + "\n")
    lines = [f"campaign neighbour start A/B (bench-20 points {args.points}, oe6dof), "
             f"{out['date']}",
             f"python {out['python']}, {out['machine']}; shared machine, load average after "
             f"the run {out['load_average_after']}",
             "point  from  iterations method neighbour  method s (A B, B A)  "
             "neighbour s (A B, B A)  neighbour/method  largest difference (std)"]
    for i in args.points:
        a, b = cpu["method"][i], cpu["neighbour"][i]
        lines.append(f"{i:5d}  {starts[i][0]:4d}  {iterations['method'][i]:10.0f} "
                     f"{iterations['neighbour'][i]:9.0f}  {a[0]:8.2f} {a[1]:6.2f}       "
                     f"{b[0]:8.2f} {b[1]:6.2f}          {sum(b) / sum(a):.2f}"
                     f"              {worst[i]:.1e}")
    total = {s: sum(iterations[s].values()) for s in STARTS}
    lines += [f"iterations over the points: method {total['method']:.0f}, neighbour "
              f"{total['neighbour']:.0f}",
              f"mean CPU per point: method {mean['method']:.2f} s, neighbour "
              f"{mean['neighbour']:.2f} s, neighbour/method {out['neighbour_over_method']}",
              f"largest estimate difference: {out['max_difference_in_std']:.1e} standard errors"]
    (RESULTS / "campaign_neighbour.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
