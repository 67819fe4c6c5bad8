"""The method contract (``flightid.testing.check_method``'s checks) on every registered
method: a method is covered by being registered, as with scikit-learn's ``check_estimator``.
"""

from __future__ import annotations

import pytest

from flightid.identification.methods import registry
from flightid.record import FlightRecord
from flightid.testing import METHOD_CHECKS, MethodContract, contract_record

METHODS = sorted(registry.methods())


@pytest.fixture(scope="module")
def record() -> FlightRecord:
    return contract_record()


@pytest.fixture(scope="module", params=METHODS)
def contract(request, record) -> MethodContract:
    """One method's contract; its estimate is computed once per module and method."""
    return MethodContract(request.param, record)


def test_the_built_in_methods_are_registered():
    assert set(METHODS) >= {"ee", "swr", "oe", "oe6dof", "fem", "fdee", "fdoe", "fr"}


@pytest.mark.parametrize("check", METHOD_CHECKS)
def test_method_meets_the_contract(contract: MethodContract, check: str):
    if check == "typed_option" and not contract.boolean_options:
        pytest.skip(f"{contract.id} has no boolean option")
    getattr(contract, f"check_{check}")()
