"""flightid: a testbed for aircraft system identification.

The folders are the architecture (docs/architecture.md): ``aircraft`` (JSBSim definitions and
truth files), ``sim`` (JSBSim flight core, truth, sensors, disturbances, the recorder
bridge ``sim/bridge/``), ``identification`` (estimation methods), ``scenarios`` (inputs,
flight cards, Monte Carlo), ``cli`` (the command line). They install as
``flightid.aircraft``, ``flightid.sim``, ``flightid.identification``,
``flightid.scenarios`` and ``flightid.cli``; this package holds the shared types: the
flight record, channel and derivative names, and unit conversions.

The public API is ``flightid.api``'s; its names are attributes of this package, loaded on
first use (PEP 562), so that ``import flightid`` loads neither the simulator nor the
methods. Importing it registers the excitation environment with gymnasium by its
entry-point string (``flightid.scenarios.gym.registration``), without importing it.

Layers (import-linter, ``[tool.importlinter]`` in pyproject.toml, ``.ci/lint-imports``):
cli > scenarios > identification > sim > aircraft > record/naming; a module imports only
from layers below its own. This file is in no layer; a lower module must therefore not
import the root package itself (``import flightid``, ``from flightid import
__version__``) once it re-exports from higher layers: the chain through it counts.
"""

from importlib import import_module
from typing import Any

from flightid.scenarios.gym.registration import register_envs

__version__ = "0.1.0"

# the public API, listed once: the same names in flightid.api's docstring and __all__ and
# in docs/architecture.md (tests/flightid/test_public_api.py checks all three)
__all__ = ["EXCITATION_ENV", "Estimate", "Flight", "FlightRecord", "Score", "__version__",
           "design_compare", "fly", "gap", "gap_benchmark", "identify", "methods",
           "montecarlo", "read", "score", "truth"]

register_envs()


def __getattr__(name: str) -> Any:
    """A name of the public API, imported from ``flightid.api`` on first use (PEP 562)."""
    if name in __all__:
        value = getattr(import_module("flightid.api"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'flightid' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
