"""flightid/Excitation-v0 refuses bad options and reset arguments, each by its name."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.scenarios.gym import ExcitationEnv
from flightid.scenarios.gym.policies import doublet

BAD_OPTIONS = [
    ({"aircraft": "sideways"}, r"unknown aircraft 'sideways'"),
    ({"aircraft": 3}, r"aircraft must be an aircraft name"),
    ({"condition": (1524.0, 46.3, 3.0)}, r"condition must be \(altitude m >= 0, true airspeed"),
    ({"condition": (1524.0, -46.3)}, r"condition must be"),
    ({"condition": (float("nan"), 46.3)}, r"condition must be"),
    ({"condition": "high"}, r"condition must be"),
    ({"card": "sideways"}, r"sideways: no such card file"),
    ({"card": 3}, r"card must be a card name, a path or a Card"),
    ({"targets": "sideways"}, r"targets must be one of 'lateral', 'longitudinal'; got 'sideways'"),
    ({"targets": []}, r"targets must be .* non-empty list"),
    ({"targets": ["Cl_p", "Cl_p"]}, r"targets must be .*repeated target"),
    ({"targets": ["Cl_x"]}, r"targets must be .*unsupported target 'Cl_x'"),
    ({"targets": [3]}, r"targets must be"),
    ({"episode_s": 1e9}, r"episode_s \* decision_hz = 1e\+09 s x 50 Hz = 50000000000 decisions"),
    ({"episode_s": 0.0}, r"episode_s must be a finite number > 0"),
    ({"episode_s": float("inf")}, r"episode_s must be a finite number > 0"),
    ({"episode_s": "long"}, r"episode_s must be a finite number > 0"),
    ({"episode_s": 0.001}, r"= 0 decisions; it must be 1 to"),
    ({"decision_hz": 0}, r"decision_hz must be a finite number > 0 and <= 1000; got 0"),
    ({"decision_hz": -50.0}, r"decision_hz must be"),
    ({"decision_hz": float("nan")}, r"decision_hz must be"),
    ({"decision_hz": 1e6}, r"decision_hz must be .* <= 1000"),
    ({"sim_hz": 0}, r"sim_hz must be a finite number > 0"),
    ({"sim_hz": 75.0}, r"sim_hz 75.0 must be an integer multiple of decision_hz 50"),
    ({"sensors": "sideways"}, r"sensors must be one of 'none', 'hobby', 'research', 'ideal'"),
    ({"turbulence": "heavy"}, r"turbulence must be one of 'none', 'light'; got 'heavy'"),
    ({"effects": [{"name": "sideways"}]}, r"effects\[0\].name': unknown airframe or actuator"),
    ({"effects": "rate_limit"}, r"effects must be a list of effect tables"),
    ({"effects": [3]}, r"effects must be a list of effect tables"),
    ({"penalty": -1.0}, r"penalty must be a finite number >= 0; got -1.0"),
    ({"penalty": float("inf")}, r"penalty must be a finite number >= 0"),
    ({"render_mode": "human"}, r"render_mode must be None or 'rgb_array'"),
    ({"reward": "accurate"}, r"reward must be one of 'valid-information', 'information', "
                             r"'accuracy'; got 'accurate'"),
    ({"reward": "accuracy", "targets": ["Cl_p", "Cl_de"]},
     r"reward 'accuracy' needs a finite, nonzero truth .*targets has Cl_de = 0$"),
    ({"observation": "normalised"}, r"observation must be one of 'si', 'scaled'"),
]


@pytest.mark.parametrize(("options", "message"), BAD_OPTIONS,
                         ids=[f"{next(iter(o))}={next(iter(o.values()))!r}"
                              for o, _ in BAD_OPTIONS])
def test_a_bad_option_is_refused_by_name(options, message):
    with pytest.raises(ValueError, match=message):
        ExcitationEnv(**options)


def _episode(env: ExcitationEnv, seed: int) -> tuple[list[np.ndarray], list[float]]:
    obs, _ = env.reset(seed=seed)
    seen, rewards = [obs], []
    for a in doublet(env, seed)[:60]:
        obs, r, *_ = env.step(a.astype(np.float32))
        seen.append(obs)
        rewards.append(r)
    return seen, rewards


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"seed": -1}, r"reset: seed must be None or an integer >= 0; got -1"),
    ({"seed": 1.5}, r"reset: seed must be"),
    ({"seed": True}, r"reset: seed must be"),
    ({"seed": "0"}, r"reset: seed must be"),
    ({"options": {"speed": 50.0}}, r"reset: options takes no keys"),
    ({"options": 3}, r"reset: options takes no keys"),
])
def test_a_refused_reset_leaves_the_environment_usable(kwargs, message):
    """The refused reset comes mid-episode; the good reset after it gives the episode a fresh
    environment gives, bit for bit."""
    fresh = _episode(ExcitationEnv(episode_s=2.0), 4)
    env = ExcitationEnv(episode_s=2.0)
    _episode(env, 9)
    with pytest.raises(ValueError, match=message):
        env.reset(**kwargs)
    again = _episode(env, 4)
    np.testing.assert_array_equal(np.array(again[0]), np.array(fresh[0]))
    assert again[1] == fresh[1]


def test_a_numpy_integer_seed_is_the_same_seed():
    a = _episode(ExcitationEnv(episode_s=2.0), 4)
    b = _episode(ExcitationEnv(episode_s=2.0), np.int64(4))
    np.testing.assert_array_equal(np.array(a[0]), np.array(b[0]))
