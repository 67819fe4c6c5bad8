"""Signed links cannot be replayed (issue 38): the last signing timestamp of every
(link id, system, component) stream persists in a file beside the key, so the correctly
signed packets of an earlier run, replayed byte for byte by a sender without the key,
are refused and counted in the next run; a new stream more than 60 s behind the clock is
refused too (the MAVLink 2 signing rules, as pymavlink's ``check_signature``).

The replay test runs ``flightid bridge fly`` twice as a real process on real loopback
UDP, in real time: the first run is flown by a ground station's MANUAL_CONTROL commands,
whose bytes are saved; in the second the ground station only says hello (one fresh signed
HEARTBEAT) and an intruder replays the saved bytes before and during the flight. Every
replayed packet must be refused as replayed, and the second flight must equal the trim
held without commands (flown directly, no link: 1e-7, the float32 transport of the
telemetry is not involved since the record is the air side's own history).
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from flightid.record import read
from flightid.sim.bridge.air.signing import (
    SenderFilter,
    read_state,
    setup_outgoing,
    signing_timestamp,
    state_path,
)
from flightid.sim.flight.simulation import fly
from flightid.sim.jsbsim.trim import trim

KEY = bytes(range(7, 39))
RATE, DURATION = 50.0, 3.0
ALTITUDE, SPEED = 1000.0, 50.0


def _ground(key: bytes, link_id: int = 0) -> mavlink2.MAVLink:
    mav = mavlink2.MAVLink(None, 255, 190)
    setup_outgoing(mav, key, link_id)
    return mav


def _pack(mav: mavlink2.MAVLink, msg) -> bytes:
    raw = bytes(msg.pack(mav))
    mav.seq = (mav.seq + 1) % 256
    return raw


def _heartbeat(mav: mavlink2.MAVLink) -> bytes:
    return _pack(mav, mavlink2.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))


def _start_fly(tmp_path, key_file, port: int, output: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "flightid.cli.app", "bridge", "fly", "navion",
         "--altitude", str(ALTITUDE), "--speed", str(SPEED), "--udp", f"127.0.0.1:{port}",
         "--rate", str(RATE), "--duration", str(DURATION), "--no-lockstep", "--timeout", "60",
         "--signing-key", str(key_file), "--output", str(tmp_path / output)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)


def _bridge_address(ground: socket.socket) -> tuple[str, int]:
    """The air side's address: where its first telemetry (a heartbeat) came from."""
    ground.settimeout(120)
    _, addr = ground.recvfrom(65536)
    return addr


def _finish(proc: subprocess.Popen) -> str:
    try:
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    return out


def test_replayed_signed_packets_are_refused_in_the_next_run(tmp_path):
    key_file = tmp_path / "link.key"
    key_file.write_bytes(KEY)
    # run 1: a ground station with the key flies a pitch and throttle command
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as ground:
        ground.bind(("127.0.0.1", 0))
        run1 = _start_fly(tmp_path, key_file, ground.getsockname()[1], "run1.parquet")
        bridge = _bridge_address(ground)
        mav = _ground(KEY)
        saved = [_heartbeat(mav)]
        for k in range(40):
            saved.append(_pack(mav, mavlink2.MAVLink_manual_control_message(
                1, 300 if k < 20 else -300, 0, 600, 0, 0)))
        for raw in saved:
            ground.sendto(raw, bridge)
            time.sleep(0.01)
        out1 = _finish(run1)
    assert "refused" not in out1
    assert read_state(state_path(key_file)) == {(0, 255, 190): int.from_bytes(
        saved[-1][-12:-6], "little")}

    # run 2: the ground station only says hello; an intruder replays run 1's bytes
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as ground, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as intruder:
        ground.bind(("127.0.0.1", 0))
        run2 = _start_fly(tmp_path, key_file, ground.getsockname()[1], "run2.parquet")
        bridge = _bridge_address(ground)
        for raw in saved:  # before the flight starts: would start it, were it accepted
            intruder.sendto(raw, bridge)
        time.sleep(0.2)
        ground.sendto(_heartbeat(_ground(KEY)), bridge)
        for raw in saved[1:]:  # during the flight
            intruder.sendto(raw, bridge)
            time.sleep(0.01)
        out2 = _finish(run2)

    replays = len(saved) + len(saved) - 1
    assert f"refused {replays} packet(s) that may not fly the aircraft: {replays} replayed" \
        in out2, out2
    assert "0 control messages received" in out2

    tr = trim("navion", ALTITUDE, SPEED)
    held = fly("navion", tr, {}, duration_s=DURATION, rate_hz=RATE)
    first, second = read(tmp_path / "run1.parquet"), read(tmp_path / "run2.parquet")
    assert len(second) == len(held)
    for name in ("q", "theta", "u", "alpha", "de", "throttle", "p", "r", "phi"):
        np.testing.assert_allclose(second[name], held[name], atol=1e-7, rtol=0,
                                   err_msg=f"{name}: the replay moved the aircraft")
    # the replayed commands do fly the aircraft when accepted: run 1 pitched
    assert np.ptp(first["q"]) > 0.01 and np.ptp(held["q"]) < 1e-4


