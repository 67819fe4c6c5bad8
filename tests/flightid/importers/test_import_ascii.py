"""``flightid import`` of delimited text: a DLR-style ASCII export (header row, units row,
time with rounding jitter) of a real JSBSim flight, imported with a mapping file and the
aircraft's constants, equals the flight and identifies as it does."""

from __future__ import annotations

import dataclasses
import json

import jsbsim
import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.api import fly, identify, score
from flightid.cli.app import app
from flightid.identification.data.reduction import reduce_record
from flightid.importers.ascii import read_delimited
from flightid.importers.constants import read_constants
from flightid.importers.mapping import ColumnMap, read_map
from flightid.record import FlightRecord, read
from flightid.sim.jsbsim.model import load
from flightid.units import DEG, FT, G0, KT, LBF, LBM, PSF, SLUG_FT2

# DLR-style columns: (name, unit in the file, flightid channel, factor SI -> file unit)
COLUMNS = (
    ("DELV", "RAD", "de", 1.0), ("PDYN", "PA", "qbar", 1.0), ("THRUST", "N", "thrust", 1.0),
    ("TASCG", "M/S", "V", 1.0), ("ALFCG", "RAD", "alpha", 1.0), ("THE", "RAD", "theta", 1.0),
    ("Q", "RAD/S", "q", 1.0), ("BETCG", "DEG", "beta", 1 / DEG), ("PHI", "RAD", "phi", 1.0),
    ("P", "RAD/S", "p", 1.0), ("R", "RAD/S", "r", 1.0), ("AXCG", "M/S2", "ax", 1.0),
    ("AYCG", "M/S2", "ay", 1.0), ("AZCG", "M/S2", "az", 1.0), ("HP", "FT", "h", 1 / FT),
    ("DELA", "RAD", "da", 1.0), ("DELR", "RAD", "dr", 1.0), ("PLA", "-", "throttle", 1.0),
)
JITTER_S = 1e-5  # the time column's rounding jitter, as in the real file
DIGITS = 7  # significant digits of the export
WINDOW = "1.0,11.5"  # the 2-1 doublet at 2 s and the response after it (the card's window)


@pytest.fixture(scope="module")
def flight():
    return fly("twinotter-21-elevator", seed=3)


def write_dlr(flight, path, *, cut_last: bool = False) -> None:
    """The measured record as a DLR-style whitespace ASCII file (no mass, no geometry)."""
    rec = flight.measured
    t = rec.time + np.random.default_rng(0).uniform(-JITTER_S, JITTER_S, len(rec))
    lines = [" ".join(["T", *(c[0] for c in COLUMNS), "NZ", "TAT"]),
             " ".join(["S", *(c[1] for c in COLUMNS), "G", "K"])]
    for i in range(len(rec)):
        fields = [f"{t[i]:.5f}", *(f"{rec[ch][i] * k:.{DIGITS}g}" for _, _, ch, k in COLUMNS),
                  f"{-rec['az'][i] / G0:.{DIGITS}g}", "288.15"]
        lines.append(" ".join(fields))
    if cut_last:
        lines[-1] = lines[-1][: len(lines[-1]) // 2]
    path.write_text("\n".join(lines) + "\n")


def write_mapping(path) -> None:
    entries = ['T = "time"', *(f'{c} = "{ch}"' for c, _, ch, _ in COLUMNS)]
    path.write_text("[columns]\n" + "\n".join(entries) + "\n")


@pytest.fixture(scope="module")
def imported(flight, tmp_path_factory):
    folder = tmp_path_factory.mktemp("dlr")
    data, mapping, out = folder / "flight.asc", folder / "map.toml", folder / "flight.parquet"
    write_dlr(flight, data)
    write_mapping(mapping)
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--mapping",
                                      str(mapping), "--aircraft", "twinotter"])
    return result, out


