"""The effect contract (``flightid.testing.check_effect``'s checks) on every entry of
``flightid.sim.effects.catalogue.CATALOGUE``: a new effect is covered by being registered.
Also: the reserved places are empty, unknown names list the valid ones, the compatibility
parameters name catalogue entries, and docs/effects.md and ``flightid effects`` list them.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from flightid.cli.effects import effects_command
from flightid.identification.compatibility.reconstruction import CATALOGUE_EFFECTS
from flightid.sim.effects.catalogue import (
    CATALOGUE,
    RESERVED,
    SECTIONS,
    ActsOn,
    Entry,
)
from flightid.sim.effects.listing import listing, markdown_table
from flightid.testing import EFFECT_CHECKS, ContractFlight, contract_flight, run_effect_check

ENTRIES = list(CATALOGUE.values())
IDS = [e.name for e in ENTRIES]
DOCS = Path(__file__).resolve().parents[2] / "docs" / "effects.md"


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> ContractFlight:
    return contract_flight(tmp_path_factory.mktemp("augmented"))


def test_names_are_unique_and_reserved_places_are_empty():
    assert len(set(IDS)) == len(IDS)
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*", n) for n in IDS)
    assert not [e.name for e in ENTRIES if e.acts_on in RESERVED]
    # every place but the reserved ones has effects
    assert {e.acts_on for e in ENTRIES} == set(ActsOn) - RESERVED


@pytest.mark.parametrize("check", EFFECT_CHECKS)
@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
def test_effect_meets_the_contract(entry: Entry, check: str, request):
    flight = (request.getfixturevalue("flight")
              if check in ("default_changes", "zero_unchanged") else None)
    run_effect_check(check, entry, flight)


def test_unknown_names_list_the_valid_ones():
    for sec in SECTIONS.values():
        valid = [e.name for e in ENTRIES if e.acts_on in sec.acts_on]
        with pytest.raises(ValueError, match=f"unknown {sec.label} 'nope'; known: "
                           + re.escape(", ".join(valid))):
            CATALOGUE.lookup("nope", sec.name, "x")


# -- who else names effects ---------------------------------------------------------------------


def test_compatibility_parameters_name_catalogue_entries():
    assert {"bias_q", "scale_ax", "upwash_alpha", "vane_beta_x", "delay_V"} <= set(
        CATALOGUE_EFFECTS)
    for effect, parameter in CATALOGUE_EFFECTS.values():
        CATALOGUE[effect].parameter(parameter)  # raises naming what is missing


def test_docs_list_every_entry_and_are_current():
    text = DOCS.read_text(encoding="utf-8")
    for name in IDS:
        assert f"| `{name}` |" in text, f"docs/effects.md does not list {name}"
    assert markdown_table() in text, ("docs/effects.md is out of date: paste the output of "
                                      "`flightid effects --format markdown`")


def test_the_effects_command_prints_the_catalogue():
    app = typer.Typer()
    app.command()(effects_command)
    runner = CliRunner()
    out = runner.invoke(app, ["--format", "json"], env={"COLUMNS": "200"})
    assert out.exit_code == 0, out.output
    assert json.loads(out.output) == listing()
    table = runner.invoke(app, ["--acts-on", "link"], env={"COLUMNS": "200"})
    assert table.exit_code == 0 and "[ch]" in table.output
    assert all(e.name in table.output for e in CATALOGUE.acting_on(ActsOn.LINK))
    assert "noise" not in table.output
