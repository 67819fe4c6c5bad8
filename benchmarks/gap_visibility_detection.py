"""How often the blind check saw an effect, by how visible it was: each in-catalogue single
of stored blind-check runs (not the derivative deltas, rate limits and trim-level entries,
whose size does not follow the square law of ``cases.size_multiple``), given the visibility
its aircraft, row and option had in a ``gap_visibility.py`` file at k = 1, times k squared
(k: its offset from neutral over the file's), binned; "seen" is a verdict other than
``no_gap`` on its axis (either axis for a row on both). Reads files only, flies nothing
(docs/gap_benchmark.md, "Sizing by visibility").

    .venv/bin/python benchmarks/gap_visibility_detection.py \\
        benchmarks/results/gap_visibility/k1_seed11.jsonl \\
        benchmarks/results/gap_blind_check/seed0 benchmarks/results/gap_blind_check/seed8
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

from flightid.sim.effects.catalogue import CATALOGUE

SKIPPED = ("derivative_delta", "rate_limit", "bias", "actuator_bias", "mass_scale")
BINS = (0.0, 0.002, 0.005, 0.01, 0.02, 0.04, 0.1, float("inf"))


def _magnitudes(label: str) -> tuple[str, dict[str, float]]:
    """The options and the magnitude of a visibility line's label, entry(opts) p v p v."""
    m = re.match(r"\w+\(([^)]*)\)\s*(.*)", label)
    words = m.group(2).split()
    return m.group(1), {words[i]: float(words[i + 1]) for i in range(0, len(words), 2)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("visibility", type=Path)
    ap.add_argument("runs", type=Path, nargs="+")
    a = ap.parse_args()
    vis = {}
    for line in a.visibility.read_text().splitlines():
        r = json.loads(line)
        if "error" not in r["visibility"]:
            opts, mag = _magnitudes(r["label"])
            vis[(r["aircraft"], r["kind"], opts, tuple(sorted(mag)))] = (
                max(r["visibility"].values()), mag)
    rows = []
    for run in a.runs:
        for line in (run / "cases.jsonl").read_text().splitlines():
            c = json.loads(line)
            e = c["case"]["effects"][0] if c["case"]["effects"] else None
            if c["case"]["category"] != "single" or c["error"] or e["entry"] in SKIPPED:
                continue
            key = (c["case"]["aircraft"], c["kind"], ",".join(e["options"].values()),
                   tuple(sorted(e["magnitude"])))
            v, mag = vis[key]
            name = next(iter(e["magnitude"]))
            zero = CATALOGUE[e["entry"]].parameter(name).zero
            k = (e["magnitude"][name] - zero) / (mag[name] - zero)
            axes = ("lateral", "longitudinal") if e["axis"] == "both" else (e["axis"],)
            seen = any(c["verdicts"].get(ax) not in ("no_gap", None) for ax in axes)
            rows.append((v * k * k, seen, bool(c["right"])))
    print("| V of the case | cases | seen (not `no_gap` on its axis) | right first |")
    print("|---|---|---|---|")
    for lo, hi in zip(BINS, BINS[1:], strict=False):
        b = [r for r in rows if lo <= r[0] < hi]
        print(f"| {lo:g}-{hi:g} | {len(b)} | {sum(r[1] for r in b)} | {sum(r[2] for r in b)} |")


if __name__ == "__main__":
    main()
