"""Coverage of output error's 95 % intervals with the defaults, on one library card.

Each seed: the card flown (fly_card), the standard data reduction (reduce_record), then
``identify`` with the default method (output error) and every option at its default, on
one axis; per derivative, the share of seeds whose truth lies within 1.96 standard errors,
against the 99 % binomial band of 95 % for that number of seeds
(``scenarios.montecarlo.intervals.binomial_band``). The record is reduced first, as
``flightid identify`` and ``flightid montecarlo`` do; the seeds are ``fly_card`` seeds.

    python benchmarks/default_coverage.py twinotter-lateral-0alpha --seeds 2001-2200

Writes benchmarks/results/default_coverage-CARD.txt.
"""

from __future__ import annotations

import argparse
import warnings
from collections import Counter
from pathlib import Path

from flightid.identification.data.reduction import reduce_record
from flightid.identification.evaluation.scoring import score
from flightid.identification.identify import identify
from flightid.scenarios.cards import fly_card, load_card
from flightid.scenarios.montecarlo.intervals import binomial_band

RESULTS = Path(__file__).parent / "results"
Z95 = 1.959964


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("card")
    parser.add_argument("--seeds", default="2001-2200")
    parser.add_argument("--model", default="lat")
    args = parser.parse_args()
    lo, _, hi = args.seeds.partition("-")
    card = load_card(args.card)
    count, inside = Counter(), Counter()
    for seed in range(int(lo), int(hi or lo) + 1):
        measured, _ = fly_card(card, seed)
        record = reduce_record(measured).record
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rows = score(identify(record, "oe", args.model), record).rows
        for r in rows:
            if r.status == "estimated":
                count[r.name] += 1
                inside[r.name] += abs(r.sigmas) <= Z95
    lines = [f"{args.card}, output error with the defaults, seeds {args.seeds}", "",
             "| derivative | n | coverage of the 95 % interval | 99 % binomial band | |",
             "|---|---|---|---|---|"]
    for name, n in count.items():
        band = binomial_band(n)
        share = inside[name] / n
        verdict = "inside" if band[0] <= share <= band[1] else "outside"
        lines.append(f"| {name} | {n} | {100 * share:.1f} % | {100 * band[0]:.1f}-"
                     f"{100 * band[1]:.1f} % | {verdict} |")
    text = "\n".join(lines) + "\n"
    (RESULTS / f"default_coverage-{args.card}.txt").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
