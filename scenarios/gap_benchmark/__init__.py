"""The gap diagnosis's blind check: cases drawn (aircraft, effect, magnitude, including
effects outside the catalogue), flown, diagnosed without being told, and scored.

``cases`` (what is drawn), ``outside`` (the effects the catalogue cannot express),
``run`` (fly, diagnose, score one case; the summary of many), ``study`` (many cases,
written as they finish).
"""

from flightid.scenarios.gap_benchmark.cases import AIRCRAFT, Case, draw
from flightid.scenarios.gap_benchmark.run import CaseResult, fly_case, run_case, summary
from flightid.scenarios.gap_benchmark.study import Benchmark, benchmark

__all__ = ["AIRCRAFT", "Benchmark", "Case", "CaseResult", "benchmark", "draw", "fly_case",
           "run_case", "summary"]
