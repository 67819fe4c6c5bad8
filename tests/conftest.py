"""Shared test settings: BLAS threads, and where the real NASA Twin Otter record lies."""

import os
from pathlib import Path

# thousands of small matrix products: one BLAS thread is faster than several on 2 cores
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# shared/ sits beside the checkout (as in CI: a fresh clone with shared/ next to it);
# FLIGHTID_SHARED overrides it
SHARED = Path(os.environ.get("FLIGHTID_SHARED", Path(__file__).resolve().parents[2] / "shared"))
TWIN_OTTER = SHARED / "data" / "twin_otter" / "totter_f1_017_data.mat"
