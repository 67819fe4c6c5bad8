"""Loading aircraft: project folder, jsbsim package, XML path; clear errors for unknown names."""

from __future__ import annotations

from pathlib import Path

import pytest

from flightid import aircraft
from flightid.sim.jsbsim.model import UnknownAircraftError, available, load
from flightid.units import FT

LINEAR = Path(__file__).parents[1] / "aircraft" / "linear_test" / "linear_test.xml"


def test_loads_jsbsim_aircraft_with_reference_geometry_in_si():
    m = load("c172p")
    assert m.origin == "jsbsim"
    # c172p.xml: wingarea 174 ft^2, wingspan 35.8 ft, chord 4.9 ft
    assert m.reference.area == pytest.approx(174.0 * FT**2)
    assert m.reference.span == pytest.approx(35.8 * FT)
    assert m.reference.chord == pytest.approx(4.9 * FT)
    assert m.propeller and m.n_engines == 1 and m.uses_alphadot


def test_loads_xml_path_with_package_engines():
    m = load(str(LINEAR))
    assert m.origin == "file" and m.name == "linear_test"
    assert m.n_engines == 1  # eng_io320 comes from the jsbsim package's engine folder
    assert m.uses_alphadot


@pytest.mark.parametrize("name", aircraft.names())
def test_every_project_aircraft_loads(name):
    m = load(name)
    assert m.origin == "project"
    assert m.reference.area > 0 and m.reference.span > 0 and m.reference.chord > 0


def test_unknown_aircraft_names_what_is_available():
    with pytest.raises(UnknownAircraftError) as err:
        load("no-such-plane")
    text = str(err.value)
    assert "no-such-plane" in text and "c172p" in text and "DHC6" in text
    assert isinstance(err.value, ValueError)
    assert "DHC6" in available()["jsbsim"]


def test_missing_xml_path_is_named():
    with pytest.raises(UnknownAircraftError, match="does not exist"):
        load("/nonexistent/foo/foo.xml")


def test_project_path_helper_names_missing_aircraft():
    with pytest.raises(FileNotFoundError, match="no project aircraft 'nope'"):
        aircraft.path("nope")


def test_reload_gives_a_fresh_exec():
    m = load("c172p")
    old = m.fdm
    m.reload()
    assert m.fdm is not old and m.get("metrics/Sw-sqft") == pytest.approx(174.0)
