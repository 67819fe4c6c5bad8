"""Monte Carlo: output error against filter error on JSBSim Navion flights in turbulence.

Each run flies the project Navion (JSBSim, 1500 m, 55 m/s, trimmed) through an aileron
3211 and a rudder 2-1-1 (2 deg) with MIL-F-8785C Dryden turbulence of moderate intensity
(``flightid.sim.flight.disturbed``), adds white sensor noise of research-grade instruments
(beta 0.1 deg, p r phi 0.2 deg/s or deg, ay 0.05 m/s^2) and identifies the 13 lateral
derivatives of Morelli & Klein example 6.1 by output error and by filter error (process
noise in the sideslip equation: the gust enters the lateral motion through the
aerodynamic sideslip). Truth: JSBSim's body-axis derivatives at the trim point
(``flightid.sim.jsbsim.truth``). Two cases, the same seeds:

* ``lateral``: only the lateral (v) component of the moderate turbulence, which the
  lateral perturbation model with process noise represents;
* ``3-axis``: all three components; the u and w gusts change airspeed and angle of attack
  by 5 % and 2 deg, a multiplicative disturbance that additive process noise does not
  describe (a limit of the linear method, shown for honesty).

Writes benchmarks/results/turbulence_mc.txt (per derivative: truth, mean, bias, Monte
Carlo scatter, bias in units of the method's mean Cramer-Rao bound and of the scatter,
scatter over bound) and turbulence_mc.png. Runs on local processes with a progress bar:
    .venv/bin/python benchmarks/bench_turbulence_mc.py [--seeds 24] [--workers 2]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core per worker process, before numpy loads

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor, as_completed  # noqa: E402
from pathlib import Path  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from rich.progress import track  # noqa: E402

from flightid.identification.methods import filter_error as fe  # noqa: E402
from flightid.identification.methods import output_error as oe  # noqa: E402
from flightid.identification.models import linear as lm  # noqa: E402
from flightid.identification.models.linear import LATERAL_EXAMPLE_6_1  # noqa: E402
from flightid.identification.models.reference_condition import condition_from_record  # noqa: E402
from flightid.record import FlightRecord  # noqa: E402
from flightid.sim.flight import disturbed as dist  # noqa: E402
from flightid.sim.jsbsim import truth as truth_mod  # noqa: E402
from flightid.sim.jsbsim.model import as_model  # noqa: E402
from flightid.sim.jsbsim.trim import trim as trim_aircraft  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
ALTITUDE_M, SPEED_M_S = 1500.0, 55.0
RATE_HZ, DURATION_S = 50.0, 20.0
AMPLITUDE_RAD = 0.035
NOISE = {"beta": 0.1 * math.pi / 180, "p": 0.2 * math.pi / 180, "r": 0.2 * math.pi / 180,
         "phi": 0.2 * math.pi / 180, "ay": 0.05}
CASES = ("lateral", "3-axis")
THRESHOLD = 3.0


def _multistep(t: np.ndarray, start: float, widths: list[float], signs: list[int],
               amplitude: float) -> np.ndarray:
    u = np.zeros_like(t)
    for width, sign in zip(widths, signs, strict=True):
        u[(t >= start) & (t < start + width)] = sign * amplitude
        start += width
    return u


def _turbulence_ned(case: str, trim, n: int, seed: int) -> np.ndarray:
    """Moderate Dryden turbulence on the record grid (n x 3, NED, m/s)."""

    turb = dist.Turbulence(intensity="moderate")
    rng = np.random.default_rng(seed)
    uvw = turb.velocities(n, RATE_HZ, trim.speed_m_s, trim.altitude_m - trim.terrain_m, rng)
    if case == "lateral":
        uvw[:, [0, 2]] = 0.0
    psi = trim.jsbsim.get("ic/psi-true-rad", 0.0)
    c, s = math.cos(psi), math.sin(psi)
    return np.column_stack([c * uvw[:, 0] - s * uvw[:, 1], s * uvw[:, 0] + c * uvw[:, 1],
                            uvw[:, 2]])


def calm_reference(trim) -> dict[str, float]:
    """Output error on the same maneuver without turbulence and sensor noise.

    What the linear lateral model can reach on this JSBSim aircraft at all: it holds V,
    alpha and theta at their means, so it differs from the slopes at trim by 1-2 % on
    the large derivatives (tests/identification/methods/test_output_error_jsbsim.py). Biases
    are also given against this reference, which separates turbulence-induced bias from model error.
    """
    return run_one("calm", 0, trim)["oe"]["values"]


def run_one(case: str, seed: int, trim) -> dict:
    """Fly one turbulent flight and fit it by output error and filter error."""

    t = np.arange(0.0, DURATION_S + 0.5 / RATE_HZ, 1.0 / RATE_HZ)
    controls = {"da": _multistep(t, 1.0, [1.5, 1.0, 0.5, 0.5], [1, -1, 1, -1], AMPLITUDE_RAD),
                "dr": _multistep(t, 8.0, [1.0, 0.5, 0.5], [1, -1, 1], AMPLITUDE_RAD)}
    calm = case == "calm"
    turbulence = np.zeros((t.size, 3)) if calm else _turbulence_ned(case, trim, t.size, seed)
    flown = dist.fly_disturbed(as_model("navion"), trim, controls, DURATION_S, RATE_HZ,
                               turbulence=None if calm else turbulence)
    rng = np.random.default_rng(10**6 + seed)
    channels = dict(flown.channels)
    for name, sigma in NOISE.items():
        if not calm:
            channels[name] = channels[name] + sigma * rng.standard_normal(t.size)
    record = FlightRecord(flown.time, channels, flown.meta)
    model = lm.lateral(condition_from_record(record))
    out = {"case": case, "seed": seed, "beta_gust_deg": float(np.degrees(
        np.std(turbulence[:, 1]) / SPEED_M_S))}
    methods = (("oe", lambda: oe.estimate(record, model)),
               ("fem", lambda: fe.estimate(record, model, process_noise=["beta"])))
    for label, fit in methods[:1] if calm else methods:
        start = time.perf_counter()
        est = fit()
        out[label] = {"values": {n: est[n] for n in est.names},
                      "std": {n: est.std_of(n) for n in est.names},
                      "converged": bool(est.fit["converged"]),
                      "seconds": time.perf_counter() - start}
    return out


def summarise(runs: list[dict], truth: dict[str, float], names: list[str],
              calm: dict[str, float]) -> dict:
    """Per case, method and derivative: mean, bias, scatter, mean bound and the ratios."""
    table: dict = {}
    for case in CASES:
        for method in ("oe", "fem"):
            rows = [r[method] for r in runs if r["case"] == case]
            for name in names:
                values = np.array([r["values"][name] for r in rows])
                bounds = np.array([r["std"][name] for r in rows])
                mean, scatter, bound = values.mean(), values.std(ddof=1), bounds.mean()
                bias = mean - truth[name]
                table[case, method, name] = {
                    "mean": mean, "bias": bias, "scatter": scatter, "bound": bound,
                    "bias_bounds": bias / bound, "bias_scatter": bias / scatter,
                    "calm_bounds": (mean - calm[name]) / bound,
                    "scatter_bound": scatter / bound, "values": values, "bounds": bounds,
                }
    return table


def report(table: dict, runs: list[dict], truth: dict[str, float], names: list[str],
           calm: dict[str, float], seconds: float, workers: int) -> str:
    """The results file text."""
    lines = [
        "Monte Carlo: output error (oe) vs filter error (fem), JSBSim Navion in moderate "
        "MIL-F-8785C Dryden turbulence",
        f"trim {ALTITUDE_M:g} m, {SPEED_M_S:g} m/s; aileron 3211 + rudder 2-1-1 of "
        f"{math.degrees(AMPLITUDE_RAD):.1f} deg; {DURATION_S:g} s at {RATE_HZ:g} Hz; sensor "
        "noise beta 0.1 deg, p r phi 0.2 deg(/s), ay 0.05 m/s^2",
        f"{len(runs) // len(CASES)} seeds per case, {workers} worker processes, "
        f"{seconds:.0f} s wall",
        "truth: JSBSim body-axis derivatives at trim (flightid.sim.jsbsim.truth)",
        "bias/CRB: bias over the method's mean Cramer-Rao bound; bias/MC: over the Monte "
        "Carlo scatter; MC/CRB: scatter over mean bound; vs calm: (mean - calm) / CRB, with "
        "calm = output error on the same maneuver flown without turbulence and noise (the "
        "linear model's own error against JSBSim)",
        "",
    ]
    for case in CASES:
        case_runs = [r for r in runs if r["case"] == case]
        conv = {m: sum(r[m]["converged"] for r in case_runs) for m in ("oe", "fem")}
        secs = {m: np.median([r[m]["seconds"] for r in case_runs]) for m in ("oe", "fem")}
        gust = np.mean([r["beta_gust_deg"] for r in case_runs])
        lines.append(f"case {case}: rms sideslip gust {gust:.2f} deg; converged oe "
                     f"{conv['oe']}/{len(case_runs)}, fem {conv['fem']}/{len(case_runs)}; "
                     f"median fit time oe {secs['oe']:.2f} s, fem {secs['fem']:.2f} s")
        cols = (f"{'bias':>9}{'MC std':>9}{'bias/CRB':>9}{'bias/MC':>8}{'MC/CRB':>7}"
                f"{'vs calm':>8}")
        head = (f"{'derivative':<10}{'truth':>9}{'calm':>9} | {'oe mean':>9}{cols} | "
                f"{'fem mean':>9}{cols}")
        lines += [head, "-" * len(head)]
        for name in names:
            cells = [f"{name:<10}{truth[name]:>9.4f}{calm[name]:>9.4f}"]
            for method in ("oe", "fem"):
                s = table[case, method, name]
                cells.append(f"{s['mean']:>9.4f}{s['bias']:>9.4f}{s['scatter']:>9.4f}"
                             f"{s['bias_bounds']:>9.1f}{s['bias_scatter']:>8.1f}"
                             f"{s['scatter_bound']:>7.1f}{s['calm_bounds']:>8.1f}")
            lines.append(" | ".join(cells))
        oe_big = [n for n in names if abs(table[case, "oe", n]["bias_bounds"]) > THRESHOLD]
        fem_ok = [n for n in oe_big if abs(table[case, "fem", n]["bias_bounds"]) <= THRESHOLD]
        fem_big = [n for n in names if abs(table[case, "fem", n]["bias_bounds"]) > THRESHOLD]
        lines += [
            f"oe bias > {THRESHOLD:g} CRB: {', '.join(oe_big) or 'none'}",
            f"  of which fem within {THRESHOLD:g} CRB: {', '.join(fem_ok) or 'none'}",
            f"fem bias > {THRESHOLD:g} CRB: {', '.join(fem_big) or 'none'}",
            "",
        ]
    return "\n".join(lines)


def plot(table: dict, names: list[str], path: Path) -> None:
    """Errors in units of each method's own Cramer-Rao bound, per derivative and case."""
    fig, axes = plt.subplots(len(CASES), 1, figsize=(12, 4.2 * len(CASES)), sharex=True)
    x = np.arange(len(names))
    for ax, case in zip(np.atleast_1d(axes), CASES, strict=True):
        for offset, method, color in ((-0.17, "oe", "tab:red"), (0.17, "fem", "tab:blue")):
            for i, name in enumerate(names):
                s = table[case, method, name]
                z = (s["values"] - (s["mean"] - s["bias"])) / s["bounds"]
                ax.plot(np.full(z.size, i + offset), z, ".", color=color, alpha=0.35, ms=4)
                ax.plot(i + offset, s["bias_bounds"], "_", color=color, ms=14, mew=2.5)
            ax.plot([], [], ".", color=color, label=f"{method} (run; bar = mean)")
        ax.axhspan(-THRESHOLD, THRESHOLD, color="0.85", zorder=0,
                   label=f"within {THRESHOLD:g} Cramer-Rao bounds")
        ax.axhline(0.0, color="0.4", lw=0.8)
        ax.set_yscale("symlog", linthresh=3.0)
        ticks = [-100, -30, -10, -3, 0, 3, 10, 30, 100]
        ax.set_yticks(ticks, [str(t) for t in ticks])
        ax.set_ylabel("(estimate - truth) / own CRB")
        ax.set_title(f"Navion, moderate Dryden turbulence, {case} gusts")
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xticks(x, names, rotation=45)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(seeds: int = 24, workers: int = 2) -> str:
    """Run the Monte Carlo, write the results file and the plot, return the text."""

    trim = trim_aircraft("navion", ALTITUDE_M, SPEED_M_S)
    truth = truth_mod.derivatives("navion", trim, axes="body")
    names = list(LATERAL_EXAMPLE_6_1)
    start = time.perf_counter()
    runs = []
    with ProcessPoolExecutor(max_workers=workers) as pool:
        calm_job = pool.submit(calm_reference, trim)
        jobs = [pool.submit(run_one, case, seed, trim) for case in CASES
                for seed in range(1, seeds + 1)]
        for job in track(as_completed(jobs), total=len(jobs), description="flights"):
            runs.append(job.result())
        calm = calm_job.result()
    seconds = time.perf_counter() - start
    runs.sort(key=lambda r: (CASES.index(r["case"]), r["seed"]))
    table = summarise(runs, truth, names, calm)
    text = report(table, runs, truth, names, calm, seconds, workers)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "turbulence_mc.txt").write_text(text + "\n")
    plot(table, names, RESULTS / "turbulence_mc.png")
    return text


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=24)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    print(main(args.seeds, args.workers))
