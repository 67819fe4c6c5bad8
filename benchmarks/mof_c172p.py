"""Held-out prediction of ``--method mof`` on the stock c172p, pre-stall (issue 35 item 4).

Trains on one flight (1000 m, 33 m/s: elevator 3211 -7 deg, aileron and rudder doublets
8 deg; alpha up to about 12 deg, below the stall hysteresis near 16 deg), predicts the
coefficients of a held-out flight (elevator doublet, aileron and rudder 2-1-1, another
seed), both with research sensors and the standard data reduction, and compares with
linear equation error. Writes benchmarks/results/mof_c172p.txt.

    .venv/bin/python benchmarks/mof_c172p.py [--sensors research|ideal]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from flightid.identification.data.reduction import reduce_record
from flightid.identification.estimate import Estimate
from flightid.identification.evaluation.validation import r_squared, theil_inequality
from flightid.identification.identify import identify
from flightid.identification.methods import equation_error as ee
from flightid.scenarios.cards import card_from_dict, fly_card

RESULTS = Path(__file__).resolve().parent / "results"
TRAIN = [{"kind": "3211", "surface": "de", "start": 2.0, "base": 0.6, "amplitude_deg": -7.0},
         {"kind": "doublet", "surface": "da", "start": 14.0, "base": 1.0, "amplitude_deg": 8.0},
         {"kind": "doublet", "surface": "dr", "start": 20.0, "base": 1.0, "amplitude_deg": 8.0}]
TEST = [{"kind": "doublet", "surface": "de", "start": 2.0, "base": 1.2, "amplitude_deg": -6.0},
        {"kind": "211", "surface": "da", "start": 12.0, "base": 0.8, "amplitude_deg": 7.0},
        {"kind": "211", "surface": "dr", "start": 20.0, "base": 0.8, "amplitude_deg": 6.0}]


def record(maneuvers: list, seed: int, sensors: str):
    card = card_from_dict({"name": "c172p-mof", "aircraft": "c172p", "duration": 30.0,
                           "rate": 100.0, "seed": seed,
                           "condition": {"altitude": 1000.0, "speed": 33.0},
                           "maneuver": maneuvers, "sensors": {"suite": sensors}})
    measured, truth = fly_card(card)
    return reduce_record(measured).record, truth


def part(est: Estimate, c: str) -> Estimate:
    names = [n for n in est.names if n.startswith(c + "_")]
    return Estimate(est.method, names, [est[n] for n in names], [est.std_of(n) for n in names],
                    fit=dict(est.fit["coefficients"][c]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sensors", default="research")
    args = ap.parse_args()
    train, truth = record(TRAIN, 1, args.sensors)
    test, _ = record(TEST, 2, args.sensors)
    lines = [f"mof on c172p, {args.sensors} sensors; training alpha "
             f"{np.degrees(truth['alpha'].min()):.1f} to {np.degrees(truth['alpha'].max()):.1f}"
             " deg (pre-stall)",
             "coefficient  mof R2  mof Theil  ee R2  ee Theil  terms"]
    for model in ("longitudinal", "lateral"):
        est = identify(train, "mof", model, window="none")
        lin = identify(train, "ee", model, window="none")
        for c in est.fit["coefficients"]:
            y = ee.channel_values(test, c)
            m, lpart = ee.predict(part(est, c), test), ee.predict(part(lin, c), test)
            terms = [n for n in est.names if n.startswith(c + "_")]
            lines.append(f"{c:<12} {r_squared(y, m):6.3f} {theil_inequality(y, m):9.3f} "
                         f"{r_squared(y, lpart):6.3f} {theil_inequality(y, lpart):8.3f}  "
                         f"{', '.join(terms)}")
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"mof_c172p-{args.sensors}.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
