"""The gymnasium environment for excitation-policy research (``flightid/Excitation-v0``).

Importing this package registers the environment; gymnasium 1.x has no plugin entry
points, so without an import use its module form::

    gymnasium.make("flightid.scenarios.gym:flightid/Excitation-v0")
"""

from flightid.scenarios.gym.chunks import DecisionChunks
from flightid.scenarios.gym.env import OBS_CHANNELS, PRESETS, ExcitationEnv
from flightid.scenarios.gym.registration import ENV_ID, register_envs

register_envs()

__all__ = ["ENV_ID", "OBS_CHANNELS", "PRESETS", "DecisionChunks", "ExcitationEnv",
           "register_envs"]
