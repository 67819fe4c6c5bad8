"""Shared test settings: where the real NASA Twin Otter record lies."""

import os
from pathlib import Path

# shared/ sits beside the checkout (as in CI: a fresh clone with shared/ next to it);
# FLIGHTID_SHARED overrides it
SHARED = Path(os.environ.get("FLIGHTID_SHARED", Path(__file__).resolve().parents[2] / "shared"))
TWIN_OTTER = SHARED / "data" / "twin_otter" / "totter_f1_017_data.mat"
