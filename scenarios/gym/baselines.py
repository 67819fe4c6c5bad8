"""Baseline excitation policies for ``flightid/Excitation-v0``, evaluated on the same seeds.

    python -m flightid.scenarios.gym.baselines [--seeds 0 1 2] [--out FILE] [--no-search]

Policies (``policies``) are open-loop schedules of normalised actions (de, da, dr) on the decision
grid: ``zero``; ``doublet`` (aileron doublet, then rudder doublet); ``3211`` (aileron
3-2-1-1, then rudder 3-2-1-1); ``multisine`` (aileron and rudder at once, interleaved
harmonics of a 20 s period with Schroeder phases, Morelli's orthogonal multisine idea);
``random`` (``action_space.sample()`` seeded with the episode's seed, the usual RL
baseline); ``full rudder`` (held until the bank limit ends the episode: the policy a PPO
agent learned to game the ``information`` reward with). All have peak ``AMPLITUDE`` on the
surfaces they move, except ``random`` and ``full rudder``.
Reported per policy: mean return under the default reward (``valid-information``) and
under ``OTHER_REWARDS``, mean relative Cramer-Rao bound (crb / |truth|) and mean
relative error of the final estimate (|estimate - truth| / |truth|) over the targets, and
how many episodes terminated early.

``cross_entropy`` searches the multisine's parameters (aileron and rudder peak, within
``AMPLITUDE`` as every other baseline, and highest frequency) with the cross-entropy
method on training seeds; the result is evaluated on
held-out seeds beside the baselines.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from flightid.scenarios.gym.env import ExcitationEnv
from flightid.scenarios.gym.policies import AMPLITUDE, POLICIES, Schedule, multisine

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "benchmarks" / "results" / "gym_baselines.txt"
TRAIN_SEEDS = (100, 101)
HELD_OUT_SEEDS = (0, 1, 2, 3)


@dataclass
class Result:
    """One policy on the held-out seeds: per seed, the return and the final bounds and
    errors (target order)."""

    policy: str
    returns: list[float]
    rel_crb: list[float]
    rel_error: list[float]
    terminated: int
    crb: list[np.ndarray] = field(default_factory=list)
    error: list[np.ndarray] = field(default_factory=list)
    # the same episodes' returns under the other rewards, by reward name
    other_returns: dict[str, list[float]] = field(default_factory=dict)

    def line(self) -> str:
        others = "".join(f"{np.mean(self.other_returns[r]):>12.1f}" if r in self.other_returns
                         else f"{'-':>12}" for r in OTHER_REWARDS)
        return (f"{self.policy:<22}{np.mean(self.returns):>10.1f}{np.min(self.returns):>10.1f}"
                f"{others}{np.mean(self.rel_crb):>12.4f}{np.mean(self.rel_error):>12.4f}"
                f"{self.terminated:>6d}/{len(self.returns)}")


OTHER_REWARDS = ("information", "accuracy")  # beside the default's return
HEADER = (f"{'policy':<22}{'return':>10}{'min':>10}" + "".join(f"{r:>12}" for r in OTHER_REWARDS)
          + f"{'rel. CRB':>12}{'rel. error':>12}{'term':>8}")


def run_episode(env: ExcitationEnv, actions: np.ndarray, seed: int
                ) -> tuple[float, dict, bool]:
    """Fly one episode with the schedule; (return, last info, terminated early).

    Parameters
    ----------
    env : ExcitationEnv
        The environment.
    actions : numpy.ndarray
        Normalised actions (de, da, dr); shape (n, 3).
    seed : int
        Episode seed.

    Returns
    -------
    tuple[float, dict, bool]
        (return, last step's info, terminated early).
    """
    env.reset(seed=seed)
    total, info, terminated = 0.0, {}, False
    for a in actions:
        _, r, terminated, truncated, info = env.step(a.astype(np.float32))
        total += r
        if terminated or truncated:
            break
    return total, info, terminated


def evaluate(env: ExcitationEnv, name: str, schedule: Schedule, seeds: Sequence[int],
             others: Sequence[ExcitationEnv] = ()) -> Result:
    """The policy on ``seeds`` in ``env``, and its returns in ``others`` (the same
    environment under other rewards).

    Parameters
    ----------
    env : ExcitationEnv
        The environment scored in.
    name : str
        Policy name.
    schedule : Schedule
        ``schedule(env, seed)`` -> actions.
    seeds : Sequence[int]
        Episode seeds.
    others : Sequence[ExcitationEnv], optional
        Environments under other rewards.

    Returns
    -------
    Result
        Returns, relative bounds and errors per seed, and the number of early terminations.
    """
    res = Result(name, [], [], [], 0)
    truth = np.abs(env._truth_vec)
    for s in seeds:
        for other in others:
            res.other_returns.setdefault(other.reward, []).append(
                run_episode(other, schedule(other, s), s)[0])
        total, info, term = run_episode(env, schedule(env, s), s)
        res.returns.append(total)
        res.rel_crb.append(float(np.mean(info["crb"] / truth)))
        res.rel_error.append(float(np.mean(np.abs(info["error"]) / truth)))
        res.crb.append(info["crb"])
        res.error.append(info["error"])
        res.terminated += int(term)
    return res


def cross_entropy(env: ExcitationEnv, seeds: Sequence[int] = TRAIN_SEEDS, iterations: int = 5,
                  population: int = 12, elite: int = 3, rng_seed: int = 0,
                  limit: float = AMPLITUDE) -> tuple[np.ndarray, list[float]]:
    """Cross-entropy search over (amp_da, amp_dr, f_max) of ``multisine``.

    Parameters
    ----------
    env : ExcitationEnv
        The environment whose return (its reward) is maximised.
    seeds : sequence of int
        Training seeds; the score of a candidate is its mean return over them.
    iterations, population, elite : int
        Cross-entropy iterations, candidates per iteration, and the elite refitted.
    rng_seed : int
        Seed of the candidates' draws.
    limit : float
        Largest peak (normalised travel) of the aileron and rudder: candidates are
        clipped to it, so the tuned multisine stays within the same travel limit as the
        other baselines (``AMPLITUDE``, 0.2 of travel).

    Returns
    -------
    best : ndarray
        (amp_da, amp_dr, f_max in Hz) of the best candidate.
    history : list of float
        The best score of each iteration.
    """
    rng = np.random.default_rng(rng_seed)
    lo, hi = np.array([0.02, 0.02, 0.3]), np.array([limit, limit, 3.0])
    start = min(AMPLITUDE, limit)
    mean, std = np.array([start, start, 1.5]), np.array([0.15, 0.15, 0.6])
    history = []
    best, best_score = mean.copy(), -np.inf
    for _ in range(iterations):
        pop = np.clip(mean + std * rng.standard_normal((population, 3)), lo, hi)
        scores = np.array([np.mean([run_episode(env, multisine(env, s, *p), s)[0]
                                    for s in seeds]) for p in pop])
        order = np.argsort(scores)[::-1][:elite]
        if scores[order[0]] > best_score:
            best, best_score = pop[order[0]].copy(), float(scores[order[0]])
        mean, std = pop[order].mean(axis=0), pop[order].std(axis=0) + 1e-3
        history.append(float(scores[order[0]]))
    return best, history


def per_target(env: ExcitationEnv, results: Sequence[Result]) -> list[str]:
    """Per target and policy: the final bound relative to |truth| (mean over seeds; the
    information the policy gathered) and the error in units of the bound (RMS over seeds;
    about 1 when the estimate is as good as its bound says).

    Parameters
    ----------
    env : ExcitationEnv
        The environment (its targets and truth).
    results : Sequence[Result]
        The evaluated policies.

    Returns
    -------
    list[str]
        Lines of the two tables.
    """
    truth = np.abs(env._truth_vec)
    head = f"{'policy':<22}" + "".join(f"{t:>9}" for t in env.targets)
    lines = ["final Cramer-Rao bound / |truth| per target (mean over seeds)", head]
    lines += [f"{r.policy:<22}" + "".join(f"{v:>9.4f}" for v in np.mean(r.crb, axis=0) / truth)
              for r in results]
    lines += ["", "final error / Cramer-Rao bound per target (RMS over seeds)", head]
    lines += [f"{r.policy:<22}" + "".join(
        f"{v:>9.2f}" for v in np.sqrt(np.mean((np.array(r.error) / r.crb) ** 2, axis=0)))
        for r in results]
    return lines


def plot(env: ExcitationEnv, results: Sequence[Result], path: Path) -> Path:
    """Bars of the final bound / |truth| per target and policy (log scale), the RMS error
    / |truth| as dots on them; written to ``path`` (PNG).

    Parameters
    ----------
    env : ExcitationEnv
        The environment (its targets and truth).
    results : Sequence[Result]
        The evaluated policies.
    path : Path
        PNG file to write.

    Returns
    -------
    Path
        ``path``.
    """
    truth = np.abs(env._truth_vec)
    fig = Figure(figsize=(11, 4.8), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    x = np.arange(len(env.targets))
    width = 0.8 / len(results)
    for i, r in enumerate(results):
        offset = x - 0.4 + (i + 0.5) * width
        bars = ax.bar(offset, np.mean(r.crb, axis=0) / truth, width, label=r.policy)
        rms = np.sqrt(np.mean(np.square(r.error), axis=0)) / truth
        ax.plot(offset, rms, "o", ms=3.5, color=bars.patches[0].get_facecolor(),
                markeredgecolor="k", markeredgewidth=0.5)
    ax.set_yscale("log")
    ax.set_ylim(top=ax.get_ylim()[1] * 20)  # room for the legend above the bars
    ax.set_xticks(x, env.targets, rotation=30)
    ax.set_ylabel("bound / |truth| (bars), RMS error / |truth| (dots)")
    ax.set_title(f"{env.aircraft}: final Cramer-Rao bounds and errors per target, "
                 f"{env.episode_s:g} s episodes", fontsize=10)
    ax.grid(axis="y", which="major", alpha=0.3)
    ax.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    fig.savefig(path)
    return path


def main(seeds: Sequence[int] = HELD_OUT_SEEDS, out: Path | None = DEFAULT_OUT,
         search: bool = True) -> str:
    """Every baseline policy on the held-out seeds: the reward table as text.

    Parameters
    ----------
    seeds : sequence of int
        The episodes' seeds.
    out : Path or None
        Where the table is written (None: not written).
    search : bool
        Whether to tune the multisine by the cross-entropy method on the training seeds
        and add it to the table.

    Returns
    -------
    str
        The table.
    """
    env = ExcitationEnv()
    others = [ExcitationEnv(reward=r) for r in OTHER_REWARDS]
    results = [evaluate(env, n, p, seeds, others) for n, p in POLICIES.items()]
    lines = [f"flightid/Excitation-v0 baselines: {env.aircraft} at "
             f"{env.condition.altitude_m:g} m, {env.condition.speed_m_s:g} m/s, "
             f"{env.episode_s:g} s episodes, {env.decision_hz:g} Hz decisions, "
             f"sensors {env.suite.name if env.suite else 'ideal'}, seeds {list(seeds)}",
             f"targets: {' '.join(env.targets)}; amplitude {AMPLITUDE} of travel",
             f"return: reward {env.reward!r} (the default); {', '.join(OTHER_REWARDS)}: the "
             "same episodes' returns under those rewards; rel. CRB and error: the default "
             "reward's estimate", "",
             HEADER, *(r.line() for r in results)]
    if search:
        best, history = cross_entropy(env)

        def tuned(e: ExcitationEnv, s: int) -> np.ndarray:
            return multisine(e, s, *best)

        r = evaluate(env, "multisine (CE-tuned)", tuned, seeds, others)
        results.append(r)
        lines += [r.line(), "",
                  f"cross-entropy on training seeds {list(TRAIN_SEEDS)}, peaks limited to "
                  f"{AMPLITUDE} of travel: amp_da {best[0]:.3f}, "
                  f"amp_dr {best[1]:.3f}, f_max {best[2]:.2f} Hz; best training return per "
                  f"iteration {', '.join(f'{h:.1f}' for h in history)}"]
    lines += ["", *per_target(env, results)]
    text = "\n".join(lines) + "\n"
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)
        plot(env, results, out.with_suffix(".png"))
    return text


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(HELD_OUT_SEEDS))
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--no-search", action="store_true")
    args = parser.parse_args()
    print(main(args.seeds, args.out, not args.no_search))
