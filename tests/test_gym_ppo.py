"""A smoke training of the PPO baseline (benchmarks/gym_ppo.py) on flightid/Excitation-v0:
stable-baselines3 is an optional extra (``.[rl]``), so the test is skipped without it."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

sb3 = pytest.importorskip("stable_baselines3")
torch = pytest.importorskip("torch")

from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

from flightid.scenarios.gym import ENV_ID, ExcitationEnv  # noqa: E402
from flightid.scenarios.gym.baselines import AMPLITUDE, closed_loop, run_episode  # noqa: E402


def _travel(env: gymnasium.Env) -> gymnasium.Env:
    return gymnasium.wrappers.TransformAction(env, lambda a: AMPLITUDE * a, env.action_space)


def _train(seed: int) -> sb3.PPO:
    torch.set_num_threads(1)
    venv = make_vec_env(ENV_ID, n_envs=2, seed=100, wrapper_class=_travel,
                        env_kwargs={"observation": "scaled", "episode_s": 1.0})
    model = sb3.PPO("MlpPolicy", venv, seed=seed, n_steps=64, batch_size=64, n_epochs=2,
                    device="cpu")
    return model.learn(total_timesteps=256)


def test_ppo_smoke_training_is_deterministic_and_evaluates_like_the_baselines():
    """Two trainings with the same seed give the same agent; its deterministic policy,
    flown on a held-out seed through ``closed_loop``, stays within 0.2 of travel and its
    return is the same flown open loop (the evaluation of benchmarks/gym_ppo.py)."""
    agents = [_train(0), _train(0)]
    env = ExcitationEnv(episode_s=1.0)
    schedules = [closed_loop(lambda o, m=m: m.predict(o.astype(np.float32),
                                                      deterministic=True)[0])(env, 0)
                 for m in agents]
    np.testing.assert_array_equal(schedules[0], schedules[1])
    assert 0.0 < np.abs(schedules[0]).max() <= AMPLITUDE
    closed = env.unwrapped._logdet
    total, info, terminated = run_episode(env, schedules[0], 0)
    assert info["logdet"] == closed and np.isfinite(total)
