"""Truth derivatives: closed form on a linear aircraft, the stock DHC6's XML constants,
kink flags, stability-axis rotation, JSBSim's linearization, and the truth files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from flightid import aircraft
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.jsbsim.truth import derivatives, linearization, pitch_entries
from flightid.sim.jsbsim.truth_files import compare_to_file, truth_file

HERE = Path(__file__).parents[1] / "aircraft" / "linear_test"
LINEAR = HERE / "linear_test.xml"
COEFFS = json.loads((HERE / "coefficients.json").read_text())
VARS = ("alpha", "beta", "p", "q", "r", "alphadot", "de", "da", "dr")


@pytest.fixture(scope="module", params=[(1000.0, 55.0), (0.0, 45.0)], ids=["1000m-55", "0m-45"])
def linear(request):
    model = load(str(LINEAR))
    t = trim(model, *request.param)
    return model, t


def test_linear_aircraft_body_derivatives_exact(linear):
    model, t = linear
    truth = derivatives(model, t, axes="body")
    assert not truth.flags
    for coef, terms in COEFFS.items():
        for var in VARS:
            want = terms.get(var, 0.0)
            got = truth.values[f"C{coef}_{var}"]
            # the model is linear: only roundoff separates the difference from the slope
            assert got == pytest.approx(want, rel=1e-6, abs=1e-9), f"C{coef}_{var}"


def test_linear_aircraft_values_at_trim(linear):
    model, t = linear
    truth = derivatives(model, t, axes="body")
    # C_0 = C0 + C_alpha alpha + C_de de at trim (rates zero in level flight)
    for coef in ("X", "Z", "m"):
        c = COEFFS[coef]
        want = c.get("0", 0.0) + c.get("alpha", 0.0) * t.alpha + c.get("de", 0.0) * t.elevator
        # the trim leaves residuals (alphadot ~1e-7 rad/s, Earth-rate q ~1e-5 rad/s,
        # qdot < 1e-4 rad/s^2) that move the coefficients by well under 1e-6
        assert truth.values[f"C{coef}_0"] == pytest.approx(want, abs=1e-6)


def test_linear_aircraft_lift_and_stability_axes(linear):
    model, t = linear
    body = derivatives(model, t, axes="body").values
    stab = derivatives(model, t, axes="stability").values
    a = t.alpha
    cx0, cz0 = body["CX_0"], body["CZ_0"]
    # CL = CX sin a - CZ cos a, differentiated with the local alpha. CL is not linear in
    # alpha (the rotation): the central difference at h = 0.125 deg errs by h^2/6 times
    # the third derivative of CL, ~ 5 * 2.2e-3^2 / 6 ~ 4e-6, hence rel 1e-5 here
    cl_alpha = (COEFFS["X"]["alpha"] * math.sin(a) + cx0 * math.cos(a)
                - COEFFS["Z"]["alpha"] * math.cos(a) + cz0 * math.sin(a))
    assert stab["CL_alpha"] == pytest.approx(cl_alpha, rel=1e-5)
    # Etkin & Reid: Cl_s = Cl cos a + Cn sin a, p_s = p cos a + r sin a
    ca, sa = math.cos(a), math.sin(a)
    l, n = COEFFS["l"], COEFFS["n"]
    dl_dp = l["p"] * ca + l["r"] * sa
    dn_dp = n["p"] * ca + n["r"] * sa
    assert stab["Cl_p"] == pytest.approx(dl_dp * ca + dn_dp * sa, rel=1e-6)
    dl_dr = -l["p"] * sa + l["r"] * ca
    dn_dr = -n["p"] * sa + n["r"] * ca
    assert stab["Cn_r"] == pytest.approx(dn_dr * ca - dl_dr * sa, rel=1e-6)
    assert stab["Cn_beta"] == pytest.approx(n["beta"] * ca - l["beta"] * sa, rel=1e-6)
    assert "CX_alpha" not in stab and "CZ_alpha" not in stab


@pytest.fixture(scope="module")
def dhc6():
    model = load("DHC6")
    t = trim(model, 1920.0, 72.3)
    return model, t, derivatives(model, t, axes="body")


def _transfer(truth, coef, var):
    """Change of a moment derivative from the DHC6's AERORP to its CG (body axes).

    M_cg = M_rp - d x F with d = r_cg - r_rp: Cl -= (dy CZ - dz CY)/b,
    Cm -= (dz CX - dx CZ)/cbar, Cn -= (dx CY - dy CX)/b, with the force derivatives.
    """
    dx, dy, dz = truth.cg_minus_aerorp_m
    b, c = truth.reference.span, truth.reference.chord
    f = {k: truth.values[f"C{k}_{var}"] for k in ("X", "Y", "Z")}
    return {"l": -(dy * f["Z"] - dz * f["Y"]) / b,
            "m": -(dz * f["X"] - dx * f["Z"]) / c,
            "n": -(dx * f["Y"] - dy * f["X"]) / b}[coef]


@pytest.mark.parametrize(("name", "xml_value", "rel", "within_2_percent"), [
    ("Cn_r", -0.18, 1e-6, True), ("Cl_p", -0.50, 1e-6, True), ("Cn_dr", -0.125, 1e-6, True),
    ("Cn_p", -0.06, 1e-6, True), ("Cm_alphadot", -8.0, 1e-6, True),
    # the CG lies 0.30 m below the AERORP: the side force adds 10-15 % to these
    ("Cl_r", 0.06, 1e-6, False), ("Cl_dr", 0.015, 1e-6, False),
    # DHC6's CmT term multiplies the propulsion thrust coefficient, and JSBSim's propeller
    # sees q through its local inflow (omega x r at the propeller): +0.016 per qhat more
    ("Cm_q", -34.2, 1e-3, True),
])
def test_dhc6_moment_derivatives_are_its_xml_constants_moved_to_the_cg(dhc6, name, xml_value,
                                                                    rel, within_2_percent):
    """DHC6.xml normalises rates with b/2V (bi2vel) and cbar/2V (ci2vel), as we do; its
    moments are about the AERORP (x 211.8 in), the CG is elsewhere (point masses), so the
    truth about the CG is the XML constant plus the lever-arm term."""
    _, _, truth = dhc6
    coef, var = name[1], name.split("_", 1)[1]
    want = xml_value + _transfer(truth, coef, var)
    assert truth.values[name] == pytest.approx(want, rel=rel)
    if within_2_percent:
        assert truth.values[name] == pytest.approx(xml_value, rel=0.02)


@pytest.mark.parametrize(("name", "xml_value"), [
    ("CY_p", -0.20), ("CY_r", 0.40), ("CY_dr", 0.15),
])
def test_dhc6_side_force_derivatives_are_its_xml_constants(dhc6, name, xml_value):
    _, _, truth = dhc6
    assert truth.values[name] == pytest.approx(xml_value, rel=1e-6)


def test_dhc6_side_force_due_to_sideslip(dhc6):
    """DHC6's SIDE force is in wind axes; body Y = Y_w cos b - D sin b, so
    CY_beta(body) = -0.60 - CD at trim."""
    _, _, truth = dhc6
    want = -0.60 - truth.values["CD_0"]
    assert truth.values["CY_beta"] == pytest.approx(want, rel=0.005)
    assert truth.values["CY_beta"] == pytest.approx(-0.60, rel=0.11)


def test_dhc6_lift_derivatives(dhc6):
    _, _, truth = dhc6
    assert truth.values["CL_q"] == pytest.approx(19.97, rel=1e-6)
    assert truth.values["CL_de"] == pytest.approx(0.608, rel=1e-6)


def test_dhc6_roll_due_to_sideslip_is_flagged_as_a_kink(dhc6):
    """DHC6.xml tabulates Clb symmetric in beta (0.036 at +-5 deg, alpha 4 deg): a V-shaped
    kink at beta = 0, so the truth gives both one-sided slopes instead of a derivative."""
    _, t, truth = dhc6
    assert "Cl_beta" not in truth.values
    kink = truth.flags["Cl_beta"]
    assert kink.minus < -0.3 and kink.plus > 0.3
    # the table's own slopes at trim alpha (interpolated between the 0.0698 column and
    # the 0.1745 column): left -(0.036 .. 0.027)/0.0873, right (0.036 .. -0.017)/0.0873
    assert abs(kink.minus) == pytest.approx(abs(kink.plus), rel=0.1)
    assert "Cn_r" not in truth.flags  # smooth terms are not flagged


def test_step_sizes_agree_for_smooth_terms(dhc6):
    _, _, truth = dhc6
    for name in ("CL_alpha", "Cm_alpha", "Cn_beta", "Cm_q"):
        assert truth.step_spread[name] < 1e-3 * max(1.0, abs(truth.values[name]))


def test_short_period_entries_match_jsbsim_linearization(dhc6):
    """qdot = M_alpha alpha + M_q q + M_alphadot alphadot, so A[q, alpha] = M_alpha +
    M_alphadot A[alpha, alpha] and A[q, q] = M_q + M_alphadot A[alpha, q] (Etkin & Reid)."""
    model, t, truth = dhc6
    ss = linearization(model, t)
    i_a, i_q = ss.x_names.index("Alpha"), ss.x_names.index("Q")
    assert ss.x_units[i_a] == "rad" and ss.x_units[i_q] == "rad/s"
    m = pitch_entries(truth)
    a = ss.A
    assert a[i_q, i_a] == pytest.approx(m["M_alpha"] + m["M_alphadot"] * a[i_a, i_a], rel=0.01)
    assert a[i_q, i_q] == pytest.approx(m["M_q"] + m["M_alphadot"] * a[i_a, i_q], rel=0.01)


def test_truth_file_format_errors_are_specific(tmp_path):
    bad = tmp_path / "truth.toml"
    bad.write_text("[condition]\naltitude_m = 0.0\n")
    with pytest.raises(ValueError, match="'speed_m_s' missing"):
        truth_file(str(bad))
    bad.write_text("[condition]\naltitude_m = 0.0\nspeed_m_s = 50.0\n"
                   "[derivatives.CL_alfa]\nvalue = 4.4\n")
    with pytest.raises(ValueError, match="CL_alfa.*not a canonical derivative"):
        truth_file(str(bad))
    bad.write_text("[condition]\naltitude_m = 0.0\nspeed_m_s = 50.0\naxes = 'wind'\n")
    with pytest.raises(ValueError, match="axes must be 'body' or 'stability'"):
        truth_file(str(bad))
    with pytest.raises(FileNotFoundError, match="no truth file"):
        truth_file("c172p")


WITH_TRUTH = [n for n in aircraft.names() if aircraft.truth_path(n) is not None]


@pytest.mark.parametrize("name", WITH_TRUTH)
def test_project_aircraft_reproduce_their_truth_files(name):
    """The JSBSim model of each project aircraft gives the derivatives its truth file cites
    (2 %, or 1e-3 absolute for near-zero values), in the axes the file states."""
    assert compare_to_file(name) == []


def test_truth_is_a_pure_function_of_aircraft_and_trim(dhc6):
    model, t, truth = dhc6
    from flightid.sim.flight.simulation import fly

    fly(model, t, {"de": np.full(101, 0.05)}, 1.0)  # whatever happened to the model before
    again = derivatives(model, t, axes="body")
    assert again.values == truth.values


# -- total (aerodynamic + propulsive) derivatives -------------------------------------------

def _thruster_y_m(model) -> list[float]:
    """Lateral positions (m, right +) of the thrusters relative to the CG, from the XML."""
    import xml.etree.ElementTree as ET

    from flightid.units import FT, IN

    cg_y = model.get("inertia/cg-y-in") * IN
    out = []
    for loc in ET.parse(model.xml_path).getroot().iter("thruster"):
        el = loc.find("location")
        scale = {"M": 1.0, "IN": IN, "FT": FT}
        out.append(float(el.findtext("y")) * scale[el.get("unit", "IN")] - cg_y)
    return out


def _thrust_slope_n_per_m_s(model, t, engine: int) -> float:
    """dT/du (N per m/s) of one engine at its trim rpm: forward speed +- 0.5 m/s, run_ic."""
    from flightid.sim.jsbsim.trim import apply
    from flightid.units import FT, LBF

    thrust, du_span = [], 1.0
    for du in (du_span / 2, -du_span / 2):
        m = model.copy()
        apply(m, t)
        for prop, value in t.jsbsim.items():
            m.fdm[prop] = value
        m.fdm["ic/u-fps"] = m.fdm["velocities/u-fps"] + du / FT
        m.fdm["ic/v-fps"] = m.fdm["velocities/v-fps"]
        m.fdm["ic/w-fps"] = m.fdm["velocities/w-fps"]
        m.fdm.set_trim_status(True)
        m.fdm.run_ic()
        m.fdm.set_trim_status(False)
        thrust.append(m.fdm[f"propulsion/engine[{engine}]/thrust-lbs"] * LBF)
    return (thrust[0] - thrust[1]) / du_span


@pytest.fixture(scope="module")
def twinotter_both():
    model = load("twinotter")
    t = trim(model, 1897.0, 61.733333)
    return (model, t, derivatives(model, t, axes="body"),
            derivatives(model, t, axes="body", propulsion=True))


def test_twinotter_total_yaw_damping_is_aero_plus_differential_thrust(twinotter_both):
    """Each propeller at y sees u - r y, so its thrust changes by -dT/du r y and its yaw
    moment -y dT by y^2 dT/du r: N_r = sum(y^2 dT/du) < 0 since thrust falls with speed
    (moment budget, thrust along body x). The total Cn_r must differ from the aerodynamic
    one by that, nondimensionalised by qSb b/2V."""
    model, t, aero, total = twinotter_both
    assert not aero.propulsion and total.propulsion
    ys = _thruster_y_m(model)
    assert len(ys) == 2 and ys[0] == pytest.approx(-ys[1], rel=1e-6)
    n_r = sum(y * y * _thrust_slope_n_per_m_s(model, t, i) for i, y in enumerate(ys))
    st, ref = total.state, total.reference
    dcn_r = n_r / (st["qbar"] * ref.area * ref.span * ref.span / (2 * st["V"]))
    got = total.values["Cn_r"] - aero.values["Cn_r"]
    assert n_r < -1000.0  # N m s/rad: a damping, of the size the flight records show
    # JSBSim's propeller thrust depends on the axial inflow u - r y alone and is smooth in
    # it: the budget (dT/du over +-0.5 m/s) and the truth (r steps of ~0.07 m/s at the
    # propellers) differ only by the curvature of T(u), measured 1e-8 relative; 1 %
    assert got == pytest.approx(dcn_r, rel=0.01)
    assert got / aero.values["Cn_r"] > 0.02  # a few percent of Cn_r: why it matters


def test_twinotter_total_keeps_the_aerodynamic_derivatives_thrust_cannot_change(twinotter_both):
    """The propellers' thrust depends only on the inflow along their axis: roll rate,
    sideslip and the controls do not change it, so those derivatives stay aerodynamic."""
    _, _, aero, total = twinotter_both
    for name in ("Cl_p", "Cn_beta", "Cl_da", "Cn_dr", "CY_beta", "Cm_de"):
        assert total.values[name] == pytest.approx(aero.values[name], rel=1e-6, abs=1e-9), name


def test_engine_rpm_is_frozen_during_a_truth_evaluation(twinotter_both):
    """run_ic evaluates at dt = 0: the propeller rpm stays at trim whatever the state."""
    from flightid.sim.jsbsim.truth import _Evaluator

    model, t, _, _ = twinotter_both
    ev = _Evaluator(model.copy(), t, propulsion=True)
    fdm = ev.model.fdm
    rpm = "propulsion/engine[{}]/propeller-rpm"
    ev()
    trim_rpm = [fdm[rpm.format(i)] for i in (0, 1)]
    for state in ({"r": 0.02}, {"alpha": 0.05}, {"q": -0.02}, {"beta": 0.05}):
        ev(**state)
        assert [fdm[rpm.format(i)] for i in (0, 1)] == trim_rpm, state


def test_navion_single_engine_on_the_centreline_total_equals_aero_yaw_damping():
    """One propeller on the centreline: a yaw rate changes no propeller's inflow, so the
    total rate derivatives equal the aerodynamic ones (0.1 %: the Navion's propeller
    torque and gyroscopic moments do not depend on r or p at frozen rpm)."""
    model = load("navion")
    t = trim(model, 0.0, 53.6448)
    aero = derivatives(model, t, axes="stability")
    total = derivatives(model, t, axes="stability", propulsion=True)
    for name in ("Cn_r", "Cl_r", "Cn_p", "Cl_p"):
        assert total.values[name] == pytest.approx(aero.values[name], rel=1e-3), name
