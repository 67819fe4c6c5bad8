"""Confident numbers from data that cannot support them are refused: channels in the wrong
unit (named with the likely cause), flights without inputs and pure noise (every method
refuses with the reason), and a clipped input is recorded and warned about."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.data.unit_sanity import implausible
from flightid.identification.methods import registry
from flightid.record import FlightRecord, read
from flightid.units import DEG, KT

CLIPPED = """name = "clipped"
duration = 6.0
aircraft = "navion"
rate = 50.0
seed = 1

[condition]
altitude = 300.0
speed = 50.0

[[maneuver]]
kind = "doublet"
surface = "dr"
start = 1.0
base = 0.5
amplitude_deg = 200.0
"""


@pytest.mark.parametrize("channels, scale, expected", [
    (("alpha", "beta"), 1 / DEG, "alpha reaches"),  # the degrees-as-rad record
    (("da", "dr"), 1 / DEG, "da looks like degrees"),
    (("p", "q", "r"), 1 / DEG, "p looks like deg/s"),
    (("V",), 1 / KT, "V looks like knots"),  # V in knots, qbar in SI, no rho channel
    (("V",), 10.0, "beyond 350 m/s"),
])
def test_implausible_units(cli, flight, tmp_path, channels, scale, expected):
    bad = flight.with_channels(**{c: flight[c] * scale for c in channels})
    path = bad.write(tmp_path / "units.parquet")
    cli(["identify", path, "--method", "ee"], 2, "units look wrong", expected)


def test_plausible_units_pass(flight):
    assert implausible(flight) == []


METHODS = sorted(registry.methods())


@pytest.fixture(scope="module")
def noise(quiet) -> FlightRecord:
    """The quiet flight with every input and response replaced by white noise (the
    accelerometers keep gravity, the trim specific force, under their noise: the unit
    check refuses a record without it)."""
    rng = np.random.default_rng(11)
    names = ("de", "da", "dr", "alpha", "beta", "p", "q", "r", "phi", "theta")
    forces = {c: np.median(quiet[c]) + rng.normal(0, 0.01, len(quiet))
              for c in ("ax", "ay", "az")}
    return quiet.with_channels(**{c: rng.normal(0, 0.01, len(quiet)) for c in names},
                               **forces)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("case", ["quiet", "noise"])
def test_every_method_refuses_without_excitation(cli, request, tmp_path, case, method):
    record = request.getfixturevalue(case)
    path = record.write(tmp_path / f"{case}.parquet")
    reason = "is constant" if case == "quiet" else "noise only"
    cli(["identify", path, "--method", method], 2, "no input is excited", reason)


def test_fdee_runs_on_a_simulated_record(cli, flight_file):
    # the "no channel 'CY'": fdee works on the project's own records
    result = cli(["identify", flight_file, "--method", "fdee", "--format", "json"], 0)
    assert '"Cn_dr"' in result.output


def test_clipped_input_is_recorded_and_warned(cli, tmp_path):
    card = tmp_path / "clipped.toml"
    card.write_text(CLIPPED)
    out = tmp_path / "clipped.parquet"
    cli(["simulate", card, "-o", out], 0, "warning", "dr was commanded 3.49 rad",
        "clipped at its travel limit")
    clipped = read(out).meta.extra["clipped"]["dr"]
    assert clipped["commanded_rad"] == pytest.approx(200 * DEG)
    # the Navion's rudder travels 25 deg (aircraft/navion/navion.xml)
    assert clipped["flown_rad"] == pytest.approx(25 * DEG, rel=0.02)
