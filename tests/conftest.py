"""Shared test settings: BLAS threads, where the real NASA Twin Otter record lies, and a
card whose flight departs (``departing_card``)."""

import os
from pathlib import Path

import pytest

# thousands of small matrix products: one BLAS thread is faster than several on 2 cores
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# shared/ sits beside the checkout (as in CI: a fresh clone with shared/ next to it);
# FLIGHTID_SHARED overrides it
SHARED = Path(os.environ.get("FLIGHTID_SHARED", Path(__file__).resolve().parents[2] / "shared"))
TWIN_OTTER = SHARED / "data" / "twin_otter" / "totter_f1_017_data.mat"

# the test modules of several minutes' work, marked ``slow`` here in one place:
# ``pytest -m "not slow"`` leaves them out (docs/architecture.md, "Tests"). Seconds: the
# module's setup + call time measured with ``pytest -n 2 --durations=0`` on the shared
# 2-core machine under load (about 2x an idle machine); a module is listed from 20 s.
SLOW_MODULES: dict[str, float] = {
    "contract/test_method_contract.py": 239,
    "aircraft/test_aircraft.py": 225,
    "identification/gap/test_gap_candidates.py": 214,
    "contract/test_effect_fitback.py": 189,
    "identification/gap/test_gap_longitudinal.py": 183,
    "identification/gap/test_gap_report.py": 181,
    "scenarios/montecarlo/test_montecarlo.py": 132,
    "identification/gap/test_gap.py": 126,
    "sim/bridge/test_bridge_badinput.py": 117,
    "identification/test_card_recovery.py": 102,
    "identification/frequency/test_frequency_navion.py": 96,
    "cli/test_cli_identify.py": 88,
    "sim/bridge/test_bridge_properties.py": 84,
    "identification/test_compatibility.py": 82,
    "sim/bridge/test_bridge.py": 79,
    "cli/test_error_policy.py": 77,
    "sim/bridge/test_bridge_identification.py": 75,
    "scenarios/test_demo.py": 73,
    "sim/test_augment.py": 71,
    "flightid/importers/test_import_gap.py": 66,
    "identification/test_truth_recovery.py": 62,
    "cli/test_cli_errors.py": 62,
    "sim/bridge/test_bridge_replay.py": 62,
    "badinput/test_confident.py": 60,
    "scenarios/montecarlo/test_montecarlo_shutdown.py": 59,
    "identification/gap/test_gap_verdict.py": 58,
    "sim/bridge/test_bridge_loop.py": 54,
    "scenarios/montecarlo/test_design_compare.py": 54,
    "scenarios/campaign/test_campaign.py": 52,
    "test_reference_outputs.py": 46,
    "identification/methods/test_nonlinear_6dof.py": 46,
    "scenarios/test_gap_benchmark.py": 42,
    "scenarios/campaign/test_campaign_update.py": 41,
    "cli/test_default_recovery.py": 38,
    "identification/test_default_recovery_cards.py": 213,  # pytest -n 0, the machine lightly loaded
    "identification/frequency/test_frequency_response.py": 29,
    "badinput/test_generated.py": 26,
    "flightid/importers/test_import_ascii.py": 22,
    "flightid/importers/test_import_dataflash.py": 22,
    # added after the tests moved, from ``pytest -n 2 -m "not slow" --durations=40`` at load
    # average 7 (about 3x the load above): the module's slowest tests summed
    "identification/gap/test_gap_envelope.py": 123,
    "identification/methods/test_filter_error.py": 110,
    "identification/gap/test_gap_naming.py": 74,
    "identification/methods/test_mof.py": 65,
    "identification/gap/test_gap_nonlinearity.py": 62,
    "scenarios/montecarlo/test_montecarlo_coverage.py": 54,
    "identification/gap/test_gap_trim_level.py": 51,
    "identification/gap/test_gap_linkage.py": 35,
    "identification/data/test_data_reduction.py": 35,
    "scenarios/gym/test_gym.py": 31,
    "scenarios/montecarlo/test_montecarlo_intervals.py": 27,
    "identification/models/test_lateral_kinematics.py": 25,
    # then from ``--durations=0`` of the quick run (209 s wall at load average 8-9)
    "identification/methods/test_filter_error_noise.py": 24,
    "identification/test_effect_fit.py": 23,
    "identification/test_default_structure.py": 23,
    "scenarios/montecarlo/test_design_optimize.py": 20,
}


def pytest_collection_modifyitems(config, items):
    """Mark every test of a module in ``SLOW_MODULES`` slow."""
    root = Path(__file__).resolve().parent
    for item in items:
        module = Path(str(item.fspath)).resolve().relative_to(root).as_posix()
        if module in SLOW_MODULES:
            item.add_marker(pytest.mark.slow)


# a card whose elevator doublet is far too big: the Navion departs after about 1.3 s (exit 3)
DEPARTING_CARD = """name = "departs"
duration = 6.0
aircraft = "navion"
rate = 50.0
seed = 1

[condition]
altitude = 300.0
speed = 50.0

[[maneuver]]
kind = "doublet"
surface = "de"
start = 0.5
base = 2.0
amplitude_deg = 25.0
"""


@pytest.fixture
def departing_card(tmp_path: Path) -> Path:
    """The departing card written to a file."""
    card = tmp_path / "departs.toml"
    card.write_text(DEPARTING_CARD, encoding="utf-8")
    return card