def test_the_file_imports_with_one_command_and_says_it_regridded(imported):
    result, out = imported
    assert result.exit_code == 0, result.output
    assert "re-gridded to a uniform 0.05 s step" in result.output
    assert "kept under their own names: NZ, TAT" in result.output
    rec = read(out)
    assert rec.meta.extra["regridded"]["max_jitter"] < 0.01
    assert rec.unit("NZ") == "m/s^2" and rec.unit("TAT") == "K"


def test_the_imported_record_equals_the_flight(flight, imported):
    rec, truth = read(imported[1]), flight.measured
    assert len(rec) == len(truth)
    assert np.max(np.abs(rec.time - truth.time)) < 2 * JITTER_S
    for name, x in ((ch, truth[ch]) for _, _, ch, _ in COLUMNS):
        assert np.max(np.abs(rec[name] - x)) < _tolerance(x, truth.dt), name
    assert np.max(np.abs(rec["NZ"] + truth["az"])) < _tolerance(truth["az"], truth.dt)
    # constants of the aircraft (the file has none)
    model = load("twinotter")
    for name, value in model.mass_properties().items():
        assert rec[name] == pytest.approx(np.full(len(rec), value)), name
    assert rec.meta.reference == model.reference
    # the file has no reference condition: it is the record's means (V, h, alpha, beta,
    # qbar, mass), within the 7 digits and the re-grid
    assert set(rec.meta.condition) >= {"V", "h", "alpha", "beta", "qbar", "mass"}
    for name in ("V", "h", "alpha", "beta", "qbar"):
        x = truth[name]
        assert rec.meta.condition[name] == pytest.approx(np.mean(x), abs=_tolerance(x, truth.dt))
    assert rec.meta.condition["mass"] == pytest.approx(model.mass_properties()["mass"])


def _tolerance(x: np.ndarray, dt: float) -> float:
    """The export's 7 digits, plus the re-grid: a value moves by about the jitter (the
    grid's distance from the true times, < 2e-5 s) times the channel's rate of change."""
    rate = np.max(np.abs(np.diff(x))) / dt
    return 10 ** -(DIGITS - 1) * np.max(np.abs(x)) + 2 * JITTER_S * rate + 1e-12


def test_identify_runs_on_it_and_recovers_the_flight(flight, imported):
    out = imported[1]
    result = CliRunner().invoke(app, ["identify", str(out), "--window", WINDOW,
                                      "--format", "json", "--truth", _truth_file(flight, out)])
    assert result.exit_code == 0, result.output
    rec = read(out)
    window = tuple(float(x) for x in WINDOW.split(","))
    # the imported record has no maneuver list, so its linear model is referred to the
    # window's mean rather than to the trim before the first maneuver
    # (models.reference_condition.trim_lead): compare with the original without its list
    extra = {k: v for k, v in flight.measured.meta.extra.items() if k != "maneuvers"}
    unlisted = FlightRecord(flight.measured.time, flight.measured.channels,
                            dataclasses.replace(flight.measured.meta, extra=extra))
    est, original = identify(rec, "oe", window=window), identify(unlisted, "oe", window=window)
    assert est.names == original.names
    # the import changes the estimates by a small fraction of their bounds (measured: 0.01)
    assert np.all(np.abs(est.values - original.values) < 0.1 * original.std)
    rows = {r.name: r for r in score(est, flight.truth).rows}
    for name in ("Cm_alpha", "Cm_q", "Cm_de"):  # measured: +1.8, -0.5, +0.3 sigma
        assert abs(rows[name].sigmas) < 3.0, name


def _truth_file(flight, out) -> str:
    path = out.with_name("truth.json")
    path.write_text(json.dumps(flight.truth))
    return str(path)


