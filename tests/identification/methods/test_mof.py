"""Multivariate orthogonal functions (issue 35, the method): the orthogonal selection finds
the terms of a known polynomial and the predicted-square-error stop keeps out the rest
(fixed seed); the simpler of two terms a doublet cannot tell apart is kept; a global model
of the c172p from three flights predicts a held-out flight's six coefficients."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.data.coefficients import channel_values
from flightid.identification.data.reduction import reduce_record
from flightid.identification.evaluation.validation import r_squared, theil_inequality
from flightid.identification.methods import mof, registry
from flightid.identification.methods.equation_error.terms import parse_term, regressor_matrix
from flightid.identification.methods.mof import candidate_terms
from flightid.identification.methods.mof_selection import _search, _sse, select
from flightid.record import FlightRecord, RecordMeta
from flightid.scenarios.cards import card_from_dict, fly_card


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


def test_a_doublet_keeps_the_linear_term_not_its_cube():
    # a doublet's levels are only -A, 0, +A, where d^3 = A^2 d: the data cannot tell the
    # cube from the linear term (r = 0.99+), so even a response made of the cube is as
    # well explained by d. Ordered orthogonalisation (Morelli 1995) leaves the cube
    # almost none of its norm after d and keeps the simpler term; a greedy search over the
    # raw candidates took the cube, which a 2-1-1 of another amplitude then mispredicts
    # (the c172p's rudder: CY_dr^3 held out R^2 0.968 before).
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 20.0, 0.02)
    d = 0.1 * (np.where((t > 2) & (t < 3), 1.0, 0.0) - np.where((t >= 3) & (t < 4), 1.0, 0.0))
    d = d + rng.normal(0.0, 1e-3, t.size)  # the position sensor's noise
    y = -30.0 * d**3 + rng.normal(0.0, 0.002, t.size)
    x = np.column_stack([d, d**2, d**3])
    chosen, _ = select(y, x, ["d", "d^2", "d^3"])
    assert chosen == [0]


TRAINING = [  # (speed m/s, seed, maneuvers): maneuvers and conditions pooled
    (33.0, 1, [("3211", "de", 2.0, 0.6, -7.0), ("doublet", "da", 14.0, 1.0, 8.0),
               ("doublet", "dr", 20.0, 1.0, 8.0)]),
    (29.0, 4, [("3211", "de", 2.0, 0.6, -5.0), ("211", "da", 13.0, 0.8, 7.0),
               ("3211", "dr", 20.0, 0.5, 6.0)]),
    (38.0, 5, [("3211", "de", 2.0, 0.5, -8.0), ("3211", "da", 12.0, 0.5, 8.0),
               ("211", "dr", 20.0, 0.8, 8.0)])]
HELD_OUT = (33.0, 2, [("doublet", "de", 2.0, 1.2, -6.0), ("211", "da", 12.0, 0.8, 7.0),
                      ("211", "dr", 20.0, 0.8, 6.0)])
# benchmarks/mof_c172p.py's confirmation to confirmation-5; -2 to -5 were each named
# before the method change it checked was scored
CONFIRMATIONS = [
    (30.0, 3, [("211", "de", 2.0, 0.8, -5.0), ("3211", "da", 11.0, 0.6, 6.0),
               ("doublet", "dr", 21.0, 1.2, 7.0)]),
    (35.0, 7, [("3211", "de", 2.0, 0.6, -6.0), ("doublet", "da", 13.0, 1.0, 7.0),
               ("3211", "dr", 20.0, 0.5, 6.0)]),
    (31.0, 8, [("doublet", "de", 2.0, 1.0, -7.0), ("3211", "da", 12.0, 0.5, 7.0),
               ("doublet", "dr", 21.0, 1.0, 6.0)]),
    (29.5, 9, [("3211", "de", 2.0, 0.6, -5.0), ("211", "da", 13.0, 0.8, 6.0),
               ("3211", "dr", 20.0, 0.5, 5.0)]),
    (31.5, 10, [("211", "de", 2.0, 0.7, -6.0), ("3211", "da", 12.0, 0.5, 7.0),
                ("211", "dr", 20.0, 0.8, 7.0)])]


def _c172p_flight(speed: float, seed: int, maneuvers: list):
    card = card_from_dict({
        "name": "c172p-mof", "aircraft": "c172p", "duration": 30.0, "rate": 100.0,
        "seed": seed, "condition": {"altitude": 1000.0, "speed": speed},
        "sensors": {"suite": "research"},
        "maneuver": [{"kind": k, "surface": s, "start": t0, "base": b, "amplitude_deg": a}
                     for k, s, t0, b, a in maneuvers]})
    measured, truth = fly_card(card)
    return reduce_record(measured).record, truth


@pytest.fixture(scope="module")
def c172p_training():
    # the training flights stay below 14.3 deg alpha, below the c172p's lift peak (16 deg)
    flights = [_c172p_flight(*f) for f in TRAINING]
    assert max(float(np.max(t["alpha"])) for _, t in flights) < np.radians(14.3)
    return [r for r, _ in flights]


def _assert_the_target(est, flights) -> None:
    """R^2 >= 0.95 and Theil <= 0.1 for all six coefficients on each held-out flight."""
    for flight in flights:
        test, _ = _c172p_flight(*flight)
        for c in ("CL", "CD", "Cm", "CY", "Cl", "Cn"):
            y, model = channel_values(test, c), mof.predict(est, test, c)
            assert r_squared(y, model) >= 0.95, (flight[:2], c)
            assert theil_inequality(y, model) <= 0.1, (flight[:2], c)


def test_spline_candidates_meet_the_target_on_all_six_held_out_c172p_flights(c172p_training):
    # issue 35 with option spline = 4 (knots 0, 4, 8, 12 deg by the rule of
    # docs/campaign.md): R^2 >= 0.95 and Theil <= 0.1 on all six held-out flights, the
    # `confirmation` flight's CD among them (0.9496 without splines). Measured R^2 0.9635
    # (that CD) to 0.9997, Theil 0.003-0.048 (benchmarks/results/mof_c172p-research.txt)
    est = mof.fit_records(c172p_training, "global", mof.Options(spline=4.0))
    _assert_the_target(est, (HELD_OUT, *CONFIRMATIONS))
    # the spline chosen for the drag: the slope above 12 deg, where the cubic fell short
    assert "CD_(alpha-12deg)+" in est.names


def test_global_model_predicts_held_out_c172p_maneuvers(c172p_training):
    # issue 35: R^2 >= 0.95 and Theil <= 0.1 on held-out maneuvers, pre-stall, research
    # sensors. The held-out flights (the first: elevator doublet, aileron and rudder 2-1-1,
    # its own seed) are never used by the fit; each excites all six coefficients.
    est = mof.fit_records(c172p_training, "global")
    # the default (no spline candidates) on every flight but `confirmation` (CD 0.9496
    # there): measured R^2 0.968-1.000 and Theil 0.004-0.048 on these five
    _assert_the_target(est, (HELD_OUT, *CONFIRMATIONS[1:]))
    # the physics the global model needs: drag on sideslip squared (the c172p's CD_beta
    # |beta|), the pitching moment's elevator power on the slipstream (Cm_de*Tc)
    assert "CD_beta^2" in est.names
    assert "Cm_de*Tc" in est.names


def _collinear_case() -> tuple[np.ndarray, np.ndarray]:
    """y = 5 (d - q) + noise with q = a + n1 and d = q + n2 (n1, n2 of std 0.3, the noise
    0.01); returns y and the columns (a, q, d)."""
    rng = np.random.default_rng(11)
    n = 3000
    a = rng.uniform(-1.0, 1.0, n)
    q = a + rng.normal(0.0, 0.3, n)
    d = q + rng.normal(0.0, 0.3, n)
    return 5.0 * (d - q) + rng.normal(0.0, 0.01, n), np.column_stack([a, q, d])


def test_the_chosen_functions_expand_into_the_chosen_terms():
    # y = 5 (d - q) with q = a + n1 and d = q + n2: in the simple-first order (a, q, d) the
    # function of d is d made orthogonal to a and q, i.e. n2, and alone explains y; but the
    # term d alone does not (Twin Otter Cm: the elevator's function carried alpha and q,
    # fit R^2 0.63 for a claimed 0.999). Generated again with d first, the search takes q
    # too, and the path's R^2 is the least-squares fit's of the chosen terms.
    y, x = _collinear_case()
    z, c = y - y.mean(), x - x.mean(axis=0)
    one_search = _search(z, c, x, [0, 1, 2], 3)
    assert one_search == [2]
    assert 1.0 - _sse(z, c[:, one_search]) / (z @ z) < 0.5  # d alone: R^2 0.3
    chosen, steps = select(y, x, ["a", "q", "d"])
    # q and d are in (a too, measured: with d first, a's function carries part of q's)
    assert {1, 2} <= set(chosen)
    r2 = 1.0 - _sse(z, c[:, chosen]) / (z @ z)
    # noise 0.01 on a signal of std 1.5: R^2 1 - (0.01 / 1.5)^2
    assert r2 > 0.9999
    assert steps[-2]["R2"] == pytest.approx(100.0 * r2, abs=1e-9)


def test_backward_elimination_drops_the_term_left_near_zero():
    # the case above: a entered (with d first, its function carried part of q's) and is
    # left near zero once q and d are in. Removing it raises the residual by less than
    # the PSE's price of a term (sigma_max^2 / N), so the backward step drops it and only
    # it (Morelli & Klein 2016 ch. 5, stepwise regression)
    y, x = _collinear_case()
    forward, _ = select(y, x, ["a", "q", "d"])
    assert 0 in forward
    chosen, steps = select(y, x, ["a", "q", "d"], backward=True)
    assert sorted(chosen) == [1, 2]
    removed = [s for s in steps if s["action"] == "remove"]
    assert [s["term"] for s in removed] == ["a"]
    assert steps[-1]["PSE"] < steps[-3]["PSE"]  # lower than the forward model's


def test_backward_elimination_keeps_every_term_of_the_polynomial():
    rng = np.random.default_rng(3)
    n = 2000
    a, d, q = rng.uniform(-0.2, 0.2, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.05, 0.05, n)
    names = candidate_terms(["a", "d", "q"], 3)
    cols = {"a": a, "d": d, "q": q}
    x = np.column_stack([np.prod([cols[f.partition("^")[0]] ** int(f.partition("^")[2] or 1)
                                  for f in t.split("*")], axis=0) for t in names])
    y = 0.1 - 4.0 * a + 3.0 * a**2 - 1.5 * d + 8.0 * a * d + rng.normal(0.0, 0.01, n)
    chosen, _ = select(y, x, names, backward=True)
    assert {names[i] for i in chosen} == {"a", "a^2", "d", "a*d"}


def _kinked_record(seed: int, slope_change: float):
    """A record whose drag coefficient is CD = 0.03 + 0.9 alpha + 0.2 de
    + slope_change (alpha - 12 deg)_+ (alpha, de in rad) with noise 0.001: alpha swept
    smoothly from -2 to 14 deg, the elevator moving on its own."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 60.0, 0.02)
    alpha = np.radians(6.0 - 8.0 * np.cos(2 * np.pi * t / 20.0)) + rng.normal(0.0, 2e-4, t.size)
    de = np.radians(3.0) * np.sin(2 * np.pi * 0.7 * t + 0.3) + rng.normal(0.0, 2e-4, t.size)
    cd = (0.03 + 0.9 * alpha + 0.2 * de + slope_change * np.maximum(alpha - np.radians(12), 0)
          + rng.normal(0.0, 1e-3, t.size))
    return FlightRecord(t, {"alpha": alpha, "de": de, "CD": cd},
                        RecordMeta(aircraft="synthetic", sample_rate=50.0, provenance="test"))


