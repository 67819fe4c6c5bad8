"""The bridge under bad input: the README example at 57,600 baud, damaged and joined tlogs,
gaps, and the link options checked before any flight (issue 22).

Real bytes over a real loopback UDP socket; the damaged files are made here from a real
recording. A record the converter returns has only finite values and no channel
interpolated across more than ``max_gap`` missing samples; anything else is a ValueError
naming the problem (exit 2 on the command line).
"""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.record import read
from flightid.scenarios.cards import fly_card, load_card
from flightid.sim.bridge.air.serve import BridgeConfig
from flightid.sim.bridge.decoding import message_time
from flightid.sim.bridge.frames import TlogWriter, read_tlog
from flightid.sim.bridge.ground.gaps import nominal_interval
from flightid.sim.bridge.ground.tlog import convert_tlog
from flightid.sim.bridge.ground.tlog_decode import decode_tlog
from flightid.sim.bridge.link import LinkFaults, UdpLink
from flightid.sim.bridge.loopback import record_bridged

RUNNER = CliRunner()


@pytest.fixture(scope="module")
def readme_flight(tmp_path_factory):
    """The README example: navion-demo served at 57,600 baud over loopback UDP with 5 %
    of the packets dropped and 0.1 % of the bytes corrupted (seed 1), and its recording."""
    folder = tmp_path_factory.mktemp("readme")
    measured, _ = fly_card(load_card("navion-demo"))
    cfg = BridgeConfig(baud=57600, faults=LinkFaults.parse("drop=0.05,corrupt=0.001"), seed=1)
    air, ground = record_bridged(measured, folder / "flight.tlog", cfg, transport="udp")
    return measured, folder / "flight.tlog", air


def test_readme_example_gives_a_complete_record_for_output_error(readme_flight, tmp_path):
    measured, tlog, air = readme_flight
    granted = {g.name: g for g in air.schedule.grants}
    assert granted["VFR_HUD"].status != "dropped"  # V is sent, without a time field
    data = decode_tlog(tlog)
    v = next(s for (_, m, ch), s in data.series.items() if m == "VFR_HUD" and ch == "V")
    assert data.untimed["VFR_HUD"]["left_out"] == 0
    # VFR_HUD goes out every 4th sample (12.5 Hz): times on that grid are exact (the
    # message shares its tick with a time-stamped one); the rest are off by one 20 ms
    # tick at most, where both neighbours belong to other ticks
    dt = 1.0 / measured.meta.sample_rate
    k = np.round(v.t / dt).astype(int)
    on_grid = (np.abs(v.t - k * dt) < 1e-6) & (k % granted["VFR_HUD"].divisor == 0)
    assert on_grid.mean() > 0.97, on_grid.mean()
    assert np.all(np.abs(v.t - k * dt) < dt + 1e-6)
    # where it is timed exactly, the value is the record's V at that sample (float32)
    np.testing.assert_allclose(v.v[on_grid], measured["V"][k[on_grid]], rtol=1e-6)

    out = tmp_path / "bridged.parquet"
    done = RUNNER.invoke(app, ["convert", str(tlog), str(out), "--aircraft", "navion"])
    assert done.exit_code == 0, done.output
    assert "VFR_HUD (no time field)" in done.output
    ident = RUNNER.invoke(app, ["identify", str(out), "--method", "oe", "--format", "json"])
    assert ident.exit_code == 0, ident.output
    assert "Cn_beta" in ident.output


def _rewrite(tlog: Path, out: Path, keep) -> int:
    """A copy of a tlog with the packets for which keep(index, message) is true."""
    writer = TlogWriter(out)
    for i, e in enumerate(read_tlog(tlog).entries):
        if keep(i, e.frame.msg):
            writer.write(e.t_recv, e.frame.raw)
    writer.close()
    return writer.count


def test_joined_tlog_is_a_time_reversal_not_a_loss(readme_flight, tmp_path):
    _, tlog, _ = readme_flight
    twice = tmp_path / "twice.tlog"
    twice.write_bytes(tlog.read_bytes() * 2)
    with pytest.raises(ValueError, match="time reversal"):
        convert_tlog(twice)
    done = RUNNER.invoke(app, ["convert", str(twice), str(tmp_path / "x.parquet")])
    assert done.exit_code == 2 and "time reversal" in done.output, done.output
    assert "lost" not in done.output
    assert not (tmp_path / "x.parquet").exists()


