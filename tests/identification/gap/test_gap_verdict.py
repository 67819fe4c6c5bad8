"""The verdict of the gap diagnosis (identification/gap/verdict.py): no gap on null flights
in calm air and in turbulence, explained when the injected effect is named, both effects
of a pair named, each axis its own verdict, and the table readable at 80 columns.

The flights are the blind check's lateral card (an aileron doublet, a rudder 2-1-1, an
aileron doublet and a rudder doublet, research sensors corrected to the CG) on seeds the
development of the thresholds did not use for the null cases (21, 22)."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.identification.gap import diagnose
from flightid.identification.gap.model.edits import Candidate
from flightid.identification.gap.rank import (
    MIN_EXCESS_SHRINK,
    MIN_SHRINK,
    rank_key,
)
from flightid.identification.gap.ranked import Ranked, mean_gap
from flightid.identification.gap.sequence import shrink_text
from flightid.identification.gap.verdict import (
    ALPHA,
    MATERIAL,
    NO_GAP,
    calibrated_p,
    channel_test,
    worst,
)
from flightid.identification.gap.window.regressors import other_outputs
from flightid.identification.gap.window.surrogates import surrogate_shifts
from flightid.scenarios.cards import card_from_dict, fly_card, load_card
from flightid.scenarios.gap_benchmark.cases import Case, Effect
from flightid.scenarios.gap_benchmark.classes import same
from flightid.scenarios.gap_benchmark.run import fly_case
from tests.lateral_card import card_data


def _flown(aircraft: str, seed: int, effects: list[dict] | None = None,
           turbulence: str | None = None):
    data = card_data(aircraft, seed)
    if turbulence:
        data["disturbance"] = [{"kind": "turbulence", "intensity": turbulence}]
    if effects:
        data["effect"] = effects
    measured, _ = fly_card(card_from_dict(data, "<verdict test>"))
    return measured


@pytest.mark.parametrize(("aircraft", "seed", "turbulence"), [
    ("navion", 21, None), ("twinotter", 21, "light"), ("telemaster", 22, "light"),
    ("navion", 22, "moderate")])
def test_exact_model_has_no_gap(aircraft, seed, turbulence):
    """The exact aircraft against its own flight: turbulence and sensor noise are the
    null level, not a model error; nothing is ranked or named."""
    result = diagnose([_flown(aircraft, seed, None, turbulence)], aircraft)
    assert result.verdict == NO_GAP, result.null_before.to_json()
    assert result.named == [] and result.effects == []


def test_effect_in_turbulence_is_named_and_explained():
    """A Cn_beta delta of +0.02 per rad (about 30 % of the Navion's) in light turbulence:
    a gap above the null level, named as that delta, and the model with it at the null
    level again."""
    result = diagnose([_flown("navion", 5, [{"name": "derivative_delta",
                                             "derivative": "Cn_beta", "axes": "body",
                                             "delta": 0.02}], "light")], "navion")
    assert result.null_before.gap
    top = result.named[0]
    assert (top.candidate.entry, top.candidate.options["derivative"]) == (
        "derivative_delta", "Cn_beta")
    delta = top.parameters["delta"]
    # turbulence biases output error (docs/gap.md): within 4 bounds or 20 %
    assert abs(delta["value"] - 0.02) < max(4 * delta["std"], 0.2 * 0.02)
    assert result.verdict == "explained" and not result.null_after.gap


def test_pair_both_named():
    """Two effects at once (a Cn_beta delta and an aileron at 70 %), calm air: both named,
    and together they explain the gap."""
    result = diagnose([_flown("navion", 5, [
        {"name": "derivative_delta", "derivative": "Cn_beta", "axes": "body", "delta": 0.02},
        {"name": "control_effectiveness", "surface": "da", "factor": 0.7}])], "navion")
    found = {(c.entry, c.options.get("derivative") or c.options.get("surface"))
             for r in result.named for c in (r.candidate.parts or (r.candidate,))}
    assert {("derivative_delta", "Cn_beta"), ("control_effectiveness", "da")} <= found
    assert result.verdict == "explained"
    factor = next(r for r in result.named if r.candidate.entry == "control_effectiveness")
    assert abs(factor.parameters["factor"]["value"] - 0.7) < 0.05


def test_both_axes_each_with_its_verdict_and_one_maneuver_split():
    """navion-demo (calm) flies one elevator 3211, one aileron doublet and one rudder
    2-1-1: both axes diagnosed, each with its verdict; the longitudinal axis, one
    maneuver, is checked on a time split and says so."""
    data = dict(load_card("navion-demo").data)
    data.pop("disturbance", None)
    measured, _ = fly_card(card_from_dict(data))
    result = diagnose([measured], "navion", try_pairs=False)
    assert set(result.axes()) == {"lateral", "longitudinal"}
    assert result.undiagnosed == {}
    for g in result.axes().values():
        assert g.verdict == NO_GAP
    assert result.axes()["longitudinal"].evidence == "time split"
    assert result.to_json()["axes"]["longitudinal"]["evidence"] == "time split"
    only = diagnose([measured], "navion", axis="lateral")
    assert "longitudinal" in only.undiagnosed


def test_channel_test_white_and_colored_null_and_a_real_gap():
    """The test itself on synthetic series: a residual of colored noise independent of
    the regressors passes (p above ALPHA in 97 of 100 draws or more); one with 40 % of its
    energy driven by the regressors fails (measured p 7.2e-6; with 30 %, p 1.5e-4: above
    the seed-7 rules' ALPHA of 1e-4 without the other outputs' residuals, which a single
    series does not have; the test below has them)."""
    rng = np.random.default_rng(0)
    n = 2000
    x = np.column_stack([np.convolve(rng.standard_normal(n), np.ones(40) / 40, "same")
                         for _ in range(6)])
    passed = 0
    for _ in range(100):
        colored = np.convolve(rng.standard_normal(n + 49), np.ones(50) / 50, "valid")
        t = channel_test(colored, x, float(np.sum(colored**2)) * 2, "c")
        passed += t.p_value >= ALPHA
    assert passed >= 97
    v = np.convolve(rng.standard_normal(n + 49), np.ones(50) / 50, "valid")
    signal_part = x @ rng.standard_normal(6)
    signal_part *= np.sqrt(0.4 * np.sum(v**2) / np.sum(signal_part**2))
    t = channel_test(v + signal_part, x, float(np.sum((v + signal_part) ** 2)), "c")
    assert t.gap and t.share > MATERIAL


def test_other_outputs_as_nuisance_keep_the_null_and_see_through_turbulence():
    """The partial form of the test (the rules for the seed-7 run) on synthetic series: a
    colored disturbance drives two outputs (as one gust drives every output of an axis),
    with 5 % white noise of its spread on each. With the other output's residual fitted
    beside the input regressors, a residual independent of them passes (p above ALPHA in
    97 of 100 draws or more: the nuisance regressor is independent of the inputs too); one
    with 5 % of its energy driven by the inputs is not seen alone (measured p 0.32) and is
    seen beside the other output (measured p 3e-71, share 0.040 against the 0.05 put in:
    the disturbance's share of the regressors' band is gone from the chance term)."""
    rng = np.random.default_rng(1)
    n = 2000
    x = np.column_stack([np.convolve(rng.standard_normal(n), np.ones(40) / 40, "same")
                         for _ in range(6)])

    def disturbance():
        g = np.convolve(rng.standard_normal(n + 49), np.ones(50) / 50, "valid")
        other = g + 0.05 * np.std(g) * rng.standard_normal(n)
        return 0.8 * g + 0.05 * np.std(g) * rng.standard_normal(n), other

    passed = 0
    for _ in range(100):
        own, other = disturbance()
        passed += channel_test(own, x, float(np.sum(own**2)), "c",
                               other[:, None]).p_value >= ALPHA
    assert passed >= 97
    own, other = disturbance()
    part = x @ rng.standard_normal(6)
    part *= np.sqrt(0.05 * np.sum(own**2) / np.sum(part**2))
    v = own + part
    assert channel_test(v, x, float(np.sum(v**2)), "c").p_value > ALPHA
    seen = channel_test(v, x, float(np.sum(v**2)), "c", other[:, None])
    assert seen.p_value < 1e-20 and MATERIAL <= seen.share <= 0.05


def test_other_outputs_leave_out_a_channel_non_finite_on_some_window():
    """A channel that is non-finite on one window only (a dropout) is left out of the
    nuisance regressors of every window: each column holds one channel throughout, and the
    windows stack (they raised ValueError in np.vstack when the column counts differed)."""
    rng = np.random.default_rng(2)
    windows = [400, 500]
    hp = {c: [rng.standard_normal(n) for n in windows] for c in ("p", "r", "ay")}
    hp["ay"][1][10] = np.nan
    z = other_outputs(hp, "p", [0.02, 0.02])
    assert z is not None and z.shape == (sum(windows), 3)  # r and its 2 Laguerre filters
    np.testing.assert_allclose(z[:400, 0], hp["r"][0] - hp["r"][0].mean())


def test_worst_verdict_and_shrink_text():
    assert worst(["no_gap", "explained"]) == "explained"
    assert worst(["unexplained", "partly_unexplained"]) == "unexplained"
    assert shrink_text(-292.68) == "worse" and shrink_text(0.5) == "50%"


def test_table_readable_at_80_columns(tmp_path):
    rec = _flown("navion", 5, [{"name": "derivative_delta", "derivative": "Cl_beta",
                                "axes": "body", "delta": -0.03}])
    path = tmp_path / "r.parquet"
    rec.write(path)
    out = CliRunner().invoke(app, ["gap", str(path), "--model", "navion"],
                             env={"COLUMNS": "80"}, terminal_width=80)
    assert out.exit_code == 0, out.output
    assert "…" not in out.output
    assert max(len(line) for line in out.output.splitlines()) <= 80
    assert "verdict: explained" in out.output
    # the null-level test names the channels above the null level, beside each p and share
    assert " GAP" in out.output and "(alone " in out.output
    # the effect's name on one line: the parameters column wraps instead
    assert "derivative_delta(Cl_beta,body)" in out.output
    assert "injected (the record's card says): derivative_delta(" in out.output


def _ranked(label: str, confirmed: bool, bic: float, held: float) -> Ranked:
    cand = Candidate(label, {}, ("x",), wrap=lambda m: m)
    r = Ranked(cand, {"x": 0.0}, {"x": 1.0}, {}, bic, bic / 2)
    r.confirmed, r.heldout_cost_change = confirmed, held
    return r


def test_confirmed_effects_rank_by_heldout_cost_then_the_rest_by_bic():
    """``rank_key``: a confirmed effect with the lower held-out cost ranks first even with
    the higher BIC (the Telemaster aileron at 0.73 of seed 0: Cl_p had the lower BIC,
    -3271 against -3193, the aileron the lower held-out cost, -1488 against -950);
    unconfirmed ones follow by BIC."""
    effects = [_ranked("Cl_p", True, -3271.0, -950.0),
               _ranked("da", True, -3193.0, -1488.0),
               _ranked("cg", False, -5000.0, 1032.0),
               _ranked("Cn_beta", False, -2476.0, -10.0)]
    assert [r.candidate.entry for r in sorted(effects, key=rank_key)] == [
        "da", "Cl_p", "cg", "Cn_beta"]


def _blind_card(aircraft: str, seed: int, effects: tuple = ()):
    """The blind check's 64 s card (both axes) flown in light turbulence, blinded."""
    category = "single" if effects else "null"
    return fly_case(Case(0, seed, aircraft, category, effects), "light")


def test_exact_model_on_the_blind_card_has_no_gap_on_either_axis():
    """The blind check's card (aileron, rudder, then an elevator doublet and a 3211) of
    the exact Twin Otter in light turbulence: `no_gap` on the lateral and the
    longitudinal axis."""
    result = diagnose([_blind_card("twinotter", 22)], "twinotter", try_pairs=False, steps=1)
    assert set(result.axes()) == {"lateral", "longitudinal"}
    for axis, g in result.axes().items():
        assert g.verdict == NO_GAP, (axis, g.null_before.to_json())


def test_effect_in_turbulence_confirmed_against_the_gap_above_the_null_level():
    """A Twin Otter elevator at 71 % on the blind card in light turbulence (seed 0's case
    54 of the blind check, a development case of this rule): its held-out shrink of the
    whole gap, turbulence included, is under the 10 % of ``MIN_SHRINK`` (the rule before:
    unexplained), but it closes more than ``MIN_EXCESS_SHRINK`` of the gap above the null
    level: it is named (measured 0.656), within two Cramer-Rao bounds of the injected
    factor."""
    factor = 0.7085677466423788
    effect = Effect("control_effectiveness", "longitudinal", "card", {"surface": "de"},
                    {"factor": factor})
    result = diagnose([_blind_card("twinotter", 1217455164, (effect,))], "twinotter",
                      axis="longitudinal", try_pairs=False, steps=1)
    assert result.null_before.gap and result.named, result.null_before.to_json()
    top = result.named[0]
    assert same(effect, top), top.candidate.label
    gain = mean_gap(top.heldout_before) - mean_gap(top.heldout_after)
    assert gain >= MIN_EXCESS_SHRINK * mean_gap(result.null_before.above())
    assert top.shrink < MIN_SHRINK  # the whole-gap rule would not have confirmed it
    value = top.parameters["factor"]
    assert abs(value["value"] - factor) < 2 * value["std"]


def test_band_limited_test_clears_a_slow_turbulence_false_alarm():
    """A null Twin Otter of the blind check (seed 0's null case 8, light turbulence): its
    slow phugoid-band turbulence response correlated by chance with the slow regressors,
    a longitudinal false alarm of the unfiltered test (q, p 5.6e-5, share 0.038). With
    residual and regressors high-passed at ``HIGHPASS_RAD_S`` both axes are `no_gap`."""
    result = diagnose([_blind_card("twinotter", 1498554800)], "twinotter", try_pairs=False,
                      steps=1)
    for axis, g in result.axes().items():
        assert g.verdict == NO_GAP, (axis, g.null_before.to_json())


def test_pitch_break_is_not_no_gap():
    """A Telemaster pitch break (outside the catalogue; seed 0's case 25, light
    turbulence: 0.49 deg above trim, 82 % of its Cm_alpha lost). The band-limited window
    test of the seed-3 to seed-6 rules saw it on q (p 2.4e-4, share 0.054); with the other
    outputs' residuals as nuisance regressors (seed-7 rules) q stays significant (measured
    p 2.5e-6) but its share falls to 0.0017, under MATERIAL: a pitching-moment change
    drives alpha, q and az as a moment disturbance does, and the other residuals take it.
    The nonlinear-structure test finds the kink: the axis is `unexplained`, not `no_gap`."""
    effect = Effect("cm_alpha_break", "longitudinal", "card", {},
                    {"above": 0.00856296474957567, "delta": 0.82086821744019},
                    in_catalogue=False)
    result = diagnose([fly_case(Case(25, 328766611, "telemaster", "outside", (effect,)),
                                "light")], "telemaster", axis="longitudinal",
                      try_pairs=False, steps=1)
    q = result.null_before.channels["q"]
    assert q.p_value < ALPHA and q.share < MATERIAL, q.to_json()
    assert result.structure.gap and result.verdict != NO_GAP, result.verdict


def test_calibrated_p_keeps_a_real_gap_and_never_lowers_the_chi_square_p():
    """The surrogate calibration on synthetic windows (four of 500 samples, colored
    regressors and residual): a residual with 30 % of its energy driven by the regressors
    stays far below ALPHA (its surrogates, shifted against the residual, lose the relation;
    measured chi-square p 1.1e-12, calibrated 7.9e-10); an independent colored residual's
    calibrated p is never below its chi-square p."""
    rng = np.random.default_rng(3)
    blocks = [np.column_stack([np.convolve(rng.standard_normal(500), np.ones(40) / 40,
                                           "same") for _ in range(4)]) for _ in range(4)]
    x = np.vstack(blocks)
    shifts = surrogate_shifts([500] * 4, [0.02] * 4)
    v = np.convolve(rng.standard_normal(2009), np.ones(10) / 10, "valid")
    part = x @ rng.standard_normal(4)
    part *= np.sqrt(0.3 * np.sum(v**2) / np.sum(part**2))
    t = channel_test(v + part, x, float(np.sum((v + part) ** 2)), "c")
    assert t.p_value < 1e-9
    assert calibrated_p(t, v + part, blocks, shifts, 1.0) < 1e-6
    t = channel_test(v, x, float(np.sum(v**2)), "c")
    assert calibrated_p(t, v, blocks, shifts, 1.0) >= t.p_value


def test_calibrated_window_test_clears_a_colored_residual_false_alarm():
    """A null Telemaster of the blind check (seed 0's null case 77, light turbulence): the
    bank angle's residual, colored and estimated on four 10 s windows, made the
    chi-square Wald test a false alarm (measured p 7.3e-10, share 0.105; verdict
    ``partly_unexplained`` under the seed-5 rules); the seed-6 rules' surrogates cleared it
    (p 0.067). Under the seed-7 rules the bank angle is only a nuisance regressor of the
    other channels (its share alone, 0.105, stays in the gap above the null level), and
    both axes are ``no_gap``."""
    result = diagnose([fly_case(Case(1000077, 1344411238, "telemaster", "null"), "light")],
                      "telemaster", try_pairs=False, steps=1)
    phi = result.axes()["lateral"].null_before.channels["phi"]
    assert phi.slow and phi.level > MATERIAL, phi.to_json()
    for axis, g in result.axes().items():
        assert g.verdict == NO_GAP, (axis, g.null_before.to_json())


def test_calibrated_window_test_keeps_a_seen_effect():
    """A 0.128 s lag on the c172p's pitch rate gyro, light turbulence (seed 0's case 113
    of the blind check, right under the seed-5 rules): q's residual is input-correlated
    beyond its surrogates (measured chi-square p 4.2e-11, calibrated the same, share
    0.31), and the lag or delay on q is named."""
    effect = Effect("lag", "longitudinal", "measured", {"channel": "q"},
                    {"tau": 0.1275964736351772})
    result = diagnose([fly_case(Case(113, 952364069, "c172p", "single", (effect,)),
                                "light")], "c172p", axis="longitudinal", try_pairs=False,
                      steps=1)
    q = result.null_before.channels["q"]
    assert q.p_value < ALPHA and q.share >= MATERIAL, q.to_json()
    assert result.named and same(effect, result.named[0]), [r.candidate.label
                                                            for r in result.named]
