"""Optimised input design on the Navion, lateral, output error (docs/montecarlo.md):
`design-optimize`'s multisine against the built-in designs flown on the aileron, then the
rudder, at the 3211's energy (4 deg) and input time; predicted bounds for all, then a Monte
Carlo (the same seeds) of the optimised design against the 3211 and, with --sweep, the
sweep; writes benchmarks/results/design_optimize.{md,json,toml}. With --equal-duration
every built-in is stretched or compressed to the 3211's input time as well (equal energy
and equal duration), each flown in the Monte Carlo, and the optimised design is compared
with the best of them; writes benchmarks/results/design_optimize-equal-duration.{md,json}.

    .venv/bin/python benchmarks/design_optimize.py --n 100 --workers 2
    nice -n 10 .venv/bin/python benchmarks/design_optimize.py --n 100 --workers 1 \
        --equal-duration

The studies live in --study (default <tempdir>/flightid-design-optimize) and continue when
the script is rerun.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from flightid.scenarios.montecarlo.design import experiment, optimize
from flightid.scenarios.montecarlo.design.comparison import compare

RESULTS = Path(__file__).resolve().parent / "results"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100)
    parser.add_argument("--criterion", default="A")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--sweep", action="store_true")
    parser.add_argument("--study", default=None)
    parser.add_argument("--equal-duration", action="store_true")
    args = parser.parse_args()
    stem = "design_optimize" + ("-equal-duration" if args.equal_duration else "")
    study = Path(args.study or Path(tempfile.gettempdir()) / "flightid-design-optimize")
    t0 = time.perf_counter()
    opt = optimize.optimize("navion-demo", "lat", ("da", "dr"), args.criterion,
                            equal_duration=args.equal_duration)
    t_opt = time.perf_counter() - t0
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "design_optimize.toml").write_text(opt.maneuver_table())
    lines = [f"# design-optimize, navion-demo, lat, criterion {args.criterion}"
             + (", every built-in at the 3211's input time" if args.equal_duration else ""),
             "",
             f"optimisation {t_opt:.0f} s wall; best built-in (predicted) "
             f"{opt.best_builtin()}; gain {100 * opt.gain():.1f} %", "",
             "| design | mean bound/|truth| (predicted) | energy (rad² s) | input (s) | "
             "flight (s) | peak (deg) |", "|---|---|---|---|---|---|"]
    for r in opt.rows:
        lines.append(f"| {r['design']} | {r['mean_relative_bound']:.4f} | {r['energy']:.5f} | "
                     f"{r['input_time']:.1f} | {r['flight_time']:.1f} | "
                     f"{np.rad2deg(r['peak']):.2f} |")
    names = opt.problem.names
    lines += ["", "| derivative | truth | " + " | ".join(opt.predicted) + " |",
              "|---|---|" + "---|" * len(opt.predicted)]
    for n in names:
        lines.append(f"| {n} | {opt.problem.values[n]:+.4f} | " + " | ".join(
            f"{opt.predicted[d][n]:.4f}" for d in opt.predicted) + " |")
    (RESULTS / f"{stem}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines), flush=True)
    own = {"3211-da-dr": opt.designs["3211"], "optimized": opt.designs["optimized"]}
    if args.sweep:
        own["sweep-da-dr"] = opt.designs["sweep"]
    if args.equal_duration:  # the 3211 is at its own input time already
        span = opt.designs["3211"].end - opt.designs["3211"].start
        own.update({f"{k}-da-dr-{span:g}s": opt.designs[k] for k in experiment.DESIGNS
                    if k != "3211"})
    t1 = time.perf_counter()
    comparison = compare("navion-demo", args.n, "oe", "lat", study, designs=(),
                         equal="energy", reference="3211-da-dr",
                         workers=args.workers, own=own)
    t_mc = time.perf_counter() - t1
    rows = {"n": args.n, "mc_wall_s": t_mc, "optimisation_wall_s": t_opt,
            "gain_predicted": opt.gain(), "best_builtin_predicted": opt.best_builtin(),
            "predicted": opt.rows, "comparison": comparison.as_dict()}
    ratios = comparison.scatter_ratios("optimized", "3211-da-dr")
    mb = comparison.table("mean_bound")
    truth = {n: opt.problem.values.get(n, np.nan) for n in mb.index}
    rel = {k: float(np.mean([mb.loc[n, k] / abs(truth[n]) for n in mb.index
                             if truth[n] != 0 and np.isfinite(mb.loc[n, k])]))
           for k in mb.columns}
    rows["mean_relative_mean_bound"] = rel
    overall = comparison.mean_relative_scatter("optimized", "3211-da-dr")
    rows["mean_relative_scatter_optimized_3211"] = overall
    sweep = (comparison.mean_relative_scatter("optimized", "sweep-da-dr") if args.sweep
             else None)
    rows["mean_relative_scatter_optimized_sweep"] = sweep
    others = {k: comparison.mean_relative_scatter("optimized", k) for k in own
              if k not in ("optimized", "3211-da-dr", "sweep-da-dr")}
    rows["mean_relative_scatter_optimized_others"] = others
    builtins = [k for k in rel if k != "optimized" and k != "sweep-da-dr"]
    best = min(builtins, key=rel.get)
    rows["best_builtin_monte_carlo"] = best
    rows["ratios_optimized_3211"] = json.loads(ratios.to_json(orient="index"))
    out = ["", f"Monte Carlo n = {args.n} per design, {t_mc:.0f} s wall", "",
           "mean over derivatives of mean bound / |truth|: "
           + ", ".join(f"{k} {v:.4f}" for k, v in rel.items())
           + f" (optimized / 3211 {rel['optimized'] / rel['3211-da-dr']:.3f})", "",
           f"mean over the {len(overall['derivatives'])} derivatives with non-zero truth of "
           f"scatter / |truth|, optimized / 3211: {overall['ratio']:.3f}, 90 % paired "
           f"bootstrap interval {overall['low']:.3f}-{overall['high']:.3f} "
           f"({overall['realizations']} realizations)", ""]
    if sweep:
        out += [f"the same, optimized / sweep: {sweep['ratio']:.3f}, 90 % paired bootstrap "
                f"interval {sweep['low']:.3f}-{sweep['high']:.3f} "
                f"({sweep['realizations']} realizations)", ""]
    for k, m in others.items():
        out += [f"the same, optimized / {k}: {m['ratio']:.3f}, 90 % paired bootstrap "
                f"interval {m['low']:.3f}-{m['high']:.3f} ({m['realizations']} "
                "realizations)", ""]
    out += [f"best built-in of the Monte Carlo (mean bound / |truth|, equal energy"
            f"{' and duration' if args.equal_duration else ''}): {best} {rel[best]:.4f}; "
            f"optimized {rel['optimized']:.4f}, "
            f"{100 * (1 - rel['optimized'] / rel[best]):.1f} % below", "",
            "| built-in | mean bound / \\|truth\\| | optimized / it: mean bound / \\|truth\\| "
            "(90 % paired interval) | optimized / it: scatter / \\|truth\\| (90 % paired "
            "interval) |", "|---|---|---|---|"]
    rows["optimized_against"] = {}
    for k in builtins:
        b = comparison.mean_relative_bound("optimized", k)
        m = comparison.mean_relative_scatter("optimized", k)
        rows["optimized_against"][k] = {"mean_relative_bound": b, "mean_relative_scatter": m}
        out.append(f"| {k} | {rel[k]:.4f} | {b['ratio']:.3f} ({b['low']:.3f}-{b['high']:.3f}) "
                   f"| {m['ratio']:.3f} ({m['low']:.3f}-{m['high']:.3f}) |")
    out.append("")
    sc = comparison.table("scatter")
    for other in dict.fromkeys(("3211-da-dr", best)):
        pair = comparison.scatter_ratios("optimized", other)
        rows[f"ratios_optimized_{other}"] = json.loads(pair.to_json(orient="index"))
        out += ["", f"| derivative | scatter optimized | scatter {other} | ratio | "
                f"90 % interval | mean bound optimized | mean bound {other} |",
                "|---|---|---|---|---|---|---|"]
        for n in pair.index:
            r = pair.loc[n]
            out.append(f"| {n} | {sc.loc[n, 'optimized']:.4f} | {sc.loc[n, other]:.4f} | "
                       f"{r['ratio']:.2f} | {r['low']:.2f}-{r['high']:.2f} {r['interval']} "
                       f"| {mb.loc[n, 'optimized']:.4f} | {mb.loc[n, other]:.4f} |")
    with open(RESULTS / f"{stem}.md", "a") as fh:
        fh.write("\n".join(out) + "\n")
    text = json.dumps(rows, indent=1, default=str).replace(str(study), "STUDY")
    (RESULTS / f"{stem}.json").write_text(text)  # no machine path in the results
    print("\n".join(out))


if __name__ == "__main__":
    main()
