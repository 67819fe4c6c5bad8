"""An output that cannot be written is refused before the work (exit 2, 'cannot write'
naming the path and the reason), and a failure never damages a file already there."""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture
def read_only(tmp_path) -> Path:
    """A folder nobody may write: a 0o555 folder, or /sys when running as root (root
    writes 0o555 folders; sysfs takes no new files even from root)."""
    if os.geteuid() == 0:
        return Path("/sys")
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    return folder


def outputs(tmp_path: Path, read_only: Path) -> dict[str, tuple[Path, str]]:
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    folder = tmp_path / "folder.parquet"
    folder.mkdir()
    return {"read-only folder": (read_only / "out.parquet", "permission denied"),
            "missing folder": (tmp_path / "no" / "out.parquet", "no such folder"),
            "path through a file": (a_file / "out.parquet", "not a folder"),
            "a folder": (folder, "it is a folder")}


@pytest.mark.parametrize("kind", ["read-only folder", "missing folder",
                                  "path through a file", "a folder"])
def test_simulate_refuses_before_flying(cli, card_path, tmp_path, read_only, kind):
    path, reason = outputs(tmp_path, read_only)[kind]
    cli(["simulate", card_path, "-o", path], 2, f"cannot write {path}", reason)


@pytest.mark.parametrize("kind", ["read-only folder", "missing folder"])
def test_compatibility_output(cli, flight_file, tmp_path, read_only, kind):
    path, reason = outputs(tmp_path, read_only)[kind]
    cli(["compatibility", flight_file, "-o", path.with_suffix(".csv")], 2, "cannot write",
        reason)


@pytest.mark.parametrize("command", [
    ["identify", "{flight}", "--report", "{out}/r.html"],
    ["frequency-response", "{flight}", "--input", "de", "--output", "q", "--plot",
     "{out}/bode.png"],
    ["demo", "--report", "{out}/demo.html"],
    ["simulate", "{card}", "-o", "{tmp}/ok.parquet", "--truth", "{out}/truth.parquet"],
])
def test_read_only_report_and_plot(cli, flight_file, card_path, tmp_path, read_only,
                                   command):
    args = [a.format(flight=flight_file, card=card_path, out=read_only, tmp=tmp_path)
            for a in command]
    cli(args, 2, f"cannot write {read_only}", "permission denied")
    assert not (tmp_path / "ok.parquet").exists()  # refused before anything was written


def test_departure_leaves_existing_output_intact(cli, tmp_path, existing, departing_card):
    cli(["simulate", departing_card, "-o", existing], 3, "the flight departed", protect=[existing])
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_bad_input_file_leaves_existing_output_intact(cli, tmp_path, existing):
    bad = tmp_path / "bad.parquet"
    bad.write_bytes(b"PAR1" + bytes(100))
    cli(["compatibility", bad, "-o", existing], 2, "not a readable Parquet record",
        protect=[existing])
