"""The gap diagnosis's blind check: cases drawn (an aircraft and an effect of the catalogue,
a pair, an effect outside it, or nothing), flown, diagnosed without being told, and scored
per kind.

``cases`` (what is drawn), ``outside`` (the effects the catalogue cannot express),
``classes`` (effects the data cannot tell apart), ``run`` (fly, diagnose, score one case),
``scoring`` (one case's diagnosis scored), ``summary`` (the figures, overall and per kind),
``study`` (many cases on the Monte Carlo executors, resumable).
"""

from flightid.scenarios.gap_benchmark.cases import AIRCRAFT, KINDS, Case, Effect, draw
from flightid.scenarios.gap_benchmark.run import fly_case, run_case
from flightid.scenarios.gap_benchmark.scoring import CaseResult
from flightid.scenarios.gap_benchmark.study import Benchmark, benchmark, check
from flightid.scenarios.gap_benchmark.summary import TARGETS, summary

__all__ = ["AIRCRAFT", "KINDS", "TARGETS", "Benchmark", "Case", "CaseResult", "Effect",
           "benchmark", "check", "draw", "fly_case", "run_case", "summary"]
