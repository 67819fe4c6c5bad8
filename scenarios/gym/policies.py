"""The open-loop baseline policies of ``flightid/Excitation-v0`` as schedules of
normalised actions (de, da, dr) on the decision grid (``zero``, ``doublet``, ``three211``,
``multisine``, ``full_rudder``, ``random_policy``; ``POLICIES`` by name) and
``closed_loop``, a feedback policy flown as a schedule; ``baselines`` evaluates them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from flightid.scenarios.gym.env import ExcitationEnv
from flightid.scenarios.multisine import schroeder_phases

AMPLITUDE = 0.2  # normalised: 0.2 of the travel (Navion: 4 deg aileron, 5 deg rudder)

Schedule = Callable[[ExcitationEnv, int], np.ndarray]  # (env, seed) -> n x 3 actions


def _grid(env: ExcitationEnv) -> np.ndarray:
    return np.arange(env.n_decisions) / env.decision_hz


def _pattern(t: np.ndarray, start: float, unit: float, levels: Sequence[float]) -> np.ndarray:
    out = np.zeros_like(t)
    for i, level in enumerate(levels):
        out[(t >= start + i * unit) & (t < start + (i + 1) * unit)] = level
    return out


def zero(env: ExcitationEnv, seed: int) -> np.ndarray:
    """No input: every action zero.

    Parameters
    ----------
    env : ExcitationEnv
        The environment (its number of decisions and decision rate).
    seed : int
        The episode's seed.
        Unused.

    Returns
    -------
    ndarray
        The actions, one row (elevator, aileron, rudder; -1 to 1) per decision.
    """
    return np.zeros((env.n_decisions, 3))


def doublet(env: ExcitationEnv, seed: int, amplitude: float = AMPLITUDE) -> np.ndarray:
    """An aileron doublet at 1 s, then a rudder doublet at 6 s, each 1 s a side.

    Parameters
    ----------
    env : ExcitationEnv
        The environment (its number of decisions and decision rate).
    seed : int
        The episode's seed.
        Unused.
    amplitude : float
        The action's amplitude (fraction of full deflection).

    Returns
    -------
    ndarray
        The actions, one row (elevator, aileron, rudder; -1 to 1) per decision.
    """
    t, a = _grid(env), np.zeros((env.n_decisions, 3))
    a[:, 1] = _pattern(t, 1.0, 1.0, (amplitude, -amplitude))
    a[:, 2] = _pattern(t, 6.0, 1.0, (amplitude, -amplitude))
    return a


def three211(env: ExcitationEnv, seed: int, amplitude: float = AMPLITUDE) -> np.ndarray:
    """An aileron 3-2-1-1 at 1 s, then a rudder 3-2-1-1 at 8 s, on 0.5 s steps.

    Parameters
    ----------
    env : ExcitationEnv
        The environment (its number of decisions and decision rate).
    seed : int
        The episode's seed.
        Unused.
    amplitude : float
        The action's amplitude (fraction of full deflection).

    Returns
    -------
    ndarray
        The actions, one row (elevator, aileron, rudder; -1 to 1) per decision.
    """
    t, a = _grid(env), np.zeros((env.n_decisions, 3))
    levels = (amplitude, amplitude, amplitude, -amplitude, -amplitude, amplitude, -amplitude)
    a[:, 1] = _pattern(t, 1.0, 0.5, levels)
    a[:, 2] = _pattern(t, 8.0, 0.5, levels)
    return a


def multisine(env: ExcitationEnv, seed: int, amp_da: float = AMPLITUDE,
              amp_dr: float = AMPLITUDE, f_max: float = 1.5, period: float = 20.0
              ) -> np.ndarray:
    """Aileron and rudder multisines on interleaved harmonics k / period up to f_max (Hz).

    Parameters
    ----------
    env : ExcitationEnv
        The environment (decision grid).
    seed : int
        Episode seed (unused: the schedule is deterministic).
    amp_da, amp_dr : float, optional
        Peak normalised aileron and rudder action, 1.
    f_max : float, optional
        Highest frequency, Hz.
    period : float, optional
        Fundamental period, s.

    Returns
    -------
    numpy.ndarray
        Normalised actions (de, da, dr); shape (n_decisions, 3).
    """
    t, a = _grid(env), np.zeros((env.n_decisions, 3))
    k = np.arange(1, max(2, int(f_max * period)) + 1)
    for col, ks, amp in ((1, k[0::2], amp_da), (2, k[1::2], amp_dr)):
        phases = schroeder_phases(np.ones(len(ks)))
        u = np.sum(np.sin(2 * np.pi * np.outer(t, ks / period) + phases), axis=1)
        a[:, col] = amp * u / np.max(np.abs(u))
    return a


def full_rudder(env: ExcitationEnv, seed: int) -> np.ndarray:
    """Full rudder (+1) on every decision: on the Navion the bank limit ends it at 2.5 s.

    Parameters
    ----------
    env : ExcitationEnv
        The environment (decision grid).
    seed : int
        Episode seed (unused).

    Returns
    -------
    numpy.ndarray
        Normalised actions (de, da, dr); shape (n_decisions, 3).
    """
    a = np.zeros((env.n_decisions, 3))
    a[:, 2] = 1.0
    return a


def random_policy(env: ExcitationEnv, seed: int) -> np.ndarray:
    """Uniformly random actions from the action space.

    Parameters
    ----------
    env : ExcitationEnv
        The environment (its number of decisions and decision rate).
    seed : int
        The episode's seed.
        Seeds the action space.

    Returns
    -------
    ndarray
        The actions, one row (elevator, aileron, rudder; -1 to 1) per decision.
    """
    env.action_space.seed(seed)
    return np.array([env.action_space.sample() for _ in range(env.n_decisions)])


def closed_loop(predict: Callable[[np.ndarray], np.ndarray], scale: float = AMPLITUDE
                ) -> Schedule:
    """A feedback policy as a ``Schedule``.

    ``predict`` maps a scaled observation (``observation="scaled"``: (value - trim) /
    ``obs_scale``) to an action in [-1, 1], e.g. a trained agent's; it flies each seed's
    episode in the environment it is given, with its actions times ``scale`` (the
    baselines' travel limit), and the actions taken are the schedule (0 after a
    termination). The environment is deterministic given the seed, so the schedule flown
    open loop on the same seed is the same flight.

    Parameters
    ----------
    predict : callable
        Scaled observation -> action in [-1, 1], shape (3,).
    scale : float, optional
        Factor on the actions, 1.

    Returns
    -------
    Schedule
        ``schedule(env, seed)`` -> normalised actions, shape (n_decisions, 3).
    """

    def schedule(env: ExcitationEnv, seed: int) -> np.ndarray:
        obs, _ = env.reset(seed=seed)
        actions = np.zeros((env.n_decisions, 3))
        for k in range(env.n_decisions):
            if env.observation == "si":
                obs = (obs - env.obs_center) / env.obs_scale
            actions[k] = scale * np.clip(np.asarray(predict(obs), dtype=float), -1.0, 1.0)
            obs, _, terminated, truncated, _ = env.step(actions[k].astype(np.float32))
            if terminated or truncated:
                break
        return actions

    return schedule


POLICIES: dict[str, Schedule] = {"zero": zero, "doublet": doublet, "3211": three211,
                                 "multisine": multisine, "random": random_policy,
                                 "full rudder": full_rudder}