def test_constants_from_a_toml_file_in_imperial_units(tmp_path):
    model = load("twinotter")
    mp, ref = model.mass_properties(), model.reference
    path = tmp_path / "aircraft.toml"
    path.write_text(f"""name = "Twin Otter"
[mass_properties]
mass = "{mp['mass'] / LBM!r} lb"
Ixx = "{mp['Ixx'] / SLUG_FT2!r} slug*ft^2"
Iyy = "{mp['Iyy'] / SLUG_FT2!r} slug ft2"
Izz = {mp['Izz']!r}
Ixz = {mp['Ixz']!r}
[reference]
area = "{ref.area / FT**2!r} ft^2"
span = "{ref.span / FT!r} ft"
chord = {ref.chord!r}
[sensors]
alpha_vane = ["15 ft", 0, "-1 ft"]
""")
    got = read_constants(path)
    for name, value in mp.items():
        assert got.mass_properties[name] == pytest.approx(value, rel=1e-12), name
    for key in ("area", "span", "chord"):
        assert getattr(got.reference, key) == pytest.approx(getattr(ref, key), rel=1e-12)
    assert got.sensors["alpha_vane"] == pytest.approx((15 * FT, 0.0, -FT))


def test_imperial_units_from_a_units_row_are_converted_to_si(tmp_path):
    """A units row in the issue's imperial units: psf, lb as a force (thrust) and as a mass,
    slug*ft^2, kt, ft, deg/s and g, each converted by its exact factor."""
    path = tmp_path / "imperial.asc"
    path.write_text("T QBAR THRUST M IXX VT H Q AZ\n"
                    "S PSF LB LB SLUG*FT^2 KT FT DEG/S G\n"
                    "0.0 50 200 1880 1524 100 5000 2.0 -1.0\n"
                    "0.1 51 210 1880 1524 101 5010 -1.0 -1.1\n")
    rec = read_delimited(path, ColumnMap({"T": "time", "QBAR": "qbar", "THRUST": "thrust",
                                          "M": "mass", "IXX": "Ixx", "VT": "V", "H": "h",
                                          "Q": "q", "AZ": "az"}))
    expected = {"qbar": np.array([50, 51]) * PSF, "thrust": np.array([200, 210]) * LBF,
                "mass": np.array([1880, 1880]) * LBM, "Ixx": np.array([1524, 1524]) * SLUG_FT2,
                "V": np.array([100, 101]) * KT, "h": np.array([5000, 5010]) * FT,
                "q": np.array([2.0, -1.0]) * DEG, "az": np.array([-1.0, -1.1]) * G0}
    for name, values in expected.items():
        np.testing.assert_allclose(rec[name], values, rtol=1e-15, err_msg=name)


def test_units_from_the_mapping_file_and_the_command_line(tmp_path):
    """A file without a units row: the mapping file's [units] give them; ``--map`` and
    ``--unit`` on the command line win over the file's entries."""
    data, mapping, out = tmp_path / "f.csv", tmp_path / "map.toml", tmp_path / "f.parquet"
    data.write_text("T,AOA,VIAS,HP\n0.0,2.0,100,5000\n0.1,2.5,101,5010\n0.2,3.0,102,5020\n")
    mapping.write_text('[columns]\nT = "time"\nAOA = "alpha"\nVIAS = "V"\nHP = "h"\n'
                       '[units]\nAOA = "deg"\nVIAS = "kt"\nHP = "ft"\n')
    rec = read_delimited(data, read_map(mapping))
    np.testing.assert_allclose(rec["alpha"], np.array([2.0, 2.5, 3.0]) * DEG, rtol=1e-15)
    np.testing.assert_allclose(rec["V"], np.array([100, 101, 102]) * KT, rtol=1e-15)
    np.testing.assert_allclose(rec["h"], np.array([5000, 5010, 5020]) * FT, rtol=1e-15)
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--mapping",
                                      str(mapping), "--unit", "VIAS=m/s", "--map", "HP=alt"])
    assert result.exit_code == 2  # the command line's map wins: 'alt' is no channel
    assert "'alt' is not a flightid channel; valid channels: time" in result.output
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--mapping",
                                      str(mapping), "--unit", "VIAS=m/s"])
    assert result.exit_code == 0, result.output
    np.testing.assert_allclose(read(out)["V"], [100.0, 101.0, 102.0], rtol=1e-15)


