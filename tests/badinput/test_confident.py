"""Nothing confidently wrong (issue 38): units judged from the record itself, in every
command that reads one; non-convergence visible; jittered time re-gridded and gaps
refused by every method; a memory guard before the work; the listed defects."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from flightid.identification.compatibility.reconstruction import reconstruct
from flightid.identification.data import time_base
from flightid.identification.data.unit_sanity import implausible, unit_ratios
from flightid.identification.engine import resources
from flightid.identification.engine.convergence import NotConvergedWarning
from flightid.identification.methods import registry
from flightid.record import FlightRecord, read
from flightid.scenarios.cards import fly_card, library_cards, load_card
from flightid.sim.bridge.air.serve import BridgeConfig
from flightid.sim.bridge.loopback import record_bridged
from flightid.sim.flight.disturbed import disturbance_from_dict
from flightid.units import DEG, FT, G0, KT, PSF, SLUG
from tests.conftest import TWIN_OTTER

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


@pytest.fixture(scope="module")
def twin_otter() -> FlightRecord:
    return read(TWIN_OTTER)


@pytest.fixture(scope="module")
def sensed(flight) -> FlightRecord:
    """The short flight without its rho channel, as a sensor suite records it."""
    return FlightRecord(flight.time, {k: v for k, v in flight.channels.items() if k != "rho"},
                        flight.meta)


# -- units ----------------------------------------------------------------------------------

def test_ratios_are_one_in_si_units(sensed, twin_otter):
    sim, real = unit_ratios(sensed), unit_ratios(twin_otter)
    # JSBSim's atmosphere is the ISA the check assumes without a rho channel
    assert sim["airspeed_qbar"].value == pytest.approx(1.0, abs=0.01)
    assert "ISA at h" in sim["airspeed_qbar"].formula
    # the Twin Otter carries rho; its V, qbar and rho are separate sensors
    assert real["airspeed_qbar"].value == pytest.approx(1.0, abs=0.02)
    assert real["airspeed_uvw"].value == pytest.approx(1.0, abs=0.01)
    # doublets of a few degrees: the median specific force stays within 5 % of 1 g
    for ratios in (sim, real):
        assert ratios["gravity"].value == pytest.approx(1.0, abs=0.05)
        assert ratios["euler_rates"].value == pytest.approx(1.0, abs=0.03)
        assert 0.2 < ratios["lift_coefficient"].value < 1.5
        assert 0.03 < ratios["gyration"].value < 0.12
    assert implausible(sensed) == [] and implausible(twin_otter) == []


def _scaled(record: FlightRecord, channels: tuple[str, ...], factor: float) -> FlightRecord:
    return record.with_channels(**{c: record[c] * factor for c in channels})


@pytest.mark.parametrize("channels, factor, ratio, expected, message", [
    (("V",), 1 / KT, "airspeed_qbar", (1 / KT) ** 2, "V looks like knots"),  # 1.944^2
    (("V",), 1 / FT, "airspeed_qbar", (1 / FT) ** 2, "V looks like ft/s"),
    (("qbar",), 1 / PSF, "airspeed_qbar", PSF, "qbar looks like lbf/ft^2"),
    (("ax", "ay", "az"), 1 / G0, "gravity", 1 / G0, "ax, ay, az look like g"),
    (("p", "q", "r"), 1 / DEG, "euler_rates", DEG, "p looks like deg/s"),
    (("mass",), 1 / SLUG, "lift_coefficient", 1 / SLUG, "mass looks like slugs"),
])
@pytest.mark.parametrize("which", ["sensed", "twin_otter"])
def test_a_wrong_unit_moves_its_ratio_by_the_unit_factor(request, which, channels, factor,
                                                         ratio, expected, message):
    record = request.getfixturevalue(which)
    bad = _scaled(record, channels, factor)
    assert unit_ratios(bad)[ratio].value == pytest.approx(
        expected * unit_ratios(record)[ratio].value, rel=1e-9)
    assert any(message in p for p in implausible(bad)), implausible(bad)


def test_small_angles_in_degrees_are_found(twin_otter):
    # alpha of the Twin Otter is 0.2 deg at trim, under 6 deg through the maneuver: within
    # any limit in rad, but not theta - gamma
    bad = _scaled(twin_otter, ("alpha",), 1 / DEG)
    assert any("alpha looks like degrees" in p for p in implausible(bad))


@pytest.fixture(scope="module")
def knots_file(sensed, tmp_path_factory):
    return _scaled(sensed, ("V",), 1 / KT).write(
        tmp_path_factory.mktemp("units") / "knots.parquet")


@pytest.mark.parametrize("args", [
    ["identify", "{}", "--method", "ee"],
    ["identify", "{}", "--method", "oe"],
    ["compatibility", "{}"],
    ["frequency-response", "{}", "--input", "de", "--output", "q"],
    ["gap", "{}", "--model", "navion"],
])
def test_every_command_that_reads_a_record_checks_its_units(cli, knots_file, args):
    cli([str(knots_file) if a == "{}" else a for a in args], 2, "units look wrong",
        "V looks like knots", "0.5 rho V^2 / qbar (rho of the ISA at h) = 3.78")


def test_gap_refuses_a_record_in_degrees(cli, sensed, tmp_path):
    # the issue's gap run named effects with 100 % shrink on such a record
    angles = ("alpha", "beta", "phi", "theta", "p", "q", "r", "de", "da", "dr")
    path = _scaled(sensed, angles, 1 / DEG).write(tmp_path / "degrees.parquet")
    cli(["gap", path, "--model", "navion"], 2, "units look wrong for gap",
        "alpha looks like degrees")


def test_library_flights_pass_the_unit_check():
    """One seed of every library card in light turbulence (the benchmark flies 3 seeds in
    calm air and turbulence, and the Twin Otter: 97 records, none flagged)."""
    light = (disturbance_from_dict({"kind": "turbulence", "intensity": "light"}),)
    flagged = {}
    for name, path in sorted(library_cards().items()):
        card = dataclasses.replace(load_card(path), disturbances=light)
        measured, _ = fly_card(card, seed=2)
        if implausible(measured):
            flagged[name] = implausible(measured)
    assert flagged == {}
    assert len(library_cards()) >= 16


# -- convergence ----------------------------------------------------------------------------

@pytest.mark.parametrize("method, option", [
    ("oe", "max_iterations=1"), ("fem", "max_iterations=1"),
    ("oe6dof", "max_iterations=1"), ("fdoe", "max_relaxations=1"),
])
def test_not_converged_is_in_the_verdict_and_strict_exits_4(cli, flight_file, method,
                                                            option):
    args = ["identify", flight_file, "--method", method, "--option", option]
    result = cli(args, 0, "warning: method", "not converged")
    verdict = [line for line in result.output.splitlines() if "within" in line]
    assert verdict and "not converged" in verdict[0]
    cli([*args, "--strict"], 4, "not converged")
    data = json.loads(cli([*args, "--format", "json"], 0).stdout)
    assert data["fit"]["converged"] is False


def test_converged_fit_has_no_warning(cli, flight_file):
    result = cli(["identify", flight_file, "--method", "oe", "--strict"], 0)
    assert "not converged" not in result.output


def test_compatibility_warns_when_not_converged(twin_otter):
    with pytest.warns(NotConvergedWarning, match="compatibility: not converged"):
        _, est = reconstruct(twin_otter, max_iterations=1)
    assert est.fit["converged"] is False


@pytest.mark.parametrize("method, option", [
    ("fem", "max_iterations=-1"), ("oe", "max_iterations=0"), ("oe6dof", "max_iterations=0"),
    ("fem", "max_relaxations=0"), ("fdoe", "max_relaxations=-2"),
])
def test_iteration_limits_below_one_are_refused(cli, flight_file, method, option):
    name, value = option.split("=")
    cli(["identify", flight_file, "--method", method, "--option", option], 2,
        f"option {name} of method {method} must be >= 1, got {value}")


# -- time bases -----------------------------------------------------------------------------

def _jittered(record: FlightRecord, fraction: float, seed: int = 5) -> FlightRecord:
    """Times with an ASCII export's rounding: each off its grid point by up to
    ``fraction`` of the step, written with 5 decimals."""
    rng = np.random.default_rng(seed)
    dt = record.time[1] - record.time[0]
    t = np.round(record.time + rng.uniform(-fraction, fraction, len(record)) * dt / 2, 5)
    return FlightRecord(t, record.channels, record.meta)


def test_jitter_below_one_percent_is_regridded(cli, flight, tmp_path):
    jittered = _jittered(flight, 0.008)
    assert 0.001 < time_base.jitter(jittered) < 0.01
    with pytest.warns(time_base.RegriddedWarning, match="re-gridded to a uniform 0.02 s"):
        regridded = time_base.regrid_jitter(jittered)
    assert regridded.uniform_step("test") == pytest.approx(0.02, rel=1e-5)
    assert np.allclose(regridded.time, flight.time, atol=1e-4 * 0.02)
    path = jittered.write(tmp_path / "jitter.parquet")
    plain = flight.write(tmp_path / "plain.parquet")
    jit = json.loads(cli(["identify", path, "--method", "ee", "--format", "json"], 0).stdout)
    ref = json.loads(cli(["identify", plain, "--method", "ee", "--format", "json"], 0).stdout)
    # linear interpolation over a 0.4 % time error: on this noiseless flight the estimates
    # move by under 1e-5 (about 1e-4 of a derivative) or a hundredth of their std
    assert jit["estimates"].keys() == ref["estimates"].keys()
    for name, e in ref["estimates"].items():
        moved = abs(jit["estimates"][name]["value"] - e["value"])
        assert moved < max(0.01 * e["std"], 1e-5), name
    cli(["identify", path, "--method", "oe"], 0, "warning: time steps jitter by up to",
        "re-gridded")


METHODS = sorted(registry.methods())


@pytest.mark.parametrize("method", METHODS)
def test_gaps_are_refused_by_every_method(cli, flight, tmp_path, method):
    keep = np.ones(len(flight), bool)
    keep[200:215] = False  # 0.3 s missing
    gapped = FlightRecord(flight.time[keep], {k: v[keep] for k, v in flight.channels.items()},
                          flight.meta)
    assert time_base.regrid_jitter(gapped) is gapped
    path = gapped.write(tmp_path / "gapped.parquet")
    cli(["identify", path, "--method", method], 2, "not uniformly sampled",
        "step 0.32 s at sample 199")


# -- resources ------------------------------------------------------------------------------

def _huge_record(path, samples: int):
    """A Parquet file that says it holds ``samples`` samples (one all-null column: its
    pages take a few bytes, so nothing large is written or allocated)."""
    pq.write_table(pa.table({"time": pa.nulls(samples)}), path)
    return path


@pytest.mark.parametrize("args, work", [
    (["identify", "{}", "--method", "ee"], "ee"),
    (["compatibility", "{}"], "compatibility"),
    (["frequency-response", "{}", "--input", "de", "--output", "q"], "frequency-response"),
])
def test_memory_guard_refuses_before_reading(cli, tmp_path, args, work):
    samples = int(3 * resources.available_bytes() / resources.BYTES_PER_SAMPLE[work])
    path = _huge_record(tmp_path / "huge.parquet", samples)
    need = resources.estimated_bytes(samples, work) / 1e9
    cli([str(path) if a == "{}" else a for a in args], 2, f"has {samples:,} samples",
        f"{work} would need about {need:.3g} GB", "--force")
    if work == "compatibility":  # the smallest file: --force skips the guard, and the
        # reader then finds that the file is not a record
        cli([*[str(path) if a == "{}" else a for a in args], "--force"], 2, "huge.parquet")


def test_memory_estimates_cover_the_issue_peaks():
    # the peaks the issue measured on a 10-million-sample record
    for work, peak in (("compatibility", 24e9), ("frequency-response", 21e9), ("ee", 13e9)):
        assert resources.estimated_bytes(10_000_000, work) >= peak


# -- listed defects -------------------------------------------------------------------------

def test_frequency_response_refuses_an_unexcited_input(cli, quiet, tmp_path):
    path = quiet.write(tmp_path / "quiet.parquet")
    cli(["frequency-response", path, "--input", "de", "--output", "q"], 2,
        "input de is not excited", "de is constant (peak to peak 0")


def test_nan_a_priori_is_refused_by_name(cli, flight_file):
    cli(["identify", flight_file, "--method", "oe", "--model", "lon", "--option",
         'a_priori={"CL_q": NaN}'], 2, "option a_priori: CL_q = nan is not a finite number")


@pytest.mark.parametrize("option, expected", [
    ("f_in=-4", "option f_in of method swr must be > 0"),
    ("f_out=0", "option f_out of method swr must be > 0"),
    ("f_out=9", "option f_out of method swr 9 must not exceed f_in 4"),
])
def test_swr_thresholds(cli, flight_file, option, expected):
    cli(["identify", flight_file, "--method", "swr", "--option", option], 2, expected)


THROTTLE = """name = "throttle"
duration = 8.0
aircraft = "navion"
rate = 50.0

