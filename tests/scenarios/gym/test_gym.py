"""The gymnasium environment flightid/Excitation-v0 (scenarios/gym)."""

from __future__ import annotations

import subprocess
import sys
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from flightid.identification.identify import identify
from flightid.scenarios.gym import ENV_ID, OBS_CHANNELS, DecisionChunks, ExcitationEnv
from flightid.scenarios.gym.baselines import cross_entropy, evaluate, per_target, plot, run_episode
from flightid.scenarios.gym.information import Information
from flightid.scenarios.gym.options import LINEAR_RANGE, OBSERVATIONS, REWARDS, SIGMA
from flightid.scenarios.gym.policies import (
    AMPLITUDE,
    closed_loop,
    doublet,
    full_rudder,
    multisine,
    three211,
    zero,
)

SEEDS = (0, 1)


@pytest.fixture(scope="module")
def env() -> ExcitationEnv:
    return ExcitationEnv(render_mode="rgb_array")


def test_check_env(env):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "no spec" note: made directly, not through make
        check_env(env)


@pytest.mark.parametrize("reward", REWARDS)
@pytest.mark.parametrize("observation", OBSERVATIONS)
def test_check_env_for_every_reward_and_observation(reward, observation):
    e = ExcitationEnv(reward=reward, observation=observation, episode_s=2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(e)


def test_make_by_id():
    e = gymnasium.make(ENV_ID, episode_s=1.0)
    obs, _ = e.reset(seed=3)
    assert obs.shape == (len(OBS_CHANNELS),)
    obs, r, term, trunc, info = e.step(e.action_space.sample())
    assert np.isfinite(r) and "crb" in info
    e.close()


def test_make_in_fresh_interpreter_by_module_form():
    # gymnasium 1.x has no plugin entry points: the documented "module:id" form imports us
    code = ("import gymnasium; e = gymnasium.make('flightid.scenarios.gym:flightid/Excitation-v0',"
            " episode_s=0.1); e.reset(seed=0); print(e.unwrapped.targets[0])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "Cl_beta"


def _single_episodes(actions: np.ndarray, seeds) -> tuple[np.ndarray, np.ndarray]:
    """Observations (steps, envs, channels) and rewards (steps, envs) of one environment
    stepped in this process, episode by episode."""
    obs, rewards = [], []
    for s in seeds:
        e = ExcitationEnv(episode_s=1.0)
        o, _ = e.reset(seed=s)
        ep_obs, ep_r = [o], []
        for a in actions:
            o, r, *_ = e.step(a)
            ep_obs.append(o)
            ep_r.append(r)
        obs.append(ep_obs)
        rewards.append(ep_r)
    return np.swapaxes(obs, 0, 1), np.array(rewards).T


@pytest.mark.parametrize("vector", [gymnasium.vector.SyncVectorEnv,
                                    gymnasium.vector.AsyncVectorEnv])
def test_vector_envs_step_the_same_episodes_as_one_env(vector):
    """Sync (one process) and async (a worker process each) vector environments give the
    single environment's episodes bit for bit on the same seeds, then reset themselves
    after the 50-decision episodes end (gymnasium's next-step autoreset: a reward of 0)."""
    seeds = [0, 1, 2]
    actions = three211(ExcitationEnv(episode_s=1.0), 0)[:50].astype(np.float32) * 4.0
    want_obs, want_r = _single_episodes(actions, seeds)
    venv = vector([lambda: ExcitationEnv(episode_s=1.0)] * len(seeds))
    obs, info = venv.reset(seed=seeds)
    got_obs, got_r = [obs], []
    for a in actions:
        obs, r, term, trunc, info = venv.step(np.repeat(a[None], len(seeds), axis=0))
        got_obs.append(obs)
        got_r.append(r)
    assert trunc.all() and not term.any() and info["crb"].shape == (len(seeds), 10)
    np.testing.assert_array_equal(np.array(got_obs), want_obs)
    np.testing.assert_array_equal(np.array(got_r), want_r)
    obs, r, term, trunc, _ = venv.step(np.zeros((len(seeds), 3), np.float32))  # autoreset
    np.testing.assert_array_equal(r, 0.0)
    np.testing.assert_allclose(obs[:, 0], 0.0, atol=1e-12)  # t = 0: a fresh episode
    venv.close()


def test_decision_chunks_fly_the_same_episode():
    """``DecisionChunks``: 50 decisions in chunks of 7 (the last chunk ends the episode
    after its first row) are the decision-by-decision flight: the same final observation
    and info, the same return to rounding; a bad chunk size or shape is refused."""
    actions = three211(ExcitationEnv(episode_s=1.0), 0)[:50].astype(np.float32) * 4.0
    one = ExcitationEnv(episode_s=1.0)
    one.reset(seed=5)
    single = [one.step(a) for a in actions]
    chunked = DecisionChunks(ExcitationEnv(episode_s=1.0), 7)
    chunked.reset(seed=5)
    padded = np.vstack([actions, np.zeros((6, 3), np.float32)]).reshape(8, 7, 3)
    steps = [chunked.step(c) for c in padded]
    assert [s[3] for s in steps] == [False] * 7 + [True]  # truncated in the last chunk
    assert sum(s[1] for s in steps) == pytest.approx(sum(r[1] for r in single), rel=1e-12)
    assert single[-1][3] and not any(r[3] for r in single[:-1])
    np.testing.assert_array_equal(steps[-1][0], single[-1][0])
    np.testing.assert_array_equal(steps[-1][4]["estimate"], single[-1][4]["estimate"])
    assert chunked.unwrapped._k == one.unwrapped._k == 50
    with pytest.raises(ValueError, match=r"k \(decisions per call\) must be an integer >= 1"):
        DecisionChunks(ExcitationEnv(episode_s=1.0), 0)
    with pytest.raises(ValueError, match=r"action must be 7 rows of \(de, da, dr\)"):
        chunked.step(np.zeros(3, np.float32))


def test_decision_chunks_in_async_workers_give_the_one_by_one_episodes():
    """``AsyncVectorEnv`` of ``DecisionChunks`` of 10 (one pipe round trip per 10
    decisions), seeds 0 and 1: after each chunk, each worker's observation is the single
    environment's at that decision bit for bit, its reward the sum of that chunk's
    rewards (the same additions), and the 50-decision episode is truncated in the last
    chunk."""
    seeds, k = [0, 1], 10
    actions = three211(ExcitationEnv(episode_s=1.0), 0)[:50].astype(np.float32) * 4.0
    want_obs, want_r = _single_episodes(actions, seeds)  # (51, 2, 16), (50, 2)
    venv = gymnasium.vector.AsyncVectorEnv(
        [lambda: DecisionChunks(ExcitationEnv(episode_s=1.0), k)] * len(seeds))
    obs, _ = venv.reset(seed=seeds)
    np.testing.assert_array_equal(obs, want_obs[0])
    for j, chunk in enumerate(actions.reshape(-1, k, 3)):
        obs, r, term, trunc, _ = venv.step(np.repeat(chunk[None], len(seeds), axis=0))
        np.testing.assert_array_equal(obs, want_obs[(j + 1) * k])
        for i in range(len(seeds)):
            total = 0.0
            for reward in want_r[j * k:(j + 1) * k, i]:
                total += reward
            assert r[i] == total
        assert not term.any() and trunc.all() == (j == len(actions) // k - 1)
    venv.close()


def test_a_feedback_policy_flown_open_loop_is_the_same_flight(env):
    """``closed_loop``: a feedback law (yaw damper and roll-rate feedback on the scaled
    observation, plus a rudder pulse) flown on a seed, then its actions flown open loop on
    the same seed, give the same return and estimate: the environment is deterministic,
    so a learned policy is evaluated beside the schedules by the same code."""
    def law(obs: np.ndarray) -> np.ndarray:
        t, p, r = obs[0], obs[OBS_CHANNELS.index("p")], obs[OBS_CHANNELS.index("r")]
        return np.array([0.0, -2.0 * p, (1.0 if 0.05 < t < 0.1 else 0.0) - r])

    schedule = closed_loop(law)
    actions = schedule(env, 4)
    assert np.abs(actions).max() == pytest.approx(0.2)  # scaled to the baselines' travel
    flown = env.unwrapped._actions[1:]
    np.testing.assert_array_equal(np.array(flown, dtype=np.float32),
                                  actions[:len(flown)].astype(np.float32))
    logdet = env.unwrapped._logdet
    total, info, terminated = run_episode(env, actions, 4)
    assert not terminated and info["logdet"] == logdet
    assert total > run_episode(env, zero(env, 4), 4)[0]


def test_same_seed_same_observations():
    def episode(seed: int) -> np.ndarray:
        e = ExcitationEnv(episode_s=2.0)
        obs, _ = e.reset(seed=seed)
        out = [obs]
        for a in doublet(e, seed)[:100]:
            out.append(e.step(a.astype(np.float32))[0])
        return np.array(out)

    a, b, c = episode(7), episode(7), episode(8)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def _returns(env: ExcitationEnv, schedule) -> list[float]:
    return [run_episode(env, schedule(env, s), s)[0] for s in SEEDS]


def test_returns_order(env):
    # measured (benchmarks/results/gym_baselines.txt): zero 24, doublet 120, 3211 123,
    # multisine 127 on every seed
    r = {name: _returns(env, f) for name, f in
         (("zero", zero), ("doublet", doublet), ("3211", three211), ("multisine", multisine))}
    for s in range(len(SEEDS)):
        assert r["zero"][s] < r["doublet"][s] < r["3211"][s] < r["multisine"][s]


def test_full_rudder_to_the_bank_limit_scores_below_the_3211(env):
    """Under the default reward a flight that leaves the envelope forfeits its information:
    the full-rudder policy returns exactly -penalty, the 3211 its information (123)."""
    assert env.reward == "valid-information"
    for s in SEEDS:
        rudder, info, terminated = run_episode(env, full_rudder(env, s), s)
        assert terminated and "bank" in info["departure"]
        assert rudder == pytest.approx(-env.penalty, abs=1e-9)
        assert rudder < run_episode(env, three211(env, s), s)[0]


def test_information_outside_the_linear_range_counts_only_under_the_old_reward():
    """The same full-rudder flight (the flight does not depend on the reward) under both
    rewards: where the default reward's validity weight is 0 (the flight beyond twice the
    linear range), the "information" reward still pays for the samples, the default pays
    nothing."""
    valid, old = ExcitationEnv(), ExcitationEnv(reward="information")
    steps = {}
    for e in (valid, old):
        e.reset(seed=0)
        steps[e.reward] = []
        for a in full_rudder(e, 0):
            _, r, term, trunc, info = e.step(a.astype(np.float32))
            steps[e.reward].append((r, info["validity"]))
            if term:
                break
    outside = [i for i, (_, w) in enumerate(steps["valid-information"][:-1]) if w == 0.0]
    assert len(outside) > 10
    assert all(steps["valid-information"][i][0] == 0.0 for i in outside)
    assert all(steps["information"][i][0] > 0.0 for i in outside)
    assert all(w == 1.0 for _, w in steps["information"])


def test_validity_weight_is_the_documented_formula_on_the_flown_record():
    """The weight of each sample, recomputed from the re-flown record (the truth, at the
    decision instants) with the documented formula and ``LINEAR_RANGE``: the larger
    multisine (0.42 of travel) gives weights of 1, between 0 and 1, and none of 0."""
    e = ExcitationEnv(sensors="ideal", episode_s=10.0)
    e.reset(seed=2)
    weights = [e.step(a.astype(np.float32))[4]["validity"]
               for a in multisine(e, 2, 0.42, 0.42, 1.27)]
    rec = e.record(measured=False)
    lr = LINEAR_RANGE
    ranges = {"alpha": np.radians(lr["alpha_deg"]), "beta": np.radians(lr["beta_deg"]),
              "p": np.radians(lr["p_deg_s"]), "q": np.radians(lr["q_deg_s"]),
              "r": np.radians(lr["r_deg_s"]), "V": lr["speed_ratio"] * e.trim.speed_m_s}
    d = np.max([np.abs(rec[c][1:] - rec[c][0]) / r for c, r in ranges.items()], axis=0)
    np.testing.assert_allclose(weights, np.clip(2.0 - d, 0.0, 1.0), rtol=0, atol=1e-12)
    w = np.array(weights)
    assert np.any(w == 1.0) and np.any((w > 0.0) & (w < 1.0)) and w.min() > 0.0


def test_accuracy_return_is_one_minus_the_final_relative_error():
    """reward="accuracy": the rewards telescope to 100 (1 - mean min(|error| / |truth|, 1))
    of the final estimate; the 3211 scores above the zero input on each seed (measured:
    96.1 and 94.8 against 8.0 and 17.9) and the full rudder returns -penalty."""
    e = ExcitationEnv(reward="accuracy")
    truth = np.abs(e._truth_vec)
    for s in SEEDS:
        total, info, _ = run_episode(e, three211(e, s), s)
        rel = np.minimum(np.abs(info["error"]) / truth, 1.0)
        assert total == pytest.approx(100.0 * (1.0 - rel.mean()), abs=1e-9)
        assert total > run_episode(e, zero(e, s), s)[0] + 50.0
        assert run_episode(e, full_rudder(e, s), s)[0] == pytest.approx(-e.penalty, abs=1e-9)


@pytest.mark.parametrize("schedule", [doublet, three211, multisine])
def test_baselines_inside_the_linear_range_score_the_same_under_both_rewards(schedule):
    """Inputs of 0.2 of travel stay inside the linear range: every weight is 1, so the
    default reward's return is the information reward's, to rounding."""
    valid, old = ExcitationEnv(), ExcitationEnv(reward="information")
    a = run_episode(valid, schedule(valid, 0), 0)
    b = run_episode(old, schedule(old, 0), 0)
    assert a[0] == pytest.approx(b[0], rel=1e-12) and a[1]["validity"] == 1.0
    np.testing.assert_array_equal(a[1]["estimate"], b[1]["estimate"])


def test_scaled_observations_are_the_si_ones_about_trim_over_the_scales():
    si, scaled = ExcitationEnv(episode_s=2.0), ExcitationEnv(episode_s=2.0, observation="scaled")
    np.testing.assert_array_equal(si.obs_scale, scaled.obs_scale)
    first = [si.reset(seed=3)[0]], [scaled.reset(seed=3)[0]]
    for a in doublet(si, 3)[:100]:
        first[0].append(si.step(a.astype(np.float32))[0])
        first[1].append(scaled.step(a.astype(np.float32))[0])
    raw, norm = np.array(first[0]), np.array(first[1])
    np.testing.assert_allclose(norm, (raw - si.obs_center) / si.obs_scale, rtol=0, atol=1e-12)
    assert norm[-1, OBS_CHANNELS.index("t")] == pytest.approx(1.0)
    # the doublet's 0.2 of travel on the aileron reads at most 0.2 of da's scale (the
    # larger side of its travel), plus the research suite's noise on da (5 sigma)
    i = OBS_CHANNELS.index("da")
    assert np.abs(norm[:, i]).max() <= 0.2 + 5 * si._sigma_obs[i] / si.obs_scale[i]
    assert np.all(np.abs(norm[:, 1:]) < 2.0)  # a small input stays within a few scales


def test_full_up_elevator_terminates_with_penalty(env):
    env.reset(seed=0)
    action = np.array([-1.0, 0.0, 0.0], dtype=np.float32)  # -de: trailing edge up
    for _ in range(env.n_decisions):
        _, r, term, trunc, info = env.step(action)
        if term or trunc:
            break
    assert term and not trunc
    assert r < -env.penalty / 2
    assert "alpha" in info["departure"] or "load factor" in info["departure"]


def test_info_bounds_and_truth_error(env):
    _, info, _ = run_episode(env, multisine(env, 0), 0)
    truth = np.abs(env._truth_vec)
    assert info["crb"].shape == (len(env.targets),)
    assert np.all(info["crb"] / truth < 0.5)
    assert np.mean(np.abs(info["error"]) / truth) < 0.2


def test_record_identifies(env):
    run_episode(env, multisine(env, 1), 1)
    rec = env.record()
    assert rec.time.size == env.n_decisions * env.sim_per_decision + 1
    est = identify(rec, "ee", "lateral", window="none")
    assert np.all(np.isfinite(est.values))


@pytest.mark.parametrize("turbulence", ["none", "light"])
def test_record_is_the_episode_that_was_stepped(turbulence):
    """A step reads only what it observes; ``record()`` flies the episode again from its
    actions. With ideal sensors the observations are the truth: the re-flown record must
    hold them bit for bit, at every decision (here two record samples per decision)."""
    e = ExcitationEnv(episode_s=2.0, sim_hz=100.0, sensors="ideal", turbulence=turbulence)
    obs, _ = e.reset(seed=5)
    seen = [obs]
    rng = np.random.default_rng(5)
    for _ in range(e.n_decisions):
        seen.append(e.step(rng.uniform(-0.3, 0.3, 3).astype(np.float32))[0])
    rec = e.record(measured=False)
    assert len(rec) == e.n_decisions * 2 + 1
    for i, c in enumerate(OBS_CHANNELS[1:], start=1):
        np.testing.assert_array_equal(rec[c][::2], np.array(seen)[:, i], err_msg=c)


def test_record_before_a_step_is_refused():
    e = ExcitationEnv(episode_s=1.0)
    e.reset(seed=0)
    with pytest.raises(ValueError, match="no step since reset"):
        e.record()


def test_information_updates_equal_the_batch_formulas():
    """The rank-one updates give log det M, M^-1 and the estimate M^-1 X^T W y of the batch
    regularised least squares (M = I + X^T X / sigma^2) to rounding, for two coefficients
    sharing a design and one with its own (CY has another sigma)."""
    spec = [("Cl", ("beta", "p")), ("Cn", ("beta", "p")), ("CY", ("beta", "p"))]
    info = Information(spec)
    rng = np.random.default_rng(0)
    X = np.column_stack([np.ones(300), rng.normal(0.0, 0.05, (300, 2))])
    Y = X @ rng.normal(0.0, 0.2, (3, 3)).T + rng.normal(0.0, 1e-3, (300, 3))
    for x, y in zip(X, Y, strict=True):
        info.add([x.tolist()] * 2, y.tolist())
    logdet = 0.0
    for g, (coef, _) in enumerate(spec):
        M = np.eye(3) + X.T @ X / SIGMA[coef] ** 2
        estimate = np.linalg.solve(M, X.T @ Y[:, g] / SIGMA[coef] ** 2)
        np.testing.assert_allclose(info.theta[g], estimate, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(info.inv[0 if g < 2 else 1], np.linalg.inv(M),
                                   rtol=1e-7, atol=1e-15)
        logdet += np.linalg.slogdet(M)[1]
    assert info.logdet_m == pytest.approx(logdet, rel=1e-10)  # 300 updates' rounding


def test_per_target_tables_and_plot(tmp_path):
    e = ExcitationEnv(episode_s=10.0)  # the rudder doublet is at 6-8 s
    results = [evaluate(e, "zero", zero, [0]), evaluate(e, "doublet", doublet, [0])]
    lines = per_target(e, results)
    bounds = np.array([float(v) for v in lines[3].split()[1:]])  # the doublet's row
    assert bounds.shape == (len(e.targets),)
    # a doublet gathers information on every target: its bounds are below the zero input's
    assert np.all(bounds < np.array([float(v) for v in lines[2].split()[1:]]))
    path = plot(e, results, tmp_path / "baselines.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_malformed_action_is_refused_by_name():
    e = ExcitationEnv(episode_s=1.0)
    e.reset(seed=0)
    for bad in ([0.1, 0.2], [[0.0, 0.0, 0.0]], [0.0, float("nan"), 0.0], 0.5):
        with pytest.raises(ValueError, match=r"action must be 3 numbers \(de, da, dr\)"):
            e.step(bad)
    e.step([2.0, -3.0, 0.0])  # out of range: clipped to the travel, as the Box says


def test_render_rgb_array(env):
    run_episode(env, doublet(env, 0)[:50], 0)
    img = env.render()
    assert img.ndim == 3 and img.shape[2] == 3 and img.dtype == np.uint8


def test_longitudinal_preset():
    e = ExcitationEnv(targets="longitudinal", episode_s=1.0)
    e.reset(seed=0)
    _, _, _, _, info = e.step(np.array([0.05, 0.0, 0.0], dtype=np.float32))
    assert info["crb"].shape == (6,)


def test_light_turbulence_is_seeded():
    def first(seed: int) -> np.ndarray:
        e = ExcitationEnv(turbulence="light", episode_s=1.0)
        e.reset(seed=seed)
        return np.array([e.step(np.zeros(3, np.float32))[0] for _ in range(20)])

    np.testing.assert_array_equal(first(1), first(1))


def test_effects_fly_the_augmented_aircraft_and_its_truth():
    """A catalogue effect given to the environment is flown and is in the truth: a body-axis
    Cn_beta delta moves the episode's truth by exactly the delta (the truth is the
    numerical linearisation of the flown XML; 1e-3 allows its finite-difference error), and
    a 20 deg/s elevator rate limit holds a full-travel step to that rate."""
    plain = ExcitationEnv(episode_s=1.0, sensors="ideal")
    delta = 0.04
    env = ExcitationEnv(episode_s=1.0, sensors="ideal", effects=[
        {"name": "derivative_delta", "derivative": "Cn_beta", "axes": "body", "delta": delta},
        {"name": "rate_limit", "surface": "de", "rate_deg": 20.0}])
    assert env.truth["Cn_beta"] - plain.truth["Cn_beta"] == pytest.approx(delta, abs=1e-3)
    assert env.truth["Cl_p"] == pytest.approx(plain.truth["Cl_p"], rel=1e-3)
    env.reset(seed=0)
    for _ in range(25):  # 0.5 s of full down elevator
        env.step(np.array([1.0, 0.0, 0.0], dtype=np.float32))
    rec = env.record(measured=False)
    rate = np.abs(np.diff(rec["de"])) * env.sim.rate_hz
    assert rate.max() == pytest.approx(np.radians(20.0), rel=0.05)
    assert [e["name"] for e in rec.meta.extra["injected"]["effects"]] == [
        "derivative_delta", "rate_limit"]


def test_cross_entropy_search_is_held_to_the_baselines_travel():
    """The CE-tuned multisine is compared with the other baselines at their travel limit:
    the search clips its peaks to ``limit`` (0.2 of travel). Without it, on the same draws,
    the search grows the inputs past 0.2, since inside the linear range larger inputs
    inform more (information ~ amplitude^2: measured on one 2 s episode, best return 96.6
    at peaks 0.40 / 0.34 against 85.1 at 0.2 / 0.2)."""
    e = ExcitationEnv(episode_s=2.0)
    limited, hist_limited = cross_entropy(e, seeds=(100,), iterations=2, population=4,
                                          elite=2)
    assert np.all(limited[:2] <= AMPLITUDE)
    assert np.abs(multisine(e, 0, *limited)).max() <= AMPLITUDE + 1e-12
    free, hist_free = cross_entropy(e, seeds=(100,), iterations=2, population=4, elite=2,
                                    limit=0.8)
    assert np.all(free[:2] > 1.5 * AMPLITUDE)
    assert hist_free[0] > hist_limited[0] + 5.0
