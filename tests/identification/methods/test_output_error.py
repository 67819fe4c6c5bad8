"""Output error: the published Twin Otter results, synthetic truth recovery, identifiability.

Synthetic flights are made by the linear models themselves, with two parameter sets:
* Twin Otter: the published output-error values of Morelli & Klein (2016) example 6.1
  (lateral) with the mass, inertia and trim of the NASA record totter_f1_017;
* Navion: Teper (NASA CR-96008, 1969) as tabulated by Nelson (1998), appendix B
  (sea level, 176 ft/s, 2750 lb, Ixx 1048, Iyy 3000, Izz 3530 slug ft^2).
"""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.estimate import StdKind
from flightid.identification.identify import identify
from flightid.identification.methods import output_error as oe
from flightid.identification.methods.output_error_problem import (
    _outputs,
    _outputs_and_sensitivities,
    problem_from_record,
)
from flightid.identification.models import linear as lm
from flightid.identification.models.discrete import simulate
from flightid.identification.models.longitudinal import (
    LONGITUDINAL_DEFAULT,
    SHORT_PERIOD_DEFAULT,
    SHORT_PERIOD_DERIVATIVES,
    longitudinal,
    short_period,
)
from flightid.identification.models.reference_condition import (
    ReferenceCondition,
    condition_from_record,
)
from flightid.record import FlightRecord, RecordMeta, Reference
from flightid.units import FT, SLUG, SLUG_FT2
from tests.conftest import TWIN_OTTER as TWIN_OTTER_FILE

TWIN_OTTER = ReferenceCondition(
    V=237.02 * FT, qbar=2696.6, alpha=0.0040, theta=0.0286, mass=339.30 * SLUG,
    Ixx=20902 * SLUG_FT2, Iyy=24256 * SLUG_FT2, Izz=38463 * SLUG_FT2, Ixz=1127 * SLUG_FT2,
    area=422.48 * FT**2, span=64.99 * FT, chord=6.496 * FT,
)
NAVION = ReferenceCondition(
    V=176.0 * FT, qbar=0.5 * 1.225 * (176.0 * FT) ** 2, alpha=0.0, theta=0.0,
    mass=2750.0 / 32.174 * SLUG, Ixx=1048 * SLUG_FT2, Iyy=3000 * SLUG_FT2,
    Izz=3530 * SLUG_FT2, Ixz=0.0, area=184.0 * FT**2, span=33.4 * FT, chord=5.7 * FT,
)

LATERAL_TRUTH = {
    "twin_otter": {
        "CY_beta": -0.8646, "CY_r": 0.9331, "CY_dr": 0.3800,
        "Cl_beta": -0.11959, "Cl_p": -0.5859, "Cl_r": 0.1889, "Cl_da": -0.2282,
        "Cl_dr": 0.0422, "Cn_beta": 0.08638, "Cn_p": -0.06441, "Cn_r": -0.19059,
        "Cn_da": -0.00298, "Cn_dr": -0.13548,
        "bias_betadot": 0.002, "bias_pdot": -0.01, "bias_rdot": 0.003, "bias_phidot": 0.0,
        "bias_ay": 0.05,
    },
    "navion": {
        "CY_beta": -0.564, "CY_r": 0.0, "CY_dr": 0.157,
        "Cl_beta": -0.074, "Cl_p": -0.410, "Cl_r": 0.107, "Cl_da": -0.134, "Cl_dr": 0.0118,
        "Cn_beta": 0.071, "Cn_p": -0.0575, "Cn_r": -0.125, "Cn_da": -0.0035,
        "Cn_dr": -0.072,
        "bias_betadot": -0.001, "bias_pdot": 0.02, "bias_rdot": -0.004, "bias_phidot": 0.001,
        "bias_ay": -0.1,
    },
}
LONGITUDINAL_TRUTH = {
    "navion": {
        "CD_0": 0.05, "CD_alpha": 0.33, "CL_0": 0.41, "CL_alpha": 4.44, "CL_de": 0.355,
        "Cm_alpha": -0.683, "Cm_q": -9.96, "Cm_de": -0.923, "Cm_alphadot": -4.36,
        "bias_Vdot": 0.05, "bias_alphadot": -0.002, "bias_qdot": 0.01, "bias_thetadot": 0.0,
        "bias_az": 0.2,
    },
}
CONDITIONS = {"twin_otter": TWIN_OTTER, "navion": NAVION}
# measurement noise (1 sigma, SI units): typical flight-test air data and inertial sensors
NOISE = {"beta": 0.1 * np.pi / 180, "p": 0.2 * np.pi / 180, "r": 0.2 * np.pi / 180,
         "phi": 0.2 * np.pi / 180, "ay": 0.05, "alpha": 0.1 * np.pi / 180,
         "q": 0.2 * np.pi / 180, "theta": 0.2 * np.pi / 180, "V": 0.2, "az": 0.1}


