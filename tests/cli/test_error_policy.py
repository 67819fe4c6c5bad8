"""The command line's one error policy (docs/errors.md) and atomic file writes.

Exit 0 success, 1 internal error, 2 bad input or usage, 3 physical failure; one line on
stderr and never a traceback unless --debug (or FLIGHTID_DEBUG=1).
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from flightid.cli.app import app, classify, main
from flightid.files import atomic_path, atomic_write, write_text
from flightid.record import FlightRecord, RecordMeta, read
from flightid.scenarios.cards import CardError
from flightid.sim.flight.simulation import DepartureError
from flightid.sim.jsbsim.trim import TrimError
from tests.conftest import TWIN_OTTER


def run(*args, cwd=None, env=None):
    return subprocess.run([sys.executable, "-m", "flightid.cli.app", *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=cwd,
                          env={**os.environ, **(env or {})})


def assert_one_line(out, code, *expected):
    assert out.returncode == code, (out.stdout, out.stderr)
    assert "Traceback" not in out.stderr
    for text in expected:
        assert text in out.stderr, out.stderr


def small_record(value: float = 1.0) -> FlightRecord:
    t = np.arange(5) * 0.1
    return FlightRecord(t, {"q": np.full(5, value)}, RecordMeta(aircraft="test"))


# -- exit 2: bad input or usage -----------------------------------------------------------

def test_missing_file_is_exit_2(tmp_path):
    assert_one_line(run("identify", tmp_path / "nope.parquet"), 2,
                    "flightid identify:", "nope.parquet: no such file")


def test_unknown_option_is_a_usage_error_exit_2():
    out = run("truth", "navion", "--altitude", "0", "--speed", "50", "--colour", "red")
    assert_one_line(out, 2, "--colour")


def test_bad_option_value_is_exit_2():
    out = run("truth", "navion", "--altitude", "0", "--speed", "50", "--format", "xml")
    assert_one_line(out, 2, "flightid truth: --format 'xml' is not accepted")


def test_malformed_card_names_file_line_and_field(tmp_path):
    card = tmp_path / "bad.toml"
    card.write_text('aircraft = "navion"\nduration = 5.0\n[condition]\naltitude = 0\n'
                    'speed = "fast"\n', encoding="utf-8")
    out = run("simulate", card, "-o", tmp_path / "x.parquet")
    assert_one_line(out, 2, "flightid simulate:", f"{card}:5", "condition.speed")
    assert not (tmp_path / "x.parquet").exists()


def test_trim_input_check_is_bad_input_not_physics():
    out = run("trim", "navion", "--altitude", "-5", "--speed", "50")
    assert_one_line(out, 2, "altitude must be >= 0 m")


def test_output_in_a_folder_that_is_a_file_is_exit_2(tmp_path):
    (tmp_path / "file.txt").write_text("x")
    target = tmp_path / "file.txt" / "out.parquet"
    out = run("convert", tmp_path / "missing.tlog", target)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    out = run("compatibility", TWIN_OTTER, "-o", target) if TWIN_OTTER.exists() else None
    if out is not None:
        assert_one_line(out, 2, f"cannot write {target}")
    assert (tmp_path / "file.txt").read_text() == "x"


def test_output_in_a_read_only_folder_is_exit_2(tmp_path):
    if not TWIN_OTTER.exists():
        pytest.skip("no Twin Otter record")
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("running as root: a 0o555 folder is still writable")
        out = run("compatibility", TWIN_OTTER, "-o", folder / "out.parquet")
        assert_one_line(out, 2, "cannot write", "permission denied")
    finally:
        folder.chmod(0o755)


def test_unwritable_output_raises_a_clear_oserror(tmp_path):
    (tmp_path / "file.txt").write_text("x")
    with pytest.raises(NotADirectoryError, match="cannot write .*out.csv"):
        small_record().write(tmp_path / "file.txt" / "out.csv")
    with pytest.raises(FileNotFoundError, match="cannot write .*: no such folder"):
        write_text(tmp_path / "no" / "such" / "r.html", "<html>")
    with pytest.raises(IsADirectoryError, match="cannot write"):
        (tmp_path / "d.csv").mkdir()
        small_record().write(tmp_path / "d.csv")  # a folder where the file should go
    code, message = classify(PermissionError(f"cannot write {tmp_path}/x: permission denied"))
    assert code == 2 and message.endswith("permission denied")


# -- exit 3: physical failure -------------------------------------------------------------

def test_trim_failure_is_exit_3():
    out = run("truth", "navion", "--altitude", "0", "--speed", "5")
    assert_one_line(out, 3, "flightid truth:", "below stall")


def test_departure_is_exit_3_and_keeps_an_existing_output(tmp_path, departing_card):
    target = tmp_path / "out.parquet"
    small_record(7.0).write(target)
    before = target.read_bytes()
    out = run("simulate", departing_card, "-o", target)
    assert_one_line(out, 3, "flightid simulate: the flight departed: departure at t =")
    assert target.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["departs.toml", "out.parquet"]


def test_physical_errors_classify_as_3_before_their_value_error_base():
    assert issubclass(TrimError, ValueError)  # so the order of the checks matters
    assert classify(TrimError("cannot trim: not enough power"))[0] == 3
    assert classify(DepartureError("alpha left the range", 1.0))[0] == 3
    assert classify(TimeoutError("no ground station answered on udp"))[0] == 3
    assert classify(CardError("card.toml", 3, "condition.speed", "expected a number"))[0] == 2


# -- exit 1: internal error, and --debug ----------------------------------------------------

@pytest.fixture
def failing_command():
    """A command registered on the app for one test only: raises what it is told."""
    raised: list[BaseException] = []

    def boom() -> None:
        raise raised[0]

    app.command("boom")(boom)
    info = app.registered_commands[-1]
    yield raised
    app.registered_commands.remove(info)


def test_internal_error_is_one_line_exit_1(failing_command, monkeypatch, capsys):
    failing_command.append(RuntimeError("the cache is inconsistent"))
    monkeypatch.setattr(sys, "argv", ["flightid", "boom"])
    monkeypatch.delenv("FLIGHTID_DEBUG", raising=False)
    with pytest.raises(SystemExit) as exit_:
        main()
    assert exit_.value.code == 1
    err = capsys.readouterr().err
    assert err.strip() == ("flightid boom: internal error: RuntimeError: the cache is "
                           "inconsistent; run with --debug for the traceback")


def test_linalg_error_is_internal_not_bad_input(failing_command):
    failing_command.append(np.linalg.LinAlgError("Singular matrix"))
    result = CliRunner().invoke(app, ["boom"], env={"FLIGHTID_DEBUG": ""})
    assert result.exit_code == 1, result.output
    assert "internal error: LinAlgError: Singular matrix" in result.output
    assert classify(ValueError("output error: singular information matrix"))[0] == 2


def test_debug_reraises_in_process(failing_command, monkeypatch):
    failing_command.append(RuntimeError("boom"))
    monkeypatch.setattr(sys, "argv", ["flightid", "boom", "--debug"])  # anywhere on the line
    with pytest.raises(RuntimeError, match="boom"):
        main()
    result = CliRunner().invoke(app, ["boom"], env={"FLIGHTID_DEBUG": "1"})
    assert isinstance(result.exception, RuntimeError)


def test_debug_shows_the_traceback():
    out = run("--debug", "truth", "navion", "--altitude", "0", "--speed", "5")
    assert out.returncode == 1 and "Traceback" in out.stderr and "TrimError" in out.stderr
    out = run("truth", "navion", "--altitude", "0", "--speed", "5",
              env={"FLIGHTID_DEBUG": "1"})
    assert out.returncode == 1 and "Traceback" in out.stderr


def test_success_is_exit_0():
    out = run("version")
    assert out.returncode == 0 and out.stdout.strip() and not out.stderr


# -- atomic writes -----------------------------------------------------------------------

def test_failed_write_leaves_an_existing_file_and_no_temporary(tmp_path):
    target = tmp_path / "report.html"
    target.write_text("old")

    def half_then_fail(tmp):
        tmp.write_text("half")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        atomic_write(target, half_then_fail)
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["report.html"]


def test_atomic_write_replaces_and_keeps_the_mode(tmp_path):
    target = tmp_path / "r.csv"
    target.write_text("old")
    target.chmod(0o640)
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".csv"
        tmp.write_text("new")
    assert target.read_text() == "new" and (target.stat().st_mode & 0o777) == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["r.csv"]


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_record_write_round_trips_through_the_helper(tmp_path, suffix):
    path = small_record(3.0).write(tmp_path / f"r{suffix}")
    assert path == tmp_path / f"r{suffix}"
    assert np.array_equal(read(path)["q"], np.full(5, 3.0))
    assert [p.name for p in tmp_path.iterdir()] == [f"r{suffix}"]


def test_typer_exit_codes_pass_through(failing_command):
    failing_command.append(typer.Exit(4))
    assert CliRunner().invoke(app, ["boom"]).exit_code == 4
