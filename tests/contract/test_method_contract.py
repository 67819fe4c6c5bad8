"""The method contract: every registered identification method meets the protocol.

Like scikit-learn's ``check_estimator``: a method is covered by being registered. On a
standard record (the Navion demo card, seed 5: elevator 3211, aileron doublet, rudder
2-1-1, research sensors, light turbulence) each method returns one Estimate whose
``method`` is its id, with finite values and positive standard errors of a declared kind
and the fitted outputs; refuses an unknown option naming the valid ones; refuses a record
without a channel it needs, naming it; and gives the same numbers twice.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from flightid.identification.estimate import Estimate, StdKind
from flightid.identification.identify import identify
from flightid.identification.methods import registry
from flightid.record import FlightRecord
from flightid.scenarios.cards import fly_card, load_card

METHODS = sorted(registry.methods())
# the aileron doublet and the rudder 2-1-1 with their free responses: what every lateral
# model needs, and 20 s instead of 45 for the 6-DOF model
WINDOW = (12.0, 32.0)
_RESULTS: dict[str, Estimate] = {}


@pytest.fixture(scope="module")
def record() -> FlightRecord:
    measured, _ = fly_card(load_card("navion-demo"), 5)
    return measured


def _estimate(record: FlightRecord, method_id: str) -> Estimate:
    if method_id not in _RESULTS:
        spec = registry.get(method_id)
        _RESULTS[method_id] = identify(record, method_id, spec.contract_model or None,
                                       window=WINDOW)
    return _RESULTS[method_id]


def test_the_built_in_methods_are_registered():
    assert set(METHODS) >= {"ee", "swr", "oe", "oe6dof", "fem", "fdee", "fdoe", "fr"}


@pytest.mark.parametrize("method_id", METHODS)
def test_declaration_is_complete(method_id):
    spec = registry.get(method_id)
    assert spec.id == method_id and spec.name and spec.summary and spec.reference
    assert spec.default_model in spec.models
    assert dataclasses.is_dataclass(spec.options)
    spec.options()  # every option has a default
    for row in spec.describe():
        assert row["help"], f"option {row['name']} of {method_id} has no help text"
    assert spec.channels(spec.contract_model or spec.default_model)


@pytest.mark.parametrize("method_id", METHODS)
def test_returns_one_estimate_meeting_the_protocol(record, method_id):
    est = _estimate(record, method_id)
    assert isinstance(est, Estimate)
    assert est.method == method_id
    assert isinstance(est.std_kind, StdKind) and est.std_kind is not StdKind.NONE
    assert est.names and len(set(est.names)) == len(est.names)
    assert np.all(np.isfinite(est.values)) and np.all(est.std > 0)
    assert not set(est.names) & set(est.unidentifiable)
    if est.covariance is not None:
        assert est.covariance.shape == (len(est.names),) * 2
        assert np.allclose(np.sqrt(np.diag(est.covariance)), est.std, rtol=1e-6)
    assert est.outputs, "the fitted and measured outputs are part of the estimate"
    for name, series in est.outputs.items():
        assert {"measured", "model"} <= set(series), name
        assert np.shape(series["measured"]) == np.shape(series["model"])


@pytest.mark.parametrize("method_id", METHODS)
def test_rejects_an_unknown_option_naming_the_valid_ones(record, method_id):
    spec = registry.get(method_id)
    with pytest.raises(ValueError) as info:
        identify(record, method_id, no_such_option=1)
    message = str(info.value)
    assert "no_such_option" in message
    for field in dataclasses.fields(spec.options):
        assert field.name in message


@pytest.mark.parametrize("method_id", METHODS)
def test_rejects_a_wrongly_typed_option_naming_it(record, method_id):
    spec = registry.get(method_id)
    boolean = [f.name for f in dataclasses.fields(spec.options) if f.type in (bool, "bool")]
    if not boolean:
        pytest.skip(f"{method_id} has no boolean option")
    with pytest.raises(ValueError, match=boolean[0]):
        identify(record, method_id, **{boolean[0]: "maybe"})


@pytest.mark.parametrize("method_id", METHODS)
def test_refuses_a_record_without_a_needed_channel_naming_it(record, method_id):
    spec = registry.get(method_id)
    model = spec.contract_model or spec.default_model
    for missing in spec.channels(model)[:2]:
        lacking = FlightRecord(record.time, {k: v for k, v in record.channels.items()
                                             if k != missing}, record.meta)
        with pytest.raises(ValueError, match=rf"\b{missing}\b"):
            identify(lacking, method_id, model)


@pytest.mark.parametrize("method_id", METHODS)
def test_is_deterministic(record, method_id):
    first = _estimate(record, method_id)
    spec = registry.get(method_id)
    again = identify(record, method_id, spec.contract_model or None, window=WINDOW)
    assert again.names == first.names
    np.testing.assert_array_equal(again.values, first.values)
    np.testing.assert_array_equal(again.std, first.std)