def test_constants_of_a_stock_jsbsim_aircraft_by_name(tmp_path):
    """``--aircraft c172p``, JSBSim's own Cessna 172P (not one of the project's): the
    constants are those JSBSim itself holds once initialised (fuel and payload in)."""
    path, out = tmp_path / "c172.csv", tmp_path / "c172.parquet"
    path.write_text("time,V (kt),alpha [deg],q [deg/s]\n0.0,100,2.0,0.5\n0.1,101,2.5,1.0\n"
                    "0.2,102,3.0,-0.5\n")
    result = CliRunner().invoke(app, ["import", str(path), "-o", str(out), "--aircraft",
                                      "c172p"])
    assert result.exit_code == 0, result.output
    rec = read(out)
    fdm = jsbsim.FGFDMExec(None)
    fdm.set_debug_level(0)
    fdm.load_model("c172p")
    fdm.run_ic()
    assert rec["mass"][0] == pytest.approx(fdm["inertia/weight-lbs"] * LBM, rel=1e-6)
    assert rec["Ixx"][0] == pytest.approx(fdm["inertia/ixx-slugs_ft2"] * SLUG_FT2, rel=1e-6)
    assert rec["Iyy"][0] == pytest.approx(fdm["inertia/iyy-slugs_ft2"] * SLUG_FT2, rel=1e-6)
    ref = rec.meta.reference
    assert ref.area == pytest.approx(fdm["metrics/Sw-sqft"] * FT**2, rel=1e-9)
    assert ref.span == pytest.approx(fdm["metrics/bw-ft"] * FT, rel=1e-9)
    assert ref.chord == pytest.approx(fdm["metrics/cbarw-ft"] * FT, rel=1e-9)


def test_sensor_positions_reach_the_data_reduction(flight, tmp_path):
    """The constants file's sensor positions go with the record to ``identify``'s standard
    data reduction, which moves the accelerometers and the vanes to the CG; a sensor it
    does not correct is refused, naming the ones it does."""
    data, mapping, out = tmp_path / "f.asc", tmp_path / "map.toml", tmp_path / "f.parquet"
    write_dlr(flight, data)
    write_mapping(mapping)
    mp, ref = load("twinotter").mass_properties(), load("twinotter").reference
    constants = tmp_path / "aircraft.toml"
    body = "\n".join(f"{k} = {v!r}" for k, v in mp.items())
    constants.write_text(f"[mass_properties]\n{body}\n[reference]\narea = {ref.area!r}\n"
                         f"span = {ref.span!r}\nchord = {ref.chord!r}\n[sensors]\n"
                         'accelerometers = ["3 ft", 0, 0]\nalpha_vane = [4.0, 0.0, 0.0]\n')
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--mapping",
                                      str(mapping), "--aircraft", str(constants)])
    assert result.exit_code == 0, result.output
    rec = read(out)
    assert rec.meta.extra["sensor_positions"]["accelerometers"] == pytest.approx([3 * FT, 0, 0])
    applied = " | ".join(reduce_record(rec).applied)
    assert "accelerometers moved to the CG from (0.9144, 0, 0) m" in applied
    assert "flow angles: alpha" in applied and "position effect removed" in applied
    constants.write_text('[sensors]\naccelerometer = [1.0, 0.0, 0.0]\n')
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--mapping",
                                      str(mapping), "--aircraft", str(constants)])
    assert result.exit_code == 2
    assert "accelerometer: not a sensor the data reduction corrects; valid: " \
        "accelerometers, alpha_vane, beta_vane" in result.output


