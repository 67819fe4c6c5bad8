"""``identify``'s default model: the axis the record excites (``excited_model``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from flightid.api import fly
from flightid.identification.identify import excited_model, identify
from flightid.record import FlightRecord, read
from tests.conftest import TWIN_OTTER


@pytest.fixture(scope="module")
def elevator_flight():
    return fly("twinotter-21-elevator", seed=2)


def _unlisted(record: FlightRecord) -> FlightRecord:
    """The record without its list of maneuvers, as a real flight comes."""
    extra = {k: v for k, v in record.meta.extra.items() if k != "maneuvers"}
    return FlightRecord(record.time, record.channels, dataclasses.replace(record.meta,
                                                                           extra=extra))


def test_an_elevator_card_is_fitted_with_the_short_period_model(elevator_flight):
    record = elevator_flight.measured
    assert excited_model(record, "oe") == excited_model(record, "ee") == "short_period"
    assert excited_model(record, "oe6dof") == "6dof"  # a method without the preset
    est = identify(record)  # oe, model auto
    assert est.fit["model"] == "short_period"
    truth = elevator_flight.truth
    for name in ("Cm_alpha", "Cm_q", "Cm_de"):  # measured: 1.7, -0.6, 0.3 bounds off
        value, std = est.values[est.names.index(name)], est.std[est.names.index(name)]
        assert abs(value - truth[name]) < 3 * std, name


def test_an_unlisted_elevator_record_is_told_by_the_surfaces_spread(elevator_flight):
    record = _unlisted(elevator_flight.measured)
    assert excited_model(record, "oe") == "short_period"
    # the same record with a rudder moved as much as the elevator is no longer elevator-only
    moved = record.with_channels(dr=record["dr"] + (record["de"] - np.median(record["de"])))
    assert excited_model(moved, "oe") == "lateral"


def test_lateral_maneuvers_keep_the_lateral_model():
    record = fly("navion-doublets", seed=1).measured  # elevator, aileron and rudder doublets
    assert excited_model(record, "oe") == "lateral"
    assert excited_model(read(TWIN_OTTER), "ee") == "lateral"  # NASA's lateral maneuver