def test_a_gap_is_never_interpolated_beyond_the_allowed_samples(readme_flight, tmp_path):
    _, tlog, _ = readme_flight
    cut = tmp_path / "gap.tlog"
    # every packet timed in 20.0 .. 21.0 s goes (VFR_HUD, without a time, goes with them)
    state = {"t": 0.0}

    def keep(_, msg):
        t = message_time(msg)
        state["t"] = state["t"] if t is None else t
        return not 20.0 <= state["t"] < 21.0

    _rewrite(tlog, cut, keep)
    with pytest.raises(ValueError, match=r"gap\(s\) of more than 5 missing samples") as err:
        convert_tlog(cut)
    assert re.search(r"from 19\.\d+ to 21\.\d+ s", str(err.value)), str(err.value)
    # the longest stretch without it: 21 .. 45 s
    rec = convert_tlog(cut, segment="longest")
    assert rec.time[0] >= 20.9 and rec.time[-1] == pytest.approx(44.96, abs=0.1)
    assert all(np.all(np.isfinite(v)) for v in rec.channels.values())
    # allowing 30 missing samples (the 25 Hz channels miss 25 there) accepts it
    rec = convert_tlog(cut, max_gap=30)
    assert rec.time[0] < 1.0


@pytest.mark.parametrize("fraction,seed", [(0.01, 1), (0.10, 2)])
def test_flipped_bytes_give_finite_values_or_a_refusal(readme_flight, tmp_path, fraction, seed):
    _, tlog, _ = readme_flight
    rng = np.random.default_rng(seed)
    raw = np.frombuffer(tlog.read_bytes(), dtype=np.uint8).copy()
    hit = rng.random(raw.size) < fraction
    raw[hit] ^= rng.integers(1, 256, hit.sum(), dtype=np.uint8)
    bad = tmp_path / "flipped.tlog"
    bad.write_bytes(raw.tobytes())
    intact = read_tlog(bad)
    assert 0 < len(intact.entries) < len(read_tlog(tlog).entries)
    assert intact.skipped_bytes > 0
    with pytest.raises(ValueError, match="gap|too few intact packets"):
        convert_tlog(bad)  # 1 % already loses more than 5 packets in a row somewhere
    for max_gap in (5, 10):
        try:
            rec = convert_tlog(bad, segment="longest", max_gap=max_gap)
        except ValueError as exc:
            assert re.search("gap|too few intact packets", str(exc)), str(exc)
            continue
        assert all(np.all(np.isfinite(v)) for v in rec.channels.values())
        # no channel is interpolated across more than max_gap missing samples
        series = decode_tlog(bad)
        for ch, longest in rec.meta.extra["bridge"]["resampling"]["max_gap_s"].items():
            t = next(s.t for (_, _, c), s in series.series.items() if c == ch)
            assert longest <= (max_gap + 1.5) * nominal_interval(t), ch


@pytest.mark.parametrize("args,message", [
    (["bridge", "serve", "navion-demo", "--udp", "127.0.0.1:99999"], "outside 1..65535"),
    (["bridge", "serve", "navion-demo", "--udp", "127.0.0.1:0"], "outside 1..65535"),
    (["bridge", "serve", "navion-demo", "--udp", "localhost"], "HOST:PORT"),
    (["bridge", "serve", "navion-demo", "--udp", "127.0.0.1:14550", "--baud", "-5"],
     "--baud"),
    (["bridge", "serve", "navion-demo", "--udp", "127.0.0.1:14550", "--faults", "drop=2"],
     "probability"),
    (["bridge", "record", "-o", "x.tlog", "--udp", "127.0.0.1:14550", "--baud", "0"],
     "--baud"),
    (["bridge", "record", "-o", "x.tlog", "--udp", "127.0.0.1:14550", "--duration", "-1"],
     "--duration"),
    (["bridge", "fly", "navion", "--altitude", "0", "--speed", "53.64", "--udp",
      "127.0.0.1:70000"], "outside 1..65535"),
    (["bridge", "fly", "navion", "--altitude", "0", "--speed", "53.64", "--udp",
      "127.0.0.1:14550", "--rate", "0"], "--rate"),
    (["bridge", "fly", "navion", "--altitude", "0", "--speed", "53.64", "--udp",
      "127.0.0.1:14550", "--timeout", "nan"], "--timeout"),
    (["convert", "no/such.tlog", "out.parquet"], "no such file"),
    (["convert", "no/such.tlog", "out.parquet", "--segment", "middle"], "--segment"),
])
def test_link_options_are_checked_before_any_flight(tmp_path, args, message):
    done = RUNNER.invoke(app, args)
    assert done.exit_code == 2, done.output
    assert message in done.output
    assert "flying card" not in done.output and "trimmed" not in done.output
    assert "Traceback" not in done.output


