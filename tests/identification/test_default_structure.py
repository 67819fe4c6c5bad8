"""The structure ``identify`` fits by default holds on cards other than navion-demo.

- The full longitudinal model estimates CL_q and Cm_alphadot unless the record holds them
  a priori (``linear_models.RATE_DERIVATIVES``): navion-doublets has no a priori table,
  and without Cm_alphadot (truth -4.36) Cm_q came out -14.5 for -9.96, 52 bounds off.
- Output error fits a hobby record without phi and theta: the attitudes stay states,
  integrated from the rates, and leave the outputs (``fit['outputs_left_out']``).

Tolerances: 3 of the estimate's own (colored-residual corrected) Cramer-Rao bounds, the
99.7 % level of a Gaussian estimator whose bound is right; fixed seeds of the development
set of docs/validation.md.
"""

from __future__ import annotations

import warnings

import pytest

from flightid.identification.data.reduction import reduce_record
from flightid.identification.evaluation.scoring import score
from flightid.identification.identify import identify
from flightid.scenarios.cards import fly_card, load_card


def _flown(card: str, seed: int):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        measured, _ = fly_card(load_card(card), seed)
        return reduce_record(measured).record


def _scored(record, axis: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = identify(record, "oe", axis)
    return est, score(est, record)


@pytest.mark.parametrize("seed", [1, 2])
def test_the_longitudinal_default_estimates_the_rate_derivatives(seed):
    est, scored = _scored(_flown("navion-doublets", seed), "lon")
    rows = {r.name: r for r in scored.rows}
    assert {"CL_q", "Cm_alphadot"} <= set(est.names)
    for name in ("CL_alpha", "CL_de", "Cm_alpha", "Cm_q", "Cm_de", "Cm_alphadot"):
        assert rows[name].status == "estimated", name
        assert abs(rows[name].sigmas) <= 3, f"{name}: {rows[name].sigmas:+.1f} bounds"
    # the pair a short maneuver hardly separates (Morelli & Klein 2016 sec. 6.3) comes
    # with the bound that says so: Cm_alphadot's is tens of % of the value (seed 1: 3.05
    # for -4.36), Cm_q's ten times the 0.09 it had with Cm_alphadot left out
    assert rows["Cm_q"].std > 1.0


def test_a_card_holding_them_a_priori_keeps_them_held():
    est, _ = _scored(_flown("navion-demo", 1), "lon")
    assert "Cm_alphadot" not in est.names and "CL_q" not in est.names
    assert set(est.fit["a_priori"]) == {"CL_q", "Cm_alphadot"}


def test_output_error_fits_a_hobby_record_without_attitudes():
    record = _flown("telemaster-lateral", 1)
    assert "phi" not in record and "theta" not in record
    est, scored = _scored(record, "lat")
    assert est.fit["outputs_left_out"].keys() == {"phi"}
    done = [r for r in scored.rows if r.status == "estimated"]
    assert len(done) >= 0.8 * 13
    assert all(abs(r.sigmas) <= 3 for r in done), [(r.name, r.sigmas) for r in done]


def test_a_failed_fit_from_the_equation_error_start_is_started_again():
    # navion-sweep-yaw: from the equation-error start every development seed ended with
    # R^2 < 0 and every derivative withheld; from the typical values seed 1 converges.
    # Known miss: CY_beta about -1 % (9 bounds), the same on the noise-free record.
    est, scored = _scored(_flown("navion-sweep-yaw", 1), "lat")
    assert est.fit["start"].startswith("typical values")
    assert est.fit["R2"] > 0.5
    done = [r for r in scored.rows if r.status == "estimated"]
    assert len(done) == 13
    assert sum(abs(r.sigmas) <= 3 for r in done) >= 0.8 * len(done)
