"""Truth recovery with default options only, the way a user runs it, on every library card.

For each card of ``flightid simulate --list`` (``example``, a schema example, aside) and
each seed: the card flown (``flightid simulate CARD --seed S -o f.parquet``: fly_card, the
record written and read back), then ``flightid identify f.parquet --model AXIS`` with the
default method (output error) and every other option at its default, on each axis the
card's maneuvers excite (lat: aileron or rudder; lon: elevator), once with the standard
data reduction (the default) and once with ``--raw``. Each estimate is scored against the
truth the record carries. Per card: the share of (seed, estimated derivative) pairs within
3 standard errors, the share of the model's derivatives estimated (the rest withheld
as not identifiable, or the whole model refused; ``unexcited`` lists those withheld
because the card never moves their surface) and the estimates whose bound the structure
check widened (``widened``, output error's ``fit['structure']``).

    python benchmarks/default_recovery.py --seeds 1-10 [--cards a,b] [--cache DIR]
    python benchmarks/default_recovery.py --seeds 1001-1010 --name heldout
    python benchmarks/default_recovery.py --seeds 1-10 --axes lat --name lateral-oe

Development seeds 1-10; held-out seeds 1001-1010 (docs/validation.md), run once at the
end. Writes benchmarks/results/default_recovery_cards[-NAME].json and .txt.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from flightid.identification.data.reduction import reduce_record
from flightid.identification.evaluation.scoring import score
from flightid.identification.identify import identify
from flightid.record import read
from flightid.scenarios.cards import fly_card, library_cards, load_card

RESULTS = Path(__file__).parent / "results"
METHOD = "oe"  # flightid identify's default method
SKIP = ("example",)
AXES = {"lat": ("da", "dr"), "lon": ("de",)}


def _seeds(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def excited_axes(card_name: str) -> list[str]:
    """The axes ('lat', 'lon') whose surfaces the card's maneuvers move."""
    flown = {s for m in load_card(card_name).maneuvers for s in m.surfaces()}
    return [axis for axis, surfaces in AXES.items() if flown & set(surfaces)]


def _record(card_name: str, seed: int, cache: Path):
    path = cache / f"{card_name}-s{seed}.parquet"
    if not path.exists():
        measured, _ = fly_card(load_card(card_name), seed)
        measured.write(path)
    return read(path)


def run_one(record, axis: str, reduced: bool) -> dict:
    """One identification: counts within 3 sigma, estimated, withheld; or the refusal."""
    if reduced:
        record = reduce_record(record).record
    try:
        est = identify(record, METHOD, axis)
    except ValueError as exc:
        return {"refused": str(exc)}
    rows = score(est, record).rows
    done = [r for r in rows if r.status == "estimated"]
    unexcited = [r for r in rows if "is not excited" in r.reason]
    return {"estimated": len(done), "withheld": len(rows) - len(done),
            "unexcited": [r.name for r in unexcited],
            "widened": sorted(est.fit.get("structure", {})),
            "start": est.fit.get("start", ""),
            "inside": sum(abs(r.sigmas) <= 3 for r in done),
            "misses": [f"{r.name} {r.sigmas:+.1f}" for r in done if abs(r.sigmas) > 3]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cards", default="", help="comma-separated (default: all)")
    parser.add_argument("--seeds", default="1-10")
    parser.add_argument("--name", default="", help="results file suffix (e.g. heldout)")
    parser.add_argument("--cache", default="", help="folder keeping the flown records")
    parser.add_argument("--fly-only", action="store_true")
    parser.add_argument("--reductions", default="raw,standard",
                        help="raw, standard or both (comma-separated)")
    parser.add_argument("--axes", default="lat,lon",
                        help="the axes identified where the card excites them (comma-separated)")
    args = parser.parse_args()
    cards = args.cards.split(",") if args.cards else [c for c in library_cards()
                                                      if c not in SKIP]
    seeds = _seeds(args.seeds)
    tmp = None if args.cache else tempfile.TemporaryDirectory()
    cache = Path(args.cache or tmp.name)
    cache.mkdir(parents=True, exist_ok=True)
    rows = []
    for card in cards:
        excited = excited_axes(card)
        axes = [axis for axis in excited if axis in args.axes.split(",")]
        if excited and not axes:  # an axis not asked for
            continue
        for seed in seeds:
            if not axes:  # nothing to identify: not flown
                rows.append({"card": card, "seed": seed, "axis": "-", "reduction": "-",
                             "refused": "no maneuver on the elevator, aileron or rudder"})
                continue
            record = _record(card, seed, cache)
            if args.fly_only:
                print(f"flew {card} seed {seed}", flush=True)
                continue
            for axis in axes:
                for reduced in [r == "standard" for r in args.reductions.split(",")]:
                    row = {"card": card, "seed": seed, "axis": axis,
                           "reduction": "standard" if reduced else "raw",
                           **run_one(record, axis, reduced)}
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    if args.fly_only:
        return
    suffix = f"-{args.name}" if args.name else ""
    (RESULTS / f"default_recovery_cards{suffix}.json").write_text(json.dumps(
        {"method": METHOD, "seeds": args.seeds, "rows": rows}, indent=1))
    text = table(rows, args.seeds)
    (RESULTS / f"default_recovery_cards{suffix}.txt").write_text(text)
    print(text)


def table(rows: list[dict], seeds: str) -> str:
    """Per card and reduction: within-3-sigma share and share estimated (markdown)."""
    lines = [f"default method ({METHOD}) on each excited axis, seeds {seeds}", "",
             "| card | axes | raw: within 3 sigma | raw: estimated | standard reduction: "
             "within 3 sigma | standard reduction: estimated |", "|---|---|---|---|---|---|"]
    by_card: dict[str, list[dict]] = {}
    for r in rows:
        by_card.setdefault(r["card"], []).append(r)
    for card, rs in by_card.items():
        cells = []
        for reduction in ("raw", "standard"):
            sel = [r for r in rs if r["reduction"] == reduction]
            if not sel and any(r["reduction"] != "-" for r in rs):
                cells += ["not run", "not run"]
                continue
            est = sum(r.get("estimated", 0) for r in sel)
            inside = sum(r.get("inside", 0) for r in sel)
            withheld = sum(r.get("withheld", 0) for r in sel)
            refused = sum("refused" in r for r in sel)
            cells.append(f"{100 * inside / est:.0f} % ({inside}/{est})" if est else "-")
            share = f"{100 * est / (est + withheld):.0f} %" if est + withheld else "0 %"
            cells.append(share + (f", {refused} refused" if refused else ""))
        axes = ",".join(sorted({r["axis"] for r in rs}))
        lines.append(f"| {card} | {axes} | " + " | ".join(cells) + " |")
    lines.append("")
    for card, rs in by_card.items():
        refusals = sorted({r["refused"][:160] for r in rs if "refused" in r})
        for text in refusals:
            lines.append(f"- {card} refused: {text}")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