def test_a_link_that_never_answers_exits_3(tmp_path):
    done = RUNNER.invoke(app, ["bridge", "fly", "navion", "--altitude", "0", "--speed",
                               "53.64", "--udp", "127.0.0.1:9", "--timeout", "1",
                               "--duration", "1", "--output", str(tmp_path / "f.parquet")])
    assert done.exit_code == 3, done.output
    assert "no ground station answered" in done.output
    assert "Traceback" not in done.output
    assert not (tmp_path / "f.parquet").exists()


def test_a_recorder_that_hears_nothing_exits_3_and_keeps_the_old_file(tmp_path):
    old = tmp_path / "flight.tlog"
    old.write_bytes(b"an earlier recording")
    probe = UdpLink(("127.0.0.1", 0), listen=True)  # a free port nobody sends to
    port = probe.local_address[1]
    probe.close()
    done = RUNNER.invoke(app, ["bridge", "record", "-o", str(old), "--udp",
                               f"127.0.0.1:{port}", "--first-timeout", "0.5"])
    assert done.exit_code == 3, done.output
    assert "no MAVLink packet arrived" in done.output
    assert old.read_bytes() == b"an earlier recording"


SILENT_CLIENT = r'''
import os, sys
os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil
port, answers = sys.argv[1], int(sys.argv[2])
conn = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", dialect="ardupilotmega",
                                  source_system=255, source_component=190)
if conn.recv_match(blocking=True, timeout=20) is None:  # learn the bridge's address
    sys.exit("no telemetry within 20 s")
conn.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID,
                        0, 0, 0)
sent = 0
while sent < answers:
    m = conn.recv_match(type="HIGHRES_IMU", blocking=True, timeout=20)
    if m is None:
        sys.exit("no telemetry within 20 s")
    conn.mav.hil_actuator_controls_send(m.time_usec + 20000, [0.0] * 16, 0, 0)
    sent += 1
'''


def test_a_ground_station_that_goes_silent_mid_flight_exits_3_and_keeps_the_steps(tmp_path):
    """Lock-step ``bridge fly`` over real UDP: the ground station answers 10 samples and
    goes silent. The 11 samples flown (the trim and 10 steps) are written, then the
    flight stops with exit 3 and says why."""
    probe = UdpLink(("127.0.0.1", 0), listen=True)
    port = probe.local_address[1]
    probe.close()
    script = tmp_path / "client.py"
    script.write_text(SILENT_CLIENT)
    client = subprocess.Popen([sys.executable, str(script), str(port), "10"],
                              stderr=subprocess.PIPE, text=True)
    out = tmp_path / "flown.parquet"
    try:
        done = subprocess.run(
            [sys.executable, "-m", "flightid.cli.app", "bridge", "fly", "navion", "--altitude", "0",
             "--speed", "53.64", "--udp", f"127.0.0.1:{port}", "--timeout", "2",
             "--duration", "2", "--output", str(out)],
            capture_output=True, text=True, timeout=120)
        _, err = client.communicate(timeout=30)
    finally:
        if client.poll() is None:
            client.kill()
    assert client.returncode == 0, err
    assert done.returncode == 3, done.stdout + done.stderr
    assert "the flight ended early: no control within 2 s after step 10 of 100" in done.stderr
    assert "Traceback" not in done.stderr
    flown = read(out)
    assert flown.time.size == 11
    assert np.all(np.isfinite(flown["q"]))
