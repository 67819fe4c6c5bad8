"""Multivariate orthogonal functions (issue 35 item 4, the method): the orthogonal
selection finds the terms of a known polynomial and the predicted-square-error stop
keeps out the rest (fixed seed)."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.methods import mof, registry
from flightid.identification.methods.mof import candidate_terms, select


def test_candidates_are_every_monomial_up_to_the_order():
    terms = candidate_terms(["alpha", "qhat", "de"], 3)
    # C(3 + 3, 3) - 1 = 19 monomials of degree 1 to 3 in 3 variables
    assert len(terms) == 19
    assert {"alpha", "alpha^2*de", "alpha*qhat*de", "de^3"} <= set(terms)
    with pytest.raises(ValueError, match="order"):
        candidate_terms(["alpha"], 5)


def test_selection_finds_the_polynomial_and_stops():
    rng = np.random.default_rng(3)
    n = 2000
    a, d, q = rng.uniform(-0.2, 0.2, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.05, 0.05, n)
    names = candidate_terms(["a", "d", "q"], 3)
    cols = {"a": a, "d": d, "q": q}

    def column(term: str) -> np.ndarray:
        out = np.ones(n)
        for factor in term.split("*"):
            base, _, power = factor.partition("^")
            out = out * cols[base] ** (int(power) if power else 1)
        return out

    x = np.column_stack([column(t) for t in names])
    # noise 0.01 against a signal of std about 0.45: every true term adds far more than
    # the PSE penalty sigma_max^2 / N = 1e-4
    y = 0.1 - 4.0 * a + 3.0 * a**2 - 1.5 * d + 8.0 * a * d + rng.normal(0.0, 0.01, n)
    chosen, steps = select(y, x, names)
    assert {names[i] for i in chosen} == {"a", "a^2", "d", "a*d"}
    assert steps[-1]["action"] == "select"


def test_registered_once():
    assert registry.get("mof") is mof.METHOD
    assert [m.id for m in registry.BUILTIN].count("mof") == 1
