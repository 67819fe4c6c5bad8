"""The lateral test card of the gap tests (not a test module): each of aileron and rudder
moved twice, 44 s at 50 Hz, at each aircraft's blind-check condition. Kept here, apart
from the blind check's own card (which flies both axes), so that the gap tests hold
whatever that card becomes."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from flightid.record import FlightRecord
from flightid.scenarios.gap_benchmark.cases import AIRCRAFT
from flightid.scenarios.inputs import input_from_dict, total_signals
from flightid.sim.effects.sensor import Sample

# (kind, surface, start s): each surface twice, 10-12 s apart (one window each)
SCHEDULE = (("doublet", "da", 2.0), ("211", "dr", 12.0), ("doublet", "da", 22.0),
            ("doublet", "dr", 32.0))
DURATION_S = 44.0
RATE_HZ = 50.0
# the research suite's vane position and accelerometer lever arm, corrected to the CG
DROPPED = ("vanes", "lever_arm")


def maneuvers(aircraft: str) -> list[dict[str, Any]]:
    """The card's ``[[maneuver]]`` tables for ``aircraft``."""
    f = AIRCRAFT[aircraft]
    return [{"kind": kind, "surface": s, "start": start, "base": f.base_s,
             "amplitude_deg": f.aileron_deg if s == "da" else f.rudder_deg}
            for kind, s, start in SCHEDULE]


def card_data(aircraft: str, seed: int, sensors: dict[str, Any] | None = None) -> dict:
    """The card as a dict (``card_from_dict``), research sensors corrected to the CG."""
    f = AIRCRAFT[aircraft]
    return {"name": "gap-lateral", "aircraft": aircraft, "duration": DURATION_S,
            "rate": RATE_HZ, "seed": seed,
            "condition": {"altitude": f.altitude_m, "speed": f.speed_m_s},
            "maneuver": maneuvers(aircraft),
            "sensors": sensors or {"suite": "research", "drop": list(DROPPED)}}


def commands(measured: FlightRecord, truth: FlightRecord, surfaces: Sequence[str]
             ) -> FlightRecord:
    """``measured`` with its ``surfaces`` channels replaced by the commands (the trim plus
    the card's designed inputs, on the flight's own time grid) through the same 50 Hz
    sampling and 10 Hz anti-alias filter as the other channels (a recorder that filters
    every channel alike), and marked so in a copy of its metadata."""
    designs = [input_from_dict(d) for d in truth.meta.extra["inputs"]]
    signals = total_signals(designs, truth.time)
    antialias = Sample(rate=50.0, antialias=10.0, order=4.0)
    rng = np.random.default_rng(0)
    channels = {**measured.channels, **{
        s: np.interp(measured.time, truth.time,
                     antialias.apply(truth.time, truth[s][0] + signals[s], rng))
        for s in surfaces}}
    meta = dataclasses.replace(measured.meta, extra={**measured.meta.extra,
                                                     "surfaces": "command"})
    return FlightRecord(measured.time, channels, meta)
