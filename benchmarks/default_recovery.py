"""Truth recovery with default options only, the way a user runs it.

For each seed: ``flightid simulate navion-demo --seed S -o f.parquet`` (fly_card, then the
record written and read back), then ``flightid identify f.parquet --method M --model lat``
and ``--model lon`` with every option at its default; each estimate scored against the
truth the record carries. Writes benchmarks/results/default_recovery.txt.

    python benchmarks/default_recovery.py [--seeds 1-10] [--methods oe,ee]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from flightid.identification.identify import identify
from flightid.identification.scoring import score
from flightid.record import read
from flightid.scenarios.cards import fly_card, load_card

RESULTS = Path(__file__).parent / "results" / "default_recovery.txt"


def _seeds(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--card", default="navion-demo")
    parser.add_argument("--seeds", default="1-10")
    parser.add_argument("--methods", default="oe,ee")
    args = parser.parse_args()
    card = load_card(args.card)
    methods = args.methods.split(",")
    counts = {m: [0, 0] for m in methods}
    misses: dict[str, list[str]] = {m: [] for m in methods}
    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in _seeds(args.seeds):
            measured, _ = fly_card(card, seed)
            path = Path(tmp) / f"s{seed}.parquet"
            measured.write(path)
            record = read(path)
            for method in methods:
                for model in ("lat", "lon"):
                    scored = score(identify(record, method, model), record)
                    rows = [r for r in scored.rows if r.status == "estimated"]
                    inside = [r for r in rows if abs(r.sigmas) <= 3]
                    counts[method][0] += len(inside)
                    counts[method][1] += len(rows)
                    misses[method] += [f"s{seed} {r.name} {r.sigmas:+.1f}" for r in rows
                                       if abs(r.sigmas) > 3]
                    line = f"seed {seed:2d} {method:3s} {model}: {scored.verdict}"
                    lines.append(line)
                    print(line, flush=True)
    lines.append("")
    for method, (inside, total) in counts.items():
        lines.append(f"{method}: {inside} of {total} (seed, derivative) pairs within 3 sigma "
                     f"({100 * inside / max(total, 1):.1f} %); beyond: "
                     f"{', '.join(misses[method]) or 'none'}")
    text = (f"card {args.card}, seeds {args.seeds}, default options\n" + "\n".join(lines)
            + "\n")
    RESULTS.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