def multistep(t: np.ndarray, start: float, widths: list[float], signs: list[int],
              amplitude: float) -> np.ndarray:
    """A multi-step input (3211, 2-1-1, doublet) in rad: pulses of the given widths (s)."""
    u = np.zeros_like(t)
    edge = start
    for width, sign in zip(widths, signs, strict=True):
        u[(t >= edge) & (t < edge + width)] = sign * amplitude
        edge += width
    return u


def lateral_inputs(t: np.ndarray, aileron: bool = True, rudder: bool = True,
                   trim: tuple[float, float] = (0.01, -0.005)) -> dict[str, np.ndarray]:
    """Aileron 3211 then rudder 2-1-1 (rad), on top of constant trim deflections."""
    da = trim[0] + (multistep(t, 1.0, [1.5, 1.0, 0.5, 0.5], [1, -1, 1, -1], 0.08)
                    if aileron else 0.0 * t)
    dr = trim[1] + (multistep(t, 7.0, [1.0, 0.5, 0.5], [1, -1, 1], 0.08) if rudder else 0.0 * t)
    return {"da": da, "dr": dr}


def record_from_model(model: lm.LinearModel, values: dict, inputs: dict[str, np.ndarray],
                      t: np.ndarray, seed: int | None, x0=None) -> FlightRecord:
    """A FlightRecord of the model's outputs (plus noise when seed is not None)."""
    u = np.column_stack([inputs[name] for name in model.inputs])
    y = simulate(model, values, t, u, x0=x0)
    channels = {name: y[:, j] for j, name in enumerate(model.outputs)}
    if seed is not None:
        rng = np.random.default_rng(seed)
        channels = {k: v + NOISE[k] * rng.standard_normal(v.size) for k, v in channels.items()}
    c = model.condition
    channels.update(inputs)
    meta = RecordMeta(aircraft="synthetic", sample_rate=1.0 / (t[1] - t[0]),
                      provenance=f"linear {model.name} model, seed {seed}",
                      reference=Reference(c.area, c.span, c.chord))
    return FlightRecord(t, channels, meta)


def _lateral_flight(aircraft: str, seed: int | None, **kw):
    model = lm.lateral(CONDITIONS[aircraft])
    t = np.arange(0.0, 16.0, 0.02)
    truth = LATERAL_TRUTH[aircraft]
    x0 = np.array([0.002, 0.0, 0.001, 0.01])
    return model, truth, record_from_model(model, truth, lateral_inputs(t, **kw), t, seed, x0)


def _perturbed_start(model: lm.LinearModel, truth: dict, factor: float = 0.3) -> dict:
    # every derivative 30 % off (alternating sign), biases from zero: a fair start
    out = {}
    for k, name in enumerate(model.parameters):
        if name.startswith("bias_"):
            out[name] = 0.0
        else:
            out[name] = truth[name] * (1 + factor * (-1) ** k) + (0.01 if truth[name] == 0 else 0)
    return out


# ------------------------------------------------------------------ real data


@pytest.fixture(scope="module")
def twin_otter():
    from flightid.record import read

    return read(TWIN_OTTER_FILE)


# Morelli & Klein (2016) example 6.1: output error, Cramer-Rao standard errors
PUBLISHED_OE = {
    "CY_beta": (-0.8646, 0.0028), "CY_r": (0.9331, 0.0167), "CY_dr": (0.3800, 0.0081),
    "Cl_beta": (-0.11959, 0.00061), "Cl_p": (-0.5859, 0.0026), "Cl_r": (0.1889, 0.0018),
    "Cl_da": (-0.2282, 0.0009), "Cl_dr": (0.0422, 0.0007), "Cn_beta": (0.08638, 0.00021),
    "Cn_p": (-0.06441, 0.00098), "Cn_r": (-0.19059, 0.00062), "Cn_da": (-0.00298, 0.00036),
    "Cn_dr": (-0.13548, 0.00027),
}


