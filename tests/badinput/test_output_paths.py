"""No output over an input, no two outputs on one path, no file of another kind replaced
without --force, and every output checked before the work (issue 38, ``checks.check_paths``).

Real files throughout: each refused case asserts the input's bytes are unchanged.
"""

from __future__ import annotations

import os
import socket

import pytest

from flightid import files


@pytest.fixture
def rec(flight_file, tmp_path):
    path = tmp_path / "rec.parquet"
    path.write_bytes(flight_file.read_bytes())
    return path


def test_identify_report_over_its_record_is_refused(cli, rec):
    cli(["identify", rec, "--method", "ee", "--report", rec], 2,
        f"--report {rec} is the input RECORD", protect=[rec])


def test_a_hard_link_or_a_symlink_to_the_input_is_the_input(cli, rec, tmp_path):
    hard, soft = tmp_path / "hard.html", tmp_path / "soft.html"
    os.link(rec, hard)
    soft.symlink_to(rec)
    for out in (hard, soft):
        cli(["identify", rec, "--method", "ee", "--report", out], 2, "is the input RECORD",
            protect=[rec])


def test_gap_report_over_an_input_is_refused(cli, rec):
    cli(["gap", rec, "--model", "navion", "--report", rec], 2, "is the input RECORDS",
        protect=[rec])


def test_simulate_measured_and_truth_on_one_path_refused_before_flying(cli, card_path,
                                                                      tmp_path):
    out = tmp_path / "a.parquet"
    cli(["simulate", card_path, "-o", out, "--truth", out], 2, "are one file")
    assert not out.exists()


def test_demo_report_over_a_parquet_record_is_refused(cli, rec):
    cli(["demo", "--report", rec], 2, "the file there is a Parquet record",
        "would write an HTML page", "--force", protect=[rec])


def test_bridge_record_tlog_over_a_parquet_record_is_refused(cli, rec):
    cli(["bridge", "record", "-o", rec, "--udp", "127.0.0.1:1", "--first-timeout", "0.5"], 2,
        "a Parquet record", "a MAVLink tlog", protect=[rec])


def test_force_replaces_a_file_of_another_kind(cli, rec, tmp_path):
    plot = tmp_path / "bode.png"
    plot.write_text("<!doctype html><html></html>\n")
    cli(["frequency-response", rec, "--input", "de", "--output", "q", "--plot", plot], 2,
        "an HTML page", "a PNG image")
    cli(["frequency-response", rec, "--input", "de", "--output", "q", "--plot", plot,
         "--force"], 0)
    assert files.content_kind(plot) == "png"


def test_same_kind_is_replaced_without_force(cli, rec, tmp_path):
    out = tmp_path / "corrected.parquet"
    out.write_bytes(rec.read_bytes())
    cli(["compatibility", rec, "-o", out, "--format", "json"], 0)
    assert out.read_bytes() != rec.read_bytes()


def test_bridge_fly_and_serve_outputs_checked_before_the_flight(cli, rec, tmp_path):
    missing = tmp_path / "no" / "x.parquet"
    # a wrong output would have flown (and waited for a ground station) before: now exit 2
    # at once, with no trim
    cli(["bridge", "fly", "navion", "--altitude", "1000", "--speed", "50", "--udp",
         "127.0.0.1:1", "--timeout", "30", "--output", missing], 2, "cannot write", "no such")
    cli(["bridge", "serve", rec, "--udp", "127.0.0.1:1", "--report", tmp_path / "no" / "r.json"],
        2, "cannot write", "no such folder")


def test_port_in_use_is_named(cli, tmp_path):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        cli(["bridge", "record", "-o", tmp_path / "x.tlog", "--udp", f"127.0.0.1:{port}",
             "--first-timeout", "0.5"], 2, f"port {port} on 127.0.0.1 is in use")


@pytest.mark.parametrize(("data", "kind"), [
    (b"PAR1\x00\x00PAR1", "parquet"), (b"<!DOCTYPE html>\n<html>", "html"),
    (b"\x89PNG\r\n\x1a\n....", "png"), (b"# flightid-record {}\ntime,q\n0,1\n", "csv"),
    (b'{"a": 1}', "json"), (b"[condition]\nspeed = 5\n", None), (b"", "empty"),
    (b"\x00" * 8 + bytes([0xFD, 1, 0, 0, 0, 1, 1, 0, 0, 0]) + b"\x07" * 3
     + b"\x00" * 8 + bytes([0xFE, 0]), "tlog"),
])
def test_content_kind(tmp_path, data, kind):
    path = tmp_path / "f"
    path.write_bytes(data)
    assert files.content_kind(path) == kind