def test_spline_knots_follow_the_rule_not_the_data():
    # knots at the multiples of the spacing strictly inside the training alpha range
    # (-2 to 14 deg here, to within the sensor noise); n = 1 to the order for each
    rec = _kinked_record(1, 0.0)
    assert mof.spline_terms([rec], 4.0, 1) == [
        "(alpha-0deg)+", "(alpha-4deg)+", "(alpha-8deg)+",
        "(alpha-12deg)+"]
    assert mof.spline_terms([rec], 5.0, 2)[-3:] == [
        "(alpha-0deg)+^2", "(alpha-5deg)+^2", "(alpha-10deg)+^2"]
    assert mof.spline_terms([rec], 0.0) == []
    with pytest.raises(ValueError, match="spline"):
        mof.Options(spline=-4.0)
    # the factor is max(alpha - knot, 0) in rad, its own origin (no reference subtracted)
    x = regressor_matrix(rec, [parse_term("(alpha+2deg)+^2")], {})
    assert np.allclose(x[:, 0], np.maximum(rec["alpha"] + np.radians(2.0), 0.0) ** 2)


def test_a_slope_break_is_found_by_its_spline():
    # a slope break of -0.5 per rad at 12 deg: a cubic in alpha and de leaves an RMS
    # of 0.0020 with the noise's 0.001 in it; the spline (alpha - 12 deg)_+ takes it out; the
    # selection keeps that knot and no other spline, and its estimate is within 4 standard
    # errors of the truth
    rec = _kinked_record(2, -0.5)
    candidates = candidate_terms(["alpha", "de"], 3) + mof.spline_terms([rec], 4.0, 3)
    est = mof.estimate(rec, "CD", candidates)
    splines = [n for n in est.names if "+" in n]
    assert splines == ["CD_(alpha-12deg)+"]
    assert abs(est["CD_(alpha-12deg)+"] + 0.5) < 4 * est.std_of("CD_(alpha-12deg)+")
    assert "CD_de" in est.names
    # without the break, no spline enters: the polynomial is enough
    plain = mof.estimate(_kinked_record(2, 0.0), "CD", candidates)
    assert not [n for n in plain.names if "+" in n]
