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
