"""The gymnasium environment for excitation-policy research (``flightid/Excitation-v0``).

Importing this package (or ``flightid``) registers the environment by its entry-point
string; the environment module itself (``env``: JSBSim, the flight core) is loaded on
first use of ``ExcitationEnv`` (PEP 562) or by ``gymnasium.make``, its options
(``options``: ``OBS_CHANNELS``, ``PRESETS``) on first use of theirs. gymnasium 1.x has no
plugin entry points, so without an import use its module form::

    gymnasium.make("flightid.scenarios.gym:flightid/Excitation-v0")
"""

from importlib import import_module
from typing import Any

from flightid.scenarios.gym.registration import ENV_ID, register_envs

register_envs()

__all__ = ["ENV_ID", "OBS_CHANNELS", "PRESETS", "DecisionChunks", "ExcitationEnv",
           "register_envs"]
# public name -> its module, imported on first use
_LAZY = {"OBS_CHANNELS": "options", "PRESETS": "options", "ExcitationEnv": "env",
         "DecisionChunks": "chunks"}


def __getattr__(name: str) -> Any:
    """``ExcitationEnv``, ``OBS_CHANNELS``, ``PRESETS`` and ``DecisionChunks``, imported on
    first use (PEP 562)."""
    if name in _LAZY:
        value = getattr(import_module(f"flightid.scenarios.gym.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'flightid.scenarios.gym' has no attribute {name!r}")
