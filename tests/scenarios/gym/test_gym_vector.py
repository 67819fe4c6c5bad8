"""The vector-environment benchmark's episodes (benchmarks/gym_vector.py): any number of
decisions per worker call flies the whole episode, and the async workers' flight is the
sequential one on the same seeds. No timing is asserted (the figures are in
benchmarks/results)."""

from __future__ import annotations

from functools import partial

import gymnasium
import numpy as np
import pytest

from flightid.scenarios.gym import DecisionChunks, ExcitationEnv
from flightid.scenarios.gym.policies import three211
from tests import benchmark_scripts

vector_bench = benchmark_scripts.load("gym_vector")


def test_chunk_rows_cover_the_episode_for_any_chunk_size():
    """50 decisions of 2 workers: chunks of 7 are 8 calls, the last padded with 6 zero
    rows; chunks of 50 and of 1000 (more than the episode: the crash of ``--chunks 1000``)
    are one call; 0 is refused naming the option."""
    batch = np.arange(50 * 2 * 3, dtype=np.float32).reshape(50, 2, 3) + 1.0
    for k, calls in ((7, 8), (50, 1), (1000, 1)):
        rows = vector_bench.chunk_rows(batch, k)
        assert rows.shape == (calls, 2, k, 3)
        flat = rows.swapaxes(1, 2).reshape(calls * k, 2, 3)
        np.testing.assert_array_equal(flat[:50], batch)
        assert not flat[50:].any()
    with pytest.raises(ValueError, match=r"--chunks: decisions per call must be integers >= 1"):
        vector_bench.chunk_rows(batch, 0)


def _sequential(actions: np.ndarray, seed: int) -> tuple[np.ndarray, list[float]]:
    """The final observation and the rewards of one environment stepped in this process."""
    env = ExcitationEnv(episode_s=1.0)
    env.reset(seed=seed)
    steps = [env.step(a) for a in actions]
    assert steps[-1][3] and not any(s[3] for s in steps[:-1])
    return steps[-1][0], [s[1] for s in steps]


@pytest.mark.parametrize("k", [7, 50, 1000])
def test_async_chunked_workers_fly_the_sequential_episodes(k):
    """``AsyncVectorEnv`` of 2 ``DecisionChunks`` workers, seeds 3 and 4, the calls of
    ``chunk_rows``: the last call truncates both episodes, the final observation is the
    sequential one bit for bit and each call's reward the sum of its decisions' rewards
    (the same additions, so equal, not close), for a chunk that divides the 50 decisions,
    one that does not, and one longer than the episode."""
    seeds = [3, 4]
    actions = three211(ExcitationEnv(episode_s=1.0), 0)[:50].astype(np.float32) * 4.0
    want = [_sequential(actions, s) for s in seeds]
    rows = vector_bench.chunk_rows(np.repeat(actions[:, None], len(seeds), axis=1), k)
    venv = gymnasium.vector.AsyncVectorEnv(
        [partial(lambda k: DecisionChunks(ExcitationEnv(episode_s=1.0), k), k)] * len(seeds))
    try:
        venv.reset(seed=seeds)
        for j, call in enumerate(rows):
            obs, reward, terminated, truncated, _ = venv.step(call)
            assert not terminated.any() and truncated.all() == (j == len(rows) - 1)
            for i, (_, rewards) in enumerate(want):
                total = 0.0
                for r in rewards[j * k:(j + 1) * k]:
                    total += r
                assert reward[i] == total
        np.testing.assert_array_equal(obs, np.array([o for o, _ in want]))
    finally:
        venv.close()


def test_same_step_autoreset_of_chunked_workers_flies_the_sequential_episodes():
    """``autoreset_mode=SameStep`` with ``DecisionChunks`` of 7 and episodes of 50 and 40
    decisions (they end in different calls): the call that ends an episode returns its
    final observation in ``info['final_obs']`` and the next episode's first observation,
    and the next episode is the one a sequential environment flies after ``reset()``;
    no call flies nothing (under NextStep the call after an end only resets)."""
    k, lengths, seeds = 7, [1.0, 0.8], [3, 4]
    actions = three211(ExcitationEnv(episode_s=1.0), 0)[:50].astype(np.float32) * 4.0
    want_end, want_next = [], []
    for s, length in zip(seeds, lengths, strict=True):
        env = ExcitationEnv(episode_s=length)
        env.reset(seed=s)
        n = int(round(length * env.decision_hz))
        want_end.append([env.step(a) for a in actions[:n]][-1][0])
        obs, _ = env.reset()
        want_next.append([obs] + [env.step(a)[0] for a in actions[:k]])
    venv = gymnasium.vector.AsyncVectorEnv(
        [partial(lambda k, s: DecisionChunks(ExcitationEnv(episode_s=s), k), k, s)
         for s in lengths],
        autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP, observation_mode="different")
    try:
        venv.reset(seed=seeds)
        rows = vector_bench.chunk_rows(np.repeat(actions[:, None], 2, axis=1), k)
        ended = [None, None]
        for j, call in enumerate(rows):
            obs, _, terminated, truncated, info = venv.step(call)
            assert not terminated.any()
            for i in np.flatnonzero(truncated):
                np.testing.assert_array_equal(info["final_obs"][i], want_end[i])
                np.testing.assert_array_equal(obs[i], want_next[i][0])
                ended[i] = j
        assert ended == [7, 5]  # 50 decisions end in call 8 of 7, 40 in call 6
        first = np.zeros((2, k, 3), np.float32)
        first[:] = actions[:k]
        obs = venv.step(first)[0]  # worker 0 starts its second episode now, worker 1 did
        np.testing.assert_array_equal(obs[0], want_next[0][k])
    finally:
        venv.close()
