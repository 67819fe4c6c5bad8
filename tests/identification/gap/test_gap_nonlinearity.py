"""The nonlinear-structure test of the gap diagnosis (identification/gap/nonlinearity.py):
a quadratic sideslip vane is found and said in words (never as a catalogue entry), null
flights in calm air and in light turbulence are not flagged, and a surface backlash (a
catalogue entry) does not trip it.

The flights are the blind check's card (scenarios/gap_benchmark/run.py) on flight seeds
the levels were not set on (seed 0's draw set them)."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.gap import diagnose
from flightid.identification.gap.nonlinearity import LEVELS, play
from flightid.identification.gap.verdict import PARTLY, UNEXPLAINED
from flightid.scenarios.gap_benchmark.cases import NULL, NULL_INDEX, OUT, SINGLE, Case, Effect
from flightid.scenarios.gap_benchmark.run import fly_case
from flightid.sim.effects.catalogue import CATALOGUE


def test_play_operator_follows_only_past_half_the_width():
    """The play's output moves only once the input is half the width past it, and a
    reversal leaves it flat for one full width."""
    x = np.concatenate([np.linspace(0, 1, 11), np.linspace(1, 0, 11)[1:]])
    y = play(x, 0.4)
    assert np.allclose(y[:11], np.maximum(x[:11] - 0.2, 0.0))
    assert np.allclose(y[11:15], 0.8)  # the input falls 0.4 before the output follows
    assert np.allclose(y[-1], 0.2)


def test_vane_nonlinearity_is_unexplained_with_its_structure():
    """A sideslip vane read as beta + 6 beta |beta| on the Telemaster, light turbulence:
    the lateral axis is not explained, and the report says an odd function of beta, not a
    catalogue entry."""
    case = Case(0, 31, "telemaster", OUT, (Effect(
        "vane_nonlinearity", "lateral", "measured", {"channel": "beta"}, {"k": 6.0},
        in_catalogue=False),))
    result = diagnose([fly_case(case, "light")], "telemaster", axis="lateral")
    assert result.verdict in (UNEXPLAINED, PARTLY)
    found = result.structure.found
    assert [s.name for s in found] == ["vane_odd"], result.structure.to_json()
    p_level, share_level = LEVELS["vane_odd"]
    assert found[0].test.p_value < p_level and found[0].test.share >= share_level
    text = result.structure.text()
    assert "odd nonlinear function of beta" in text
    assert not any(entry in text for entry in CATALOGUE)
    assert result.axis_json()["structure"]["says"] == text


@pytest.mark.parametrize("turbulence", ["calm", "light"])
def test_null_flight_is_not_flagged(turbulence):
    """The exact aircraft (nothing injected) on both axes: no structure found."""
    record = fly_case(Case(NULL_INDEX, 32, "telemaster", NULL), turbulence)
    result = diagnose([record], "telemaster", try_pairs=False, steps=1)
    for axis, g in result.axes().items():
        assert g.structure is not None and not g.structure.gap, (axis, g.structure.to_json())


def test_surface_backlash_is_not_flagged():
    """An elevator backlash of 1 deg (twice the catalogue's default) is a catalogue entry:
    its response lies in the known set (the surface through a play), so no structure is
    found on the longitudinal axis."""
    case = Case(0, 33, "navion", SINGLE, (Effect(
        "backlash", "longitudinal", "card", {"surface": "de"}, {"width": np.radians(1.0)}),))
    result = diagnose([fly_case(case, "light")], "navion", axis="longitudinal",
                      try_pairs=False, steps=1)
    assert not result.structure.gap, result.structure.to_json()
