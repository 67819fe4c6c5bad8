"""Benchmark: output error on the NASA Twin Otter lateral record (Morelli & Klein ex. 6.1).

The published 18-parameter model (13 derivatives, 5 biases), 1001 samples at 50 Hz,
on one core. Times ``output_error.estimate`` from the equation-error start values (as
in the book) and from the model's generic start values; median of several runs.
Writes benchmarks/results/output_error.txt. Run:
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_output_error.py
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, before numpy loads

import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from flightid.identification.methods import output_error as oe  # noqa: E402
from flightid.identification.models import linear as lm  # noqa: E402
from flightid.identification.models.reference_condition import condition_from_record  # noqa: E402
from flightid.record import read  # noqa: E402

# the record where the tests find it (tests/conftest.py: shared/ beside the checkout, or
# FLIGHTID_SHARED)
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import TWIN_OTTER as DATA  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "output_error.txt"
RUNS = 15
TARGET_S = 0.3  # the project's target; NASA's SIDPAC oe.m needs about 1.5 s


def _time(fn, runs: int = RUNS) -> tuple[float, list[float], object]:
    times, out = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), times, out


def main() -> str:
    """Run the benchmark, write the results file, return its text."""
    record = read(DATA)
    model = lm.lateral(condition_from_record(record))
    ee_start = oe.start_from_equation_error(record, model)
    lines = [
        "output error, Twin Otter lateral (totter_f1_017), 18 parameters, "
        f"{len(record)} samples, one core",
        f"python {platform.python_version()}, numpy {np.__version__}, "
        f"machine {platform.machine()} {platform.processor() or ''}".rstrip(),
        f"target < {TARGET_S} s per fit (SIDPAC oe.m about 1.5 s)",
        "",
    ]
    for label, kwargs in (
        ("equation-error start (as in the book)", {"start": ee_start}),
        ("generic start values", {}),
        ("equation-error start, colored-residual bounds", {"start": ee_start, "colored": True}),
    ):
        median, times, est = _time(lambda kw=kwargs: oe.estimate(record, model, **kw))
        lines.append(
            f"{label}: median {median * 1e3:.1f} ms (min {min(times) * 1e3:.1f}, "
            f"max {max(times) * 1e3:.1f}, {len(times)} runs), {est.fit['iterations']} "
            f"iterations, converged={est.fit['converged']}, "
            f"{'meets' if median < TARGET_S else 'MISSES'} the target"
        )
    text = "\n".join(lines) + "\n"
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(text)
    return text


if __name__ == "__main__":
    print(main(), end="")
