"""CPU seconds of a campaign point started from equation error or from the model's tables.

A/B of the campaign field ``start`` on test points of the 20-point campaign of
``campaign_speed.py`` (twinotter-id maneuvers, 6-DOF output error with the propulsive
moments): each point runs ``scenarios.campaign.point.run_point`` twice in this process,
with ``start = "method"`` (equation error's start values) and ``start = "model"`` (the
model aircraft's derivatives at the point), in both orders (A B, then B A over all the
points), and the CPU seconds of each (``time.process_time``: the flight, the data
reduction and the fit) are kept. The estimates of both are compared in their standard
errors. Writes benchmarks/results/campaign_start.txt and .json.

    .venv/bin/python benchmarks/campaign_start.py [--points 0 3 5 8 11 14 17 19]
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

from campaign_speed import card

from flightid.scenarios.campaign.card import campaign_from_dict
from flightid.scenarios.campaign.point import run_point

RESULTS = Path(__file__).resolve().parent / "results"
STARTS = ("method", "model")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, nargs="+", default=[0, 3, 5, 8, 11, 14, 17, 19])
    args = ap.parse_args()
    base = campaign_from_dict(card("oe6dof"), "bench-20")
    cpu: dict[str, dict[int, list[float]]] = {s: {i: [] for i in args.points} for s in STARTS}
    worst = {}
    for order in (STARTS, STARTS[::-1]):
        for i in args.points:
            rows = {}
            for start in order:
                t = time.process_time()
                rows[start] = run_point(dataclasses.replace(base, start=start), i)
                cpu[start][i].append(time.process_time() - t)
            ref = {r["name"]: r for r in rows["method"] if r["status"] == "estimated"}
            worst[i] = max(abs(r["estimate"] - ref[r["name"]]["estimate"]) / ref[r["name"]]["std"]
                           for r in rows["model"] if r["name"] in ref)
    mean = {s: sum(sum(v) for v in cpu[s].values()) / sum(len(v) for v in cpu[s].values())
            for s in STARTS}
    out = {"date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
           "points": args.points,
           "cpu_s": {s: {str(i): [round(x, 2) for x in v] for i, v in cpu[s].items()}
                     for s in STARTS},
           "mean_cpu_s": {s: round(v, 2) for s, v in mean.items()},
           "model_over_method": round(mean["model"] / mean["method"], 3),
           "max_difference_in_std": max(worst.values()),
           "load_average_after": [round(x, 2) for x in os.getloadavg()],
           "machine": platform.machine(), "python": platform.python_version()}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "campaign_start.json").write_text(json.dumps(out, indent=2) + "\n")
    lines = [f"campaign start A/B (bench-20 points {args.points}, oe6dof), {out['date']}",
             f"python {out['python']}, {out['machine']}; shared machine, load average after "
             f"the run {out['load_average_after']}",
             "point  method s (A B, B A)  model s (A B, B A)  model/method"]
    for i in args.points:
        a, b = cpu["method"][i], cpu["model"][i]
        lines.append(f"{i:5d}  {a[0]:6.2f} {a[1]:6.2f}       {b[0]:6.2f} {b[1]:6.2f}       "
                     f"{sum(b) / sum(a):.2f}")
    lines += [f"mean CPU per point: method {mean['method']:.2f} s, model {mean['model']:.2f} s, "
              f"model/method {out['model_over_method']}",
              f"largest estimate difference: {out['max_difference_in_std']:.1e} standard errors"]
    (RESULTS / "campaign_start.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
