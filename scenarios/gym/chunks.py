"""``DecisionChunks``: several decisions per ``step`` call, for vector environments whose
workers cost a pipe round trip per call."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces


class DecisionChunks(gymnasium.Wrapper):
    """Step ``k`` decisions per call: the action is ``(k, 3)``, row i the action of the
    i-th decision (each held for one decision interval, as ``step`` holds one).

    Returns the last decision's observation and ``info``, the sum of the ``k`` rewards,
    and its termination or truncation; an episode that ends within a chunk ends there
    (the chunk's remaining rows are not flown). An episode of n decisions flown in chunks
    is the same flight, with the same return, as flown one decision at a time (tested).
    """

    def __init__(self, env: gymnasium.Env, k: int) -> None:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"k (decisions per call) must be an integer >= 1; got {k!r}")
        super().__init__(env)
        self.k = int(k)
        single = env.action_space
        self.action_space = spaces.Box(np.repeat(single.low[None], self.k, axis=0),
                                       np.repeat(single.high[None], self.k, axis=0),
                                       dtype=single.dtype)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        rows = np.asarray(action)
        if rows.shape != self.action_space.shape:
            raise ValueError(f"action must be {self.k} rows of (de, da, dr), shape "
                             f"{self.action_space.shape}; got shape {rows.shape}")
        total = 0.0
        for row in rows:
            obs, reward, terminated, truncated, info = self.env.step(row)
            total += reward
            if terminated or truncated:
                break
        return obs, total, terminated, truncated, info