def test_a_cut_last_row_is_dropped_and_said(flight, tmp_path):
    data = tmp_path / "cut.asc"
    write_dlr(flight, data, cut_last=True)
    mapping = ColumnMap({"T": "time", **{c: ch for c, _, ch, _ in COLUMNS}})
    rec = read_delimited(data, mapping)
    assert len(rec) == len(flight.measured) - 1
    assert "the last row has" in rec.meta.extra["import"]["dropped"][0]


def test_a_map_to_an_unknown_channel_is_refused_naming_the_valid_ones(flight, tmp_path):
    data, out = tmp_path / "f.asc", tmp_path / "f.parquet"
    write_dlr(flight, data)
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out),
                                      "--map", "T=time,ALFCG=aoa"])
    assert result.exit_code == 2
    assert "'aoa' is not a flightid channel; valid channels: time, V, alpha" in result.output
    assert "Traceback" not in result.output and not out.exists()


def test_a_column_in_the_wrong_unit_is_refused(flight, tmp_path):
    data, out = tmp_path / "f.asc", tmp_path / "f.parquet"
    write_dlr(flight, data)
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out),
                                      "--map", "T=time,TASCG=V,HP=alpha"])
    assert result.exit_code == 2
    assert "column HP (alpha): unit 'FT' is a unit of m, not of rad" in result.output


def test_degrees_taken_as_radians_are_refused_by_the_unit_check(flight, tmp_path):
    data, out = tmp_path / "f.asc", tmp_path / "f.parquet"
    write_dlr(flight, data)
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--map",
                                      "T=time,TASCG=V,PDYN=qbar,P=p,Q=q,R=r,PHI=phi,THE=theta",
                                      "--unit", "P=deg/s,Q=deg/s,R=deg/s"])
    assert result.exit_code == 2
    assert "units look wrong" in result.output and not out.exists()


def test_an_output_never_replaces_the_input(flight, tmp_path):
    data = tmp_path / "f.csv"
    write_dlr(flight, data)
    before = data.read_bytes()
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(data), "--map", "T=time"])
    assert result.exit_code == 2 and "an output never replaces an input" in result.output
    assert data.read_bytes() == before


def test_a_map_naming_a_column_the_file_lacks_is_refused_naming_its_columns(flight, tmp_path):
    data, out = tmp_path / "f.asc", tmp_path / "f.parquet"
    write_dlr(flight, data)
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--map",
                                      "T=time,ALPHA=alpha"])
    assert result.exit_code == 2
    assert "does not have; its columns: T, DELV, PDYN" in result.output


def test_a_csv_with_units_in_its_names_needs_no_map(tmp_path):
    # flightid names with units in brackets: converted, nothing to map; a comment line first
    path = tmp_path / "flight.csv"
    path.write_text("# exported by a logger\ntime,alpha [deg],V (kt),q [deg/s],OAT [degC]\n"
                    "0.0,2.0,100,0.5,15\n0.1,2.5,101,1.0,15\n0.2,3.0,102,-0.5,15\n")
    rec = read_delimited(path)
    np.testing.assert_allclose(rec["alpha"], np.array([2.0, 2.5, 3.0]) * DEG)
    np.testing.assert_allclose(rec["V"], np.array([100, 101, 102]) * KT)
    np.testing.assert_allclose(rec["q"], np.array([0.5, 1.0, -0.5]) * DEG)
    assert rec.unit("OAT") == "degC" and list(rec["OAT"]) == [15.0] * 3
    assert rec.meta.extra["import"]["kept"] == ["OAT"]


# -- the methods on the imported record: agreement and nuisance biases ---------------------