def test_twin_otter_reproduces_published_output_error(twin_otter):
    model = lm.lateral(condition_from_record(twin_otter))
    est = oe.estimate(twin_otter, model)
    assert est.fit["converged"], est.fit["reason"]
    assert est.unidentifiable == {}
    assert len(est.names) == 18  # 13 derivatives and 5 biases, as in the book
    for name, (value, std) in PUBLISHED_OE.items():
        # each estimate within 2 published standard errors of the published value
        assert abs(est[name] - value) < 2 * std, (name, est[name], value, std)
        # and the Cramer-Rao bounds of the published size (rounded to 2 digits there)
        assert 0.85 < est.std_of(name) / std < 1.2, (name, est.std_of(name), std)


def test_twin_otter_through_the_method_registry(twin_otter):
    # the model of M&K example 6.1: qbar held and the kinematics linearised
    est = identify(twin_otter, "oe", "lateral", colored=False, initial_state="measured",
                   start=None, dynamic_pressure=False)
    assert est.method == "oe" and est.fit["model"] == "lateral"
    value, std = PUBLISHED_OE["Cn_r"]
    assert abs(est["Cn_r"] - value) < 2 * std
    assert est.fit["R2"] > 0.9  # the published fit is close (M&K fig. 6.4)
    with pytest.raises(ValueError, match="unknown option.*colour.*method oe"):
        identify(twin_otter, "oe", "lateral", colour=True)


def test_twin_otter_zero_order_hold_is_what_breaks_the_match(twin_otter):
    # the published values need inputs interpolated between samples; holding them for a
    # sample delays them by half a sample, which moves Cl_p by many standard errors
    model = lm.lateral(condition_from_record(twin_otter))
    est = oe.estimate(twin_otter, model, hold="zoh")
    value, std = PUBLISHED_OE["Cl_p"]
    assert abs(est["Cl_p"] - value) > 5 * std


def test_twin_otter_colored_residual_bounds_are_larger(twin_otter):
    model = lm.lateral(condition_from_record(twin_otter))
    plain = oe.estimate(twin_otter, model)
    colored = oe.estimate(twin_otter, model, colored=True)
    ratio = colored.std / plain.std
    # real-data residuals are colored (unmodelled dynamics, M&K example 6.2): the
    # corrected bounds are larger, by factors of 3 to 9 (median about 6) with eq. 6.54
    # alone, median 9.3 with the fit's leverage put back (engine.bounds)
    assert np.all(ratio > 1.0)
    assert 1.5 < np.median(ratio) < 12.0
    assert colored.std_kind == StdKind.CRAMER_RAO_COLORED


# ------------------------------------------------------------------ synthetic truth


@pytest.mark.parametrize("aircraft", ["twin_otter", "navion"])
def test_noise_free_lateral_recovery(aircraft):
    model, truth, rec = _lateral_flight(aircraft, seed=None)
    est = oe.estimate(rec, model, start=_perturbed_start(model, truth),
                      initial_state="estimate")
    assert est.fit["converged"], est.fit["reason"]
    for name in model.parameters:
        if truth[name] != 0 and not name.startswith("bias_"):
            # the data are the model itself: recovery to rounding, far below 1 %
            assert est[name] == pytest.approx(truth[name], rel=1e-6), name


@pytest.mark.parametrize("aircraft,seed", [("twin_otter", 1), ("twin_otter", 3),
                                           ("navion", 3), ("navion", 4)])
def test_noisy_lateral_recovery_within_cramer_rao_bounds(aircraft, seed):
    model, truth, rec = _lateral_flight(aircraft, seed=seed)
    # x0 estimated: taking it from the noisy first sample would bias every estimate
    est = oe.estimate(rec, model, start=_perturbed_start(model, truth),
                      initial_state="estimate")
    assert est.fit["converged"], est.fit["reason"]
    names = [n for n in est.names if not n.startswith("x0_")]
    z = np.array([(est[n] - truth[n]) / est.std_of(n) for n in names])
    # white Gaussian noise: errors are N(0, CRB); every one within 3 bounds, and their
    # spread close to 1 (a chi-square check that the bounds are the right size). Over
    # seeds 1-8 the largest |error|/bound is 3.1 once (seed 2), as expected for the
    # maximum of 18 correlated normal draws about 5 % of the time.
    assert np.all(np.abs(z) < 3.0), dict(zip(names, z.round(2), strict=True))
    assert 0.4 < np.sqrt(np.mean(z**2)) < 1.6


