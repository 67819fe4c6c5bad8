"""Broken JSBSim aircraft files and malformed flight cards: exit 2 naming the file and the
problem (line and field for cards), never a traceback or an internal error."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from flightid.sim.jsbsim.model import load

GOOD = """name = "ok"
duration = 10.0
aircraft = "navion"
rate = 50.0

[condition]
altitude = 300.0
speed = 50.0
"""


@pytest.fixture(scope="module")
def navion_folder(tmp_path_factory) -> Path:
    """A copy of the Navion's JSBSim folder, whose XML the tests then break."""
    source = Path(load("navion").xml_path).parent
    target = tmp_path_factory.mktemp("aircraft") / "navion"
    shutil.copytree(source, target)
    return target


def broken_aircraft(folder: Path, how: str) -> Path:
    xml = folder / "navion.xml"
    text = xml.read_text()
    if how == "no aerodynamics":
        text = re.sub(r"<aerodynamics>.*</aerodynamics>", "", text, flags=re.S)
    elif how == "empty aerodynamics":
        text = re.sub(r"<aerodynamics>.*</aerodynamics>", "<aerodynamics/>", text,
                      flags=re.S)
    elif how == "truncated":
        text = text[: len(text) // 2]
    elif how == "not jsbsim":
        text = "<?xml version='1.0'?><html><body/></html>"
    out = folder.parent / how.replace(" ", "_")
    shutil.copytree(folder, out, dirs_exist_ok=True)
    (out / "navion.xml").unlink()
    path = out / f"{out.name}.xml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("how, expected", [
    ("no aerodynamics", "no <aerodynamics> section"),
    ("empty aerodynamics", "no <aerodynamics> section"),
    ("truncated", "not a well-formed JSBSim XML file"),
    ("not jsbsim", "expected <fdm_config>"),
])
@pytest.mark.parametrize("command", ["trim", "truth"])
def test_broken_aircraft_xml(cli, navion_folder, how, expected, command):
    path = broken_aircraft(navion_folder, how)
    cli([command, path, "--altitude", "300", "--speed", "50"], 2, str(path), expected)


def test_missing_aircraft_file(cli, tmp_path):
    cli(["trim", tmp_path / "none.xml", "--altitude", "300", "--speed", "50"], 2,
        "no such aircraft file")


@pytest.mark.parametrize("edit, expected", [
    (lambda t: t.replace("duration = 10.0", "duration = -10.0"), "duration"),
    (lambda t: t.replace("duration = 10.0", "duration = \"long\""), "duration"),
    (lambda t: t.replace('aircraft = "navion"', 'aircraft = "nosuch"'), "nosuch"),
    (lambda t: t + "\nwingspan = 3\n", "wingspan"),
    (lambda t: t.replace("[condition]", "[condition"), "ok.toml"),  # TOML syntax
    (lambda t: t.replace("speed = 50.0", ""), "speed"),
    (lambda t: t + '\n[[maneuver]]\nkind = "wobble"\nsurface = "de"\nstart = 1.0\n', "wobble"),
    (lambda t: t + '\n[[maneuver]]\nkind = "doublet"\nsurface = "de"\nstart = 9.0\n'
                   'base = 1.0\namplitude_deg = 2.0\n', "beyond the flight's duration"),
])
def test_malformed_card(cli, tmp_path, existing, edit, expected):
    card = tmp_path / "ok.toml"
    card.write_text(edit(GOOD))
    cli(["simulate", card, "-o", existing], 2, expected, protect=[existing])


def test_card_not_utf8(cli, tmp_path):
    card = tmp_path / "latin.toml"
    card.write_bytes(GOOD.replace("ok", "\xe9t\xe9").encode("latin-1"))
    cli(["simulate", card, "-o", tmp_path / "x.parquet"], 2, "UTF-8")


def test_card_naming_an_xml_path(cli, navion_folder, tmp_path):
    # cards name project or JSBSim aircraft, not files: refused at the card's line
    path = broken_aircraft(navion_folder, "no aerodynamics")
    card = tmp_path / "card.toml"
    card.write_text(GOOD.replace('"navion"', f'"{path}"'))
    cli(["simulate", card, "-o", tmp_path / "x.parquet"], 2, "card.toml:3",
        "unknown aircraft")
