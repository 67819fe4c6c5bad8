"""pytest helpers: hold any identification method, yours included, to the known truth.

    from flightid.testing import assert_recovers

    def test_my_method_recovers_the_navion():
        assert_recovers("mymethod", card="navion-demo", seeds=range(5), sigma=3)

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

__all__ = ["Recovery", "assert_recovers", "recovery"]


@dataclass
class Recovery:
    """How well a method recovered a card's truth over several seeds."""

    method: str
    card: str
    sigma: float
    pairs: int = 0  # (seed, estimated derivative) pairs
    inside: int = 0  # of them within ``sigma`` standard errors of the truth
    misses: list[str] = field(default_factory=list)  # "seed 3 Cn_p +4.2 sigma"
    unidentifiable: list[str] = field(default_factory=list)

    @property
    def fraction(self) -> float:
        """Share of the pairs within ``sigma`` (0..1)."""
        return self.inside / self.pairs if self.pairs else 0.0


def recovery(method: str | Method, card: str = "navion-demo", seeds: Iterable[int] = range(5),
             sigma: float = 3.0, model: str | None = None, **options: Any) -> Recovery:
    """Fly ``card`` once per seed, identify with ``method`` (an id, or a Method that is
    registered for the call) and count the estimates within ``sigma`` of the truth."""
    if isinstance(method, Method) and method.id not in registry.methods():
        registry.register(method)
    method_id = method.id if isinstance(method, Method) else method
    result = Recovery(method_id, card, sigma)
    for seed in seeds:
        flight = fly(card, seed=seed)
        scored = score(identify(flight.measured, method_id, model, **options), flight.truth,
                       n_sigma=sigma)
        for row in scored.rows:
            if row.status != "estimated":
                result.unidentifiable.append(f"seed {seed} {row.name}: {row.reason}")
                continue
            result.pairs += 1
            if abs(row.sigmas) <= sigma:
                result.inside += 1
            else:
                result.misses.append(f"seed {seed} {row.name} {row.sigmas:+.1f} sigma")
    return result


def assert_recovers(method: str | Method, card: str = "navion-demo",
                    seeds: Iterable[int] = range(5), sigma: float = 3.0,
                    fraction: float = 1.0, model: str | None = None,
                    **options: Any) -> Recovery:
    """Fail (AssertionError listing the misses) unless at least ``fraction`` of the
    (seed, estimated derivative) pairs lie within ``sigma`` standard errors of the truth
    and something was estimated at all."""
    result = recovery(method, card, seeds, sigma, model, **options)
    if result.pairs == 0:
        raise AssertionError(f"{result.method} estimated no derivative of {card}")
    if result.fraction < fraction:
        raise AssertionError(
            f"{result.method} on {card}: {result.inside} of {result.pairs} estimates within "
            f"{sigma:g} sigma ({100 * result.fraction:.0f} %, required "
            f"{100 * fraction:.0f} %); misses: {', '.join(result.misses)}")
    return result
