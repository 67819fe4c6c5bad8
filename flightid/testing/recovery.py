"""Hold any identification method, yours included, to the known truth.

    from flightid.testing import assert_recovers

    def test_my_method_recovers_the_navion():
        assert_recovers("mymethod", card="navion-demo", seeds=range(5), sigma=3)
        assert_recovers("mymethod", seeds=range(5), sigma=3, rel=0.05, need="either")

Each seed flies the card in JSBSim (its own sensor noise and turbulence), identifies with
the method's defaults (the record's maneuver windows and a priori values included) and
scores every estimated derivative against the exact truth of the JSBSim model.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from flightid.api import fly, identify, score
from flightid.identification.methods import registry
from flightid.identification.methods.protocol import Method

__all__ = ["Recovery", "assert_recovers", "miss_text", "recovery", "within"]


NEEDS = ("both", "either")
ZERO_TRUTH_TOL = 1e-3  # per rad: the absolute tolerance a zero truth is held to with ``rel``


@dataclass
class Recovery:
    """How well a method recovered a card's truth over several seeds.

    A (seed, derivative) pair is inside when its error is within ``sigma`` standard errors
    and/or within ``rel`` of the truth (``need``: ``both`` or ``either`` when both are
    given; a zero truth is held to ``abs_tol`` instead of ``rel``)."""

    method: str
    card: str
    sigma: float | None
    rel: float | None = None
    abs_tol: float = ZERO_TRUTH_TOL
    need: str = "both"
    pairs: int = 0  # (seed, estimated derivative) pairs
    inside: int = 0  # of them within the tolerance
    # "seed 3 Cn_p: estimate -0.0612, truth -0.0644, error +5.0 % (+4.2 sigma)"
    misses: list[str] = field(default_factory=list)
    unidentifiable: list[str] = field(default_factory=list)

    @property
    def fraction(self) -> float:
        """Share of the pairs within the tolerance (0..1)."""
        return self.inside / self.pairs if self.pairs else 0.0

    def tolerance(self) -> str:
        """The tolerance in words, e.g. ``3 sigma and 5 %``."""
        parts = ([f"{self.sigma:g} sigma"] if self.sigma is not None else []) + (
            [f"{100 * self.rel:g} % (|error| <= {self.abs_tol:g} where the truth is 0)"]
            if self.rel is not None else [])
        return f" {'and' if self.need == 'both' else 'or'} ".join(parts)


def within(truth: float, estimate: float, std: float | None, sigma: float | None = 3.0,
           rel: float | None = None, abs_tol: float = ZERO_TRUTH_TOL,
           need: str = "both") -> bool:
    """Whether an estimate lies within the tolerance of the truth.

    Parameters
    ----------
    truth, estimate : float
        The true and the estimated value (the derivative's units).
    std : float or None
        The estimate's standard error (same units).
    sigma : float or None
        Standard errors the estimate may lie from the truth (None: not checked).
    rel : float or None
        Relative tolerance (0.05: 5 % of |truth|; None: not checked).
    abs_tol : float
        The tolerance of a zero truth instead of ``rel`` (the derivative's units).
    need : str
        ``both`` or ``either`` of the sigma and relative tests must hold.

    Returns
    -------
    bool
        True when inside.
    """
    if need not in NEEDS:
        raise ValueError(f"need must be one of {', '.join(NEEDS)}, got {need!r}")
    if sigma is None and rel is None:
        raise ValueError("give sigma, rel or both")
    error = abs(estimate - truth)
    tests = []
    if sigma is not None:
        tests.append(std is not None and std > 0 and error <= sigma * std)
    if rel is not None:
        tests.append(error <= (rel * abs(truth) if truth != 0 else abs_tol))
    return all(tests) if need == "both" else any(tests)


def miss_text(seed: int, name: str, truth: float, estimate: float, std: float | None) -> str:
    """One miss in words: estimate, truth, error in % of the truth and in standard errors.

    Parameters
    ----------
    seed : int
        The flight's seed.
    name : str
        The derivative.
    truth, estimate : float
        The true and the estimated value (the derivative's units).
    std : float or None
        The estimate's standard error.

    Returns
    -------
    str
        e.g. ``seed 3 Cn_p: estimate -0.0612, truth -0.0644, error +5.0 % (+4.2 sigma)``.
    """
    error = estimate - truth
    percent = f"{100 * error / abs(truth):+.1f} %" if truth != 0 else "truth 0"
    sigmas = f"{error / std:+.1f} sigma" if std else "no bound"
    return (f"seed {seed} {name}: estimate {estimate:.4g}, truth {truth:.4g}, "
            f"error {percent} ({sigmas})")


def recovery(method: str | Method, card: str = "navion-demo", seeds: Iterable[int] = range(5),
             sigma: float | None = 3.0, model: str | None = None, *, rel: float | None = None,
             abs_tol: float = ZERO_TRUTH_TOL, need: str = "both",
             **options: Any) -> Recovery:
    """Fly a card once per seed, identify, and count the estimates within the tolerance.

    Parameters
    ----------
    method : str or Method
        A method's id, or a Method value (registered for the call).
    card : str
        A library card.
    seeds : iterable of int
        One flight per seed.
    sigma, rel, abs_tol, need
        The tolerance, as in ``within``.
    model : str, optional
        The model (default: the method's choice for the record).
    **options
        The method's options.

    Returns
    -------
    Recovery
        The counts of (seed, derivative) pairs inside and the misses in words.
    """
    within(0.0, 0.0, 1.0, sigma, rel, abs_tol, need)  # a bad tolerance fails before flying
    if isinstance(method, Method) and method.id not in registry.methods():
        registry.register(method)
    method_id = method.id if isinstance(method, Method) else method
    result = Recovery(method_id, card, sigma, rel, abs_tol, need)
    for seed in seeds:
        flight = fly(card, seed=seed)
        scored = score(identify(flight.measured, method_id, model, **options), flight.truth,
                       n_sigma=3.0 if sigma is None else sigma)
        for row in scored.rows:
            if row.status != "estimated":
                result.unidentifiable.append(f"seed {seed} {row.name}: {row.reason}")
                continue
            result.pairs += 1
            if within(row.truth, row.estimate, row.std, sigma, rel, abs_tol, need):
                result.inside += 1
            else:
                result.misses.append(miss_text(seed, row.name, row.truth, row.estimate,
                                               row.std))
    return result


def assert_recovers(method: str | Method, card: str = "navion-demo",
                    seeds: Iterable[int] = range(5), sigma: float | None = 3.0,
                    fraction: float = 1.0, model: str | None = None, *,
                    rel: float | None = None, abs_tol: float = ZERO_TRUTH_TOL,
                    need: str = "both", **options: Any) -> Recovery:
    """Fail unless at least ``fraction`` of the (seed, estimated derivative) pairs lie
    within the tolerance and something was estimated at all.

    Parameters
    ----------
    method : str or Method
        A method's id, or a Method value (registered for the call).
    card : str
        A library card.
    seeds : iterable of int
        One flight per seed.
    sigma : float or None
        Standard errors an estimate may lie from the truth (None: not checked).
    fraction : float
        The share of pairs that must be inside (0..1).
    model : str, optional
        The model (default: the method's choice for the record).
    rel : float or None
        Relative tolerance (0.05: 5 % of |truth|; None: not checked); a zero truth is
        held to ``abs_tol`` instead (absolute, in the derivative's units, per rad).
    abs_tol : float
        The tolerance of a zero truth (the derivative's units).
    need : str
        ``both`` (default) or ``either`` of the sigma and relative tests must hold when
        both are given.
    **options
        The method's options.

    Returns
    -------
    Recovery
        The counts, when the assertion holds.

    Raises
    ------
    AssertionError
        Listing every miss: estimate, truth, error in % and in sigmas.
    """
    result = recovery(method, card, seeds, sigma, model, rel=rel, abs_tol=abs_tol,
                      need=need, **options)
    if result.pairs == 0:
        raise AssertionError(f"{result.method} estimated no derivative of {card}")
    if result.fraction < fraction:
        misses = "\n  ".join(result.misses)
        raise AssertionError(
            f"{result.method} on {card}: {result.inside} of {result.pairs} estimates within "
            f"{result.tolerance()} ({100 * result.fraction:.0f} %, required "
            f"{100 * fraction:.0f} %); misses:\n  {misses}")
    return result