def _signed(mav: mavlink2.MAVLink) -> bytes:
    return _heartbeat(mav)


def test_new_stream_more_than_60_s_old_is_stale_and_state_persists(tmp_path):
    state = tmp_path / "k.timestamps.json"
    check = SenderFilter(255, None, KEY, state=state)
    old = _ground(KEY, link_id=1)
    old.signing.timestamp = signing_timestamp(time.time() - 120.0)
    recent = _ground(KEY, link_id=2)
    recent.signing.timestamp = signing_timestamp(time.time() - 30.0)
    assert check.reason(_signed(old), (255, 190)) == "stale"
    first = _signed(recent)
    assert check.accept(first, (255, 190))
    check.save()
    # a new filter (the next run) knows the stream: the same packet is a replay, a newer
    # one on it passes
    again = SenderFilter(255, None, KEY, state=state)
    assert again.reason(first, (255, 190)) == "replayed"
    assert again.accept(_signed(recent), (255, 190))
    assert again.rejected == {}


def test_damaged_state_file_is_named(tmp_path):
    state = tmp_path / "k.timestamps.json"
    state.write_text("{not json")
    with pytest.raises(ValueError, match="k.timestamps.json: not a signing timestamp file"):
        SenderFilter(255, None, KEY, state=state)


def test_nan_controls_are_refused_and_counted_not_flown_as_trim(tmp_path):
    """HIL_ACTUATOR_CONTROLS carrying NaN (unsigned link): refused and counted as 'not
    finite'; the flight is the trim held, as without commands."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as ground:
        ground.bind(("127.0.0.1", 0))
        proc = subprocess.Popen(
            [sys.executable, "-m", "flightid.cli.app", "bridge", "fly", "navion",
             "--altitude", str(ALTITUDE), "--speed", str(SPEED), "--udp",
             f"127.0.0.1:{ground.getsockname()[1]}", "--rate", str(RATE), "--duration",
             str(DURATION), "--no-lockstep", "--timeout", "60", "--output",
             str(tmp_path / "nan.parquet")],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
        bridge = _bridge_address(ground)
        mav = mavlink2.MAVLink(None, 255, 190)
        ground.sendto(_heartbeat(mav), bridge)
        nan = float("nan")
        for k in range(30):
            controls = [nan, 0.5, 0.0, 0.5] if k % 2 else [0.0, nan, nan, nan]
            ground.sendto(_pack(mav, mavlink2.MAVLink_hil_actuator_controls_message(
                k, controls + [0.0] * 12, 0, 0)), bridge)
            time.sleep(0.01)
        out = _finish(proc)
    assert "refused 30 packet(s) that may not fly the aircraft: 30 not finite" in out, out
    held = fly("navion", trim("navion", ALTITUDE, SPEED), {}, duration_s=DURATION,
               rate_hz=RATE)
    flown = read(tmp_path / "nan.parquet")
    for name in ("q", "theta", "de", "da", "dr", "throttle", "p"):
        np.testing.assert_allclose(flown[name], held[name], atol=1e-7, rtol=0, err_msg=name)
