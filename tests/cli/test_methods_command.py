"""``flightid methods``: every registered method with each option's type, default, meaning."""

from __future__ import annotations

import dataclasses
import json

from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.identification.methods import registry


def test_json_lists_every_method_and_option():
    result = CliRunner().invoke(app, ["methods", "--format", "json"])
    assert result.exit_code == 0, result.output
    listed = json.loads(result.output)
    assert set(listed) == set(registry.methods())
    for method_id, entry in listed.items():
        spec = registry.get(method_id)
        names = [o["name"] for o in entry["options"]]
        assert names == [f.name for f in spec.option_fields()]
        assert set(names) == {f.name for f in dataclasses.fields(spec.options)}
        assert all(o["help"] and o["type"] for o in entry["options"])
        assert entry["default_model"] in entry["models"]


def test_table_of_one_method_shows_types_unmangled():
    result = CliRunner().invoke(app, ["methods", "oe"], env={"COLUMNS": "160"})
    assert result.exit_code == 0, result.output
    assert "oe: output error" in result.output
    assert "list[str] | None" in result.output and "initial_state" in result.output


def test_unknown_method_is_named():
    result = CliRunner().invoke(app, ["methods", "magic"])
    assert result.exit_code != 0
    assert "unknown method 'magic'" in str(result.exception) + result.output
