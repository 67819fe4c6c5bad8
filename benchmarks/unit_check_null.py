"""False alarms of the unit check (``flightid.identification.data.unit_sanity``) on null cases:
every library card (``flightid simulate --list``) flown with seeds 1, 2, 3 in calm air (its
disturbances removed) and in light turbulence (its disturbances replaced by one
``turbulence`` of intensity ``light``), plus the real NASA Twin Otter record. Every one
must pass; the script reports how many were flagged and the range of every ratio.
Writes benchmarks/results/unit_check_null.json.

    .venv/bin/python benchmarks/unit_check_null.py --twin-otter PATH/totter_f1_017_data.mat
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from flightid.identification.data.unit_sanity import RATIO_BANDS, implausible, unit_ratios
from flightid.record import FlightRecord, read
from flightid.scenarios.cards import fly_card, library_cards, load_card
from flightid.sim.flight.disturbed import disturbance_from_dict

SEEDS = (1, 2, 3)
RESULTS = Path(__file__).parent / "results" / "unit_check_null.json"


def null_records() -> list[tuple[str, FlightRecord]]:
    """(name, measured record) of every library card, seed and air."""
    light = (disturbance_from_dict({"kind": "turbulence", "intensity": "light"}),)
    out = []
    for name, path in sorted(library_cards().items()):
        card = load_card(path)
        for air, disturbances in (("calm", ()), ("light turbulence", light)):
            flown = dataclasses.replace(card, disturbances=disturbances)
            for seed in SEEDS:
                measured, _ = fly_card(flown, seed=seed)
                out.append((f"{name}, {air}, seed {seed}", measured))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--twin-otter", type=Path, help="the NASA Twin Otter .mat record")
    args = parser.parse_args()
    records = null_records()
    if args.twin_otter:
        records.append(("NASA Twin Otter flight 1 maneuver 17", read(args.twin_otter)))
    flagged, ranges = {}, {}
    for name, record in records:
        problems = implausible(record)
        if problems:
            flagged[name] = problems
        for ratio in unit_ratios(record).values():
            low, high = ranges.get(ratio.name, (ratio.value, ratio.value))
            ranges[ratio.name] = (min(low, ratio.value), max(high, ratio.value))
    result = {"records": len(records), "flagged": len(flagged), "flagged_records": flagged,
              "ratio_ranges": {k: {"min": v[0], "max": v[1], "band": RATIO_BANDS[k]}
                               for k, v in sorted(ranges.items())}}
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