def _identify_json(path, *args: str) -> dict:
    result = CliRunner().invoke(app, ["identify", str(path), "--window", WINDOW,
                                      "--format", "json", *args])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_the_methods_disagreement_is_said_with_its_reasons(imported):
    """Output error (short-period model) against equation error and frequency-domain
    output error on the imported file, over the card's window. Measured: oe and ee differ
    on CL_de by -4.3 sigma of the difference (ee estimates CL_q, oe holds it at zero), oe
    and fdoe on CL_de and Cm_de (-4.2, -3.1; fdoe did not converge), ee and fdoe on every
    derivative (13.8-40.8). Each reason must be named; with CL_q estimated by both, oe and
    ee agree, so the model structure is the reason they differ."""
    out = _identify_json(imported[1], "--compare", "ee", "--compare", "fdoe")
    agreement = out["agreement"]
    assert agreement["verdict"] == "disagree"
    pairs = {(c["parameter"], *c["methods"]): c for c in agreement["comparisons"]}
    assert not pairs[("CL_de", "oe", "ee")]["agree"]
    for name in ("Cm_alpha", "Cm_q", "Cm_de"):  # measured: 0.3, 2.1, 0.1 sigma
        assert pairs[(name, "oe", "ee")]["agree"], name
    reasons = " | ".join(agreement["reasons"])
    assert "fdoe did not converge" in reasons
    assert "CL_q estimated by ee, held by oe" in reasons
    assert "measured states as exact regressors" in reasons
    same = _identify_json(imported[1], "--model", "short_period", "--option",
                          "derivatives=CL_alpha,CL_q,CL_de,Cm_alpha,Cm_q,Cm_de",
                          "--compare", "ee")
    assert same["agreement"]["verdict"] == "agree"


def test_nuisance_biases_are_split_and_a_wrong_accelerometer_is_flagged(flight, imported,
                                                                      tmp_path):
    """The longitudinal model's az bias on the imported file is the trim's lift and
    gravity (the model takes absolute states): measured 15.35 m/s^2, of it 15.32 the trim,
    0.037 left, under the 0.2 g an accelerometer can have. Mapping the file's load factor
    NZ (g, positive up) to az instead of AZCG flips az's sign: the unit check passes it,
    the fit absorbs it in the bias, and the excess is 2 g cos(theta) (measured 19.4 m/s^2):
    flagged."""
    est = _identify_json(imported[1], "--model", "longitudinal")
    az = next(t for t in est["fit"]["biases"] if t["name"] == "bias_az")
    assert abs(az["value"]) > G0  # the fitted bias alone looks like more than 1 g
    assert abs(az["excess"]) < 0.2 * G0 and not az["implausible"]
    # the mapping error: NZ (in g, up) mapped to az, AZCG kept under its own name
    data, mapping, out = tmp_path / "f.asc", tmp_path / "map.toml", tmp_path / "f.parquet"
    write_dlr(flight, data)
    entries = ['T = "time"', 'NZ = "az"',
               *(f'{c} = "{ch}"' for c, _, ch, _ in COLUMNS if ch != "az")]
    mapping.write_text("[columns]\n" + "\n".join(entries) + "\n")
    result = CliRunner().invoke(app, ["import", str(data), "-o", str(out), "--mapping",
                                      str(mapping), "--aircraft", "twinotter"])
    assert result.exit_code == 0, result.output  # the unit check cannot see a sign
    result = CliRunner().invoke(app, ["identify", str(out), "--window", WINDOW, "--model",
                                      "longitudinal"])
    assert result.exit_code == 0, result.output
    assert "bias_az" in result.output and "beyond any instrument" in result.output
    flipped = next(t for t in _identify_json(out, "--model", "longitudinal")["fit"]["biases"]
                   if t["name"] == "bias_az")
    theta = np.mean(flight.measured.slice(1.0, 11.5)["theta"])
    assert flipped["implausible"]
    assert flipped["excess"] == pytest.approx(2 * G0 * np.cos(theta), rel=0.05)


def test_an_unknown_method_to_compare_is_refused_naming_the_valid_ones(imported):
    result = CliRunner().invoke(app, ["identify", str(imported[1]), "--compare", "magic"])
    assert result.exit_code == 2
    assert "--compare 'magic' is not accepted; use one of ee, swr, oe" in result.output
    assert "Traceback" not in result.output
