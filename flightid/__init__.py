"""flightid: a testbed for aircraft system identification.

The folders are the architecture (docs/architecture.md): ``aircraft`` (JSBSim definitions and
truth files), ``sim`` (JSBSim flight core, truth, sensors, disturbances, the recorder
bridge ``sim/bridge/``), ``identification`` (estimation methods), ``scenarios`` (inputs,
flight cards, Monte Carlo), ``cli`` (the command line). They install as
``flightid.aircraft``, ``flightid.sim``, ``flightid.identification``,
``flightid.scenarios`` and ``flightid.cli``; this package holds the shared types: the
flight record, channel and derivative names, and unit conversions.

Layers (import-linter, ``[tool.importlinter]`` in pyproject.toml, ``.ci/lint-imports``):
cli > scenarios > identification > sim > aircraft > record/naming; a module imports only
from layers below its own. This file is in no layer; a lower module must therefore not
import the root package itself (``import flightid``, ``from flightid import
__version__``) once it re-exports from higher layers: the chain through it counts.
"""

__version__ = "0.1.0"

from flightid.api import (  # noqa: E402
    Flight,
    fly,
    gap,
    identify,
    methods,
    montecarlo,
    score,
    truth,
)

__all__ = ["Flight", "__version__", "fly", "gap", "identify", "methods", "montecarlo", "score",
           "truth"]
