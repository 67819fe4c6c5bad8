"""A smoke training of the PPO baseline (benchmarks/gym_ppo.py) on flightid/Excitation-v0:
stable-baselines3 is an optional extra (``.[rl]``), so the test is skipped without it."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

from tests import benchmark_scripts

sb3 = pytest.importorskip("stable_baselines3")
torch = pytest.importorskip("torch")

from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

from flightid.scenarios.gym import ENV_ID, ExcitationEnv  # noqa: E402
from flightid.scenarios.gym.baselines import evaluate, run_episode  # noqa: E402
from flightid.scenarios.gym.policies import AMPLITUDE, closed_loop, multisine  # noqa: E402


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


def test_clone_and_best_checkpoint_on_training_seeds():
    """benchmarks/gym_bc_ppo.py: the cloned policy flies the multisine it copies (same
    accuracy return on the selection seeds, to the float32 rounding of its actions), and
    the checkpoint kept is the best of those evaluated, whose weights score the same when
    evaluated again (the selection is deterministic)."""
    bc = benchmark_scripts.load("gym_bc_ppo")
    torch.set_num_threads(1)
    episode_s, seeds = 2.0, (100, 101)
    scale = bc.LIMITS["0.2"]
    env = ExcitationEnv(episode_s=episode_s, reward="accuracy")
    venv = make_vec_env(ENV_ID, n_envs=2, seed=100,
                        env_kwargs={"observation": "scaled", "reward": "accuracy",
                                    "episode_s": episode_s},
                        wrapper_class=lambda e: bc.TimeFeatures(bc.travel_limit(e, scale)))
    model = sb3.PPO("MlpPolicy", venv, seed=0, n_steps=100, batch_size=100, n_epochs=2,
                    learning_rate=1e-3, device="cpu",
                    policy_kwargs={"net_arch": {"pi": [], "vf": [8]}, "log_std_init": -1.0})
    demo = multisine(env, 0, *bc.DEMOS["0.2"])
    assert bc.clone(model, env, demo, scale) < 1e-9  # the demo is a sum of the features
    def score(m):
        return evaluate(env, "s", bc.policy_schedule(m, scale, True, episode_s), seeds)

    selection = bc.BestCheckpoint(score, every=1)
    selection.check(model)
    demo_return = np.mean(evaluate(env, "demo", lambda e, s: multisine(e, s, *bc.DEMOS["0.2"]),
                                   seeds).returns)
    assert selection.history[0][1] == pytest.approx(demo_return, abs=1e-3)
    model.learn(total_timesteps=400, callback=selection, reset_num_timesteps=False)
    assert len(selection.history) == 3  # the clone and two rollouts of 2 x 100
    means = [h[1] for h in selection.history]
    assert selection.best == max(means)
    assert selection.best_timesteps == selection.history[int(np.argmax(means))][0]
    again = np.mean(score(bc.snapshot(model, selection.best_state)).returns)
    assert again == selection.best