[condition]
altitude = 300.0
speed = 50.0

[[maneuver]]
kind = "doublet"
surface = "throttle"
start = 1.0
base = 2.0
amplitude = {amplitude}
"""


def test_throttle_beyond_its_range_is_refused_or_warned(cli, tmp_path):
    card = tmp_path / "throttle.toml"
    card.write_text(THROTTLE.format(amplitude=5))
    cli(["simulate", card, "-o", tmp_path / "t.parquet"], 2, "maneuver[0].amplitude",
        "a throttle increment of 5 cannot be flown")
    # 0.5 from a trim near 0.6: the throttle stops at 1 (and at 0), clipped with a warning
    card.write_text(THROTTLE.format(amplitude=0.5))
    out = tmp_path / "t.parquet"
    cli(["simulate", card, "-o", out], 0, "warning", "throttle was commanded 0.5 (fraction)",
        "clipped")
    clipped = read(out).meta.extra["clipped"]["throttle"]
    trim_throttle = read(out).meta.condition["throttle"]
    assert clipped["flown_rad"] == pytest.approx(1 - trim_throttle, abs=0.01)


def test_convert_rate_giving_too_few_samples(cli, flight, tmp_path):
    tlog = tmp_path / "short.tlog"
    record_bridged(flight.slice(0.0, 3.0), tlog, BridgeConfig(baud=115200))
    cli(["convert", tlog, tmp_path / "out.parquet", "--rate", "0.01"], 2,
        "--rate", "0.01 Hz gives 1 sample(s)")


@pytest.mark.parametrize("command", ["trim", "truth"])
def test_absurd_speed_is_bad_input(cli, command):
    """Mach 1.2 for a propeller aircraft, and a speed no aircraft here flies: exit 2."""
    cli([command, "navion", "--altitude", "1000", "--speed", "400"], 2, "Mach",
        "absurd for a propeller aircraft")
    cli([command, "navion", "--altitude", "1000", "--speed", "1e6"], 2,
        "speed 1e+06 m/s is absurd")


@pytest.mark.parametrize("command", [["simulate", "navion-demo", "-o", "{out}"], ["demo"]])
def test_negative_seed_names_the_option(cli, tmp_path, command):
    args = [str(tmp_path / "o.parquet") if a == "{out}" else a for a in command]
    cli([*args, "--seed", "-1", *(["--report", tmp_path / "d.html"] if "demo" in args
                                  else [])], 2, "--seed must be 0..4294967295, got -1")
    assert not list(tmp_path.iterdir())


def test_fly_names_the_seed():
    with pytest.raises(ValueError, match="seed must be 0..4294967295"):
        fly_card(load_card("navion-doublets"), seed=-1)
