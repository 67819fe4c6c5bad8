"""Registration of ``flightid/Excitation-v0`` in gymnasium's registry."""

from __future__ import annotations

import gymnasium

ENV_ID = "flightid/Excitation-v0"


def register_envs() -> None:
    """Register the environment (idempotent)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point="flightid.scenarios.gym.env:ExcitationEnv")