def test_monte_carlo_scatter_matches_the_bounds():
    # 20 noise realisations: the scatter of Cl_p and Cn_r equals their Cramer-Rao bound
    model, truth, _ = _lateral_flight("twin_otter", seed=0)
    values, bounds = [], []
    for seed in range(20):
        _, _, rec = _lateral_flight("twin_otter", seed=100 + seed)
        est = oe.estimate(rec, model, start=truth, initial_state="estimate")
        values.append([est["Cl_p"], est["Cn_r"]])
        bounds.append([est.std_of("Cl_p"), est.std_of("Cn_r")])
    ratio = np.std(values, axis=0, ddof=1) / np.mean(bounds, axis=0)
    # the sample std of 20 draws is within about +-35 % of the true one (2 sigma)
    assert np.all((ratio > 0.6) & (ratio < 1.45)), ratio


def test_noisy_longitudinal_recovery():
    model = longitudinal(NAVION, derivatives=LONGITUDINAL_DEFAULT + ("Cm_alphadot",))
    truth = LONGITUDINAL_TRUTH["navion"]
    t = np.arange(0.0, 30.0, 0.02)
    de = -0.02 + multistep(t, 1.0, [3.0, 2.0, 1.0, 1.0], [1, -1, 1, -1], 0.03)
    x0 = np.array([NAVION.V, 0.05, 0.0, 0.05])
    rec = record_from_model(model, truth, {"de": de}, t, seed=5, x0=x0)
    est = oe.estimate(rec, model, free=[n for n in model.parameters if n != "CL_0"],
                      start={**_perturbed_start(model, truth, 0.2), "CL_0": truth["CL_0"]},
                      initial_state="estimate")
    assert est.fit["converged"], est.fit["reason"]
    for name in ("CL_alpha", "Cm_alpha", "Cm_q", "Cm_de", "CD_alpha", "CD_0"):
        assert abs(est[name] - truth[name]) < 3 * est.std_of(name), name


def _short_period_flight(derivatives):
    model = short_period(NAVION, derivatives=derivatives)
    truth = {**{k: v for k, v in LONGITUDINAL_TRUTH["navion"].items() if k in
                model.parameters}, "CL_q": 3.8, "bias_alphadot": 0.001, "bias_qdot": -0.02,
             "bias_az": 0.3}
    truth = {k: v for k, v in truth.items() if k in model.parameters}
    t = np.arange(0.0, 8.0, 0.02)
    de = multistep(t, 0.5, [0.6, 0.4, 0.2, 0.2], [1, -1, 1, -1], 0.05)
    return model, truth, record_from_model(model, truth, {"de": de}, t, seed=None)


def test_short_period_noise_free_recovery():
    model, truth, rec = _short_period_flight(SHORT_PERIOD_DEFAULT + ("CL_q",))
    est = oe.estimate(rec, model, start=_perturbed_start(model, truth, 0.2),
                      initial_state="zero")
    assert est.unidentifiable == {}
    for name in ("CL_alpha", "CL_q", "CL_de", "Cm_alpha", "Cm_q", "Cm_de"):
        assert est[name] == pytest.approx(truth[name], rel=1e-6), name


def test_short_period_cannot_separate_cm_q_from_cm_alphadot():
    # alphadot is a combination of alpha, q and de in the short period, so Cm_alphadot
    # only adds to the Cm_alpha, Cm_q, Cm_de entries of the model: a singular direction
    model, truth, rec = _short_period_flight(SHORT_PERIOD_DERIVATIVES)
    est = oe.estimate(rec, model, start=_perturbed_start(model, truth, 0.2),
                      initial_state="zero")
    assert len(est.unidentifiable) == 1
    (name, reason), = est.unidentifiable.items()
    assert name in ("Cm_q", "Cm_alphadot")
    assert "Cm_q" in reason and "Cm_alphadot" in reason and "singular" in reason
    # the identifiable combinations still fit the data exactly
    assert est.fit["noise_std"]["q"] < 1e-8


# ------------------------------------------------------------------ identifiability


def test_rudder_terms_unidentifiable_on_an_aileron_only_flight():
    model, truth, rec = _lateral_flight("twin_otter", seed=7, rudder=False)
    est = oe.estimate(rec, model, start=_perturbed_start(model, truth),
                      initial_state="estimate")
    assert set(est.unidentifiable) == {"CY_dr", "Cl_dr", "Cn_dr"}
    for name, reason in est.unidentifiable.items():
        assert "dr" in reason and "not excited" in reason, reason
        with pytest.raises(KeyError, match="unidentifiable"):
            est[name]
    assert est.fit["fixed"]["Cl_dr"] == _perturbed_start(model, truth)["Cl_dr"]
    # the rest is still estimated, within its bounds
    for name in ("Cl_p", "Cl_da", "Cn_beta", "Cn_r"):
        assert abs(est[name] - truth[name]) < 3 * est.std_of(name), name


