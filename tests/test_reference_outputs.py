"""The numbers that a change of layout must not change: the method contract's estimates,
the demo's estimates and the Twin Otter reproductions, bit for bit (exact float equality)
against tests/reference_outputs.json, saved before the layout moved (tests/reference_outputs.py
computes both).
"""

from __future__ import annotations

import json

import pytest

from tests.conftest import TWIN_OTTER
from tests.reference_outputs import SAVED, contract, demo_estimates, twin_otter

REFERENCE = json.loads(SAVED.read_text(encoding="utf-8"))


@pytest.mark.slow
@pytest.mark.parametrize("name, compute", [("contract", contract), ("demo", demo_estimates)])
def test_navion_estimates_are_bit_identical(name, compute):
    assert compute() == REFERENCE[name]


@pytest.mark.slow
def test_twin_otter_reproductions_are_bit_identical():
    assert twin_otter(TWIN_OTTER) == REFERENCE["twin_otter"]
