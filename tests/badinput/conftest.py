"""Shared pieces of the bad-input suite: one short simulated flight (flown once per
session), a quiet flight without inputs, and ``cli``: run a command in-process and check
the error policy (exit code, a message naming the problem, no traceback, protected files
untouched)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.record import FlightRecord
from flightid.scenarios.cards import fly_card, load_card

# 10 s of the Navion with an elevator, an aileron and a rudder doublet: enough for every
# reader and argument check, short enough to fly in about a second
SHORT_CARD = """name = "short"
duration = 10.0
aircraft = "navion"
rate = 50.0
seed = 3

[condition]
altitude = 300.0
speed = 50.0

[[maneuver]]
kind = "doublet"
surface = "de"
start = 1.0
base = 0.5
amplitude_deg = 2.0

[[maneuver]]
kind = "doublet"
surface = "da"
start = 3.5
base = 0.5
amplitude_deg = 3.0

[[maneuver]]
kind = "doublet"
surface = "dr"
start = 6.0
base = 0.5
amplitude_deg = 3.0
"""


@pytest.fixture(scope="session")
def card_path(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("cards") / "short.toml"
    path.write_text(SHORT_CARD)
    return path


@pytest.fixture(scope="session")
def flight(card_path) -> FlightRecord:
    """The short card flown once (measured = truth: the card has no sensors)."""
    measured, _ = fly_card(load_card(str(card_path)))
    return measured


@pytest.fixture(scope="session")
def quiet(card_path) -> FlightRecord:
    """The short card flown without its maneuvers: no surface input at all."""
    card = dataclasses.replace(load_card(str(card_path)), maneuvers=())
    measured, _ = fly_card(card)
    return measured


@pytest.fixture(scope="session")
def flight_file(flight, tmp_path_factory) -> Path:
    return flight.write(tmp_path_factory.mktemp("records") / "flight.parquet")


@pytest.fixture
def existing(tmp_path) -> Path:
    """An output file that is already there and must survive every failure."""
    path = tmp_path / "existing.parquet"
    path.write_bytes(b"precious content")
    return path


@pytest.fixture
def cli() -> Callable[..., object]:
    """``cli(args, code, *expected, protect=())``: invoke and check the error policy."""

    def run(args: Sequence[object], code: int, *expected: str,
            protect: Sequence[Path] = ()) -> object:
        before = {p: p.read_bytes() for p in protect}
        result = CliRunner().invoke(app, [str(a) for a in args])
        out = result.output
        assert result.exit_code == code, out
        assert "Traceback" not in out
        if code:
            assert isinstance(result.exception, SystemExit), repr(result.exception)
        for text in expected:
            assert text.lower() in out.lower(), out
        for path, content in before.items():
            assert path.read_bytes() == content, f"{path} was changed"
        return result

    return run