def test_constant_but_nonzero_input_is_found_by_the_information_matrix():
    # with the input check off, the eigenvector of the smallest eigenvalue of the
    # normalised information matrix must name the aileron terms and the biases they
    # are confounded with (da is a constant 0.01 rad, so Cl_da da == a bias)
    model, truth, rec = _lateral_flight("navion", seed=8, aileron=False)
    est = oe.estimate(rec, model, start=_perturbed_start(model, truth), min_input_range=0.0)
    assert {"Cl_da", "Cn_da"} <= set(est.unidentifiable)
    assert "bias_pdot" in est.unidentifiable["Cl_da"] or "bias_rdot" in est.unidentifiable[
        "Cl_da"]
    assert "singular" in est.unidentifiable["Cl_da"]
    assert "Cl_p" in est.names and "bias_pdot" in est.names


def test_parameter_without_effect_has_zero_sensitivity():
    # CY_da multiplies da, which never moves off zero in this flight: no effect at all
    model = lm.lateral(NAVION, derivatives=lm.LATERAL_EXAMPLE_6_1 + ("CY_da",))
    truth = {**LATERAL_TRUTH["navion"], "CY_da": 0.0}
    t = np.arange(0.0, 16.0, 0.02)
    inputs = lateral_inputs(t, aileron=False, trim=(0.0, 0.0))
    rec = record_from_model(model, truth, inputs, t, seed=9)
    est = oe.estimate(rec, model, start=truth, min_input_range=0.0)
    assert "CY_da" in est.unidentifiable
    assert "zero sensitivity" in est.unidentifiable["CY_da"]


# ------------------------------------------------------------------ numerics


def test_sensitivities_equal_finite_differences():
    model, truth, rec = _lateral_flight("navion", seed=1)
    problem = problem_from_record(rec, model)
    names = list(model.parameters)
    y, sens = _outputs_and_sensitivities(problem, truth, names)
    for k, name in enumerate(names):
        h = 1e-6 * max(1.0, abs(truth[name]))
        up = _outputs(problem, {**truth, name: truth[name] + h})
        down = _outputs(problem, {**truth, name: truth[name] - h})
        fd = (up - down) / (2 * h)
        scale = np.max(np.abs(fd)) + 1e-12
        assert np.max(np.abs(sens[:, :, k] - fd)) < 1e-5 * scale, name


def test_colored_covariance_without_leverage_equals_the_direct_double_sum():
    rng = np.random.default_rng(0)
    n, ny, k = 60, 3, 4
    sens = rng.standard_normal((n, ny, k))
    white = rng.standard_normal((n + 5, ny))
    residuals = np.array([white[i:i + 5].sum(axis=0) for i in range(n)])  # colored
    weight = np.diag(1 / residuals.var(axis=0))
    info = np.einsum("iak,ab,ibl->kl", sens, weight, sens)
    fast = oe.colored_residual_covariance(sens, residuals, weight, info, leverage=False)
    # M&K eq. 6.54 literally: R_vv(l) = 1/N sum_i v(i+l) v(i)^T over all lags
    middle = np.zeros((k, k))
    ws = np.einsum("ab,ibk->iak", weight, sens)
    for i in range(n):
        for j in range(n):
            lag = i - j
            if lag >= 0:
                rvv = residuals[lag:].T @ residuals[:n - lag] / n
            else:
                rvv = (residuals[-lag:].T @ residuals[:n + lag] / n).T
            middle += ws[i].T @ rvv @ ws[j]
    inv = np.linalg.inv(info)
    np.testing.assert_allclose(fast, inv @ middle @ inv, rtol=1e-9, atol=1e-14)


def test_bad_input_is_reported_clearly():
    model, truth, rec = _lateral_flight("navion", seed=1)
    missing = FlightRecord(rec.time, {k: v for k, v in rec.channels.items() if k != "ay"},
                           rec.meta)
    with pytest.raises(ValueError, match="lacks channel.*ay"):
        oe.estimate(missing, model)
    bent = rec.time.copy()
    bent[100:] += 0.005
    with pytest.raises(ValueError, match="not uniformly sampled.*sample 99"):
        oe.estimate(FlightRecord(bent, rec.channels, rec.meta), model)
    with pytest.raises(ValueError, match="not parameter"):
        oe.estimate(rec, model, free=["Cm_q"])
    with pytest.raises(ValueError, match="hold must be one of.*spline"):
        oe.estimate(rec, model, hold="spline")
