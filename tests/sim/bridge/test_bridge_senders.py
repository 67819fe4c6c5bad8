"""Who may fly the aircraft: packets from other senders, unsigned or badly signed packets
never move a surface, and the report counts them (issue 22).

A separate pymavlink process flies an elevator doublet in lock-step over a real pty, as
in test_bridge_loop.py. Before each of its controls, intruders on the same wire send a
full-deflection command: another system, another component of the ground system, and,
with signing on, the ground's own ids unsigned, signed with a wrong key (and a timestamp
far ahead, which would lock the real sender out if the timestamp were stored before the
signature is checked), and a replay of the ground's previous signed packet. In lock-step
every accepted control is one step, so one accepted intruder packet would change the
flight: it must equal the doublet flown directly (float32 command transport, 1e-7).
"""

import subprocess
import sys

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from flightid.sim.bridge.air.closed_loop import FlightCoreAdapter, serve_simulation
from flightid.sim.bridge.air.serve import BridgeConfig
from flightid.sim.bridge.air.signing import (
    SenderFilter,
    read_key,
    setup_outgoing,
    signature_valid,
)
from flightid.sim.bridge.link import open_pty_pair
from flightid.sim.flight.simulation import Simulation, fly
from flightid.sim.jsbsim.trim import trim
from flightid.units import DEG

CLIENT = r'''
import os, sys
os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
port, mode, key_hex = sys.argv[1:4]
de_trim, da_trim, dr_trim, throttle, amp, t_on, width, max_defl, dt, t_end = map(
    float, sys.argv[4:])
conn = mavutil.mavlink_connection(port, baud=115200, dialect="ardupilotmega",
                                  source_system=255, source_component=190)
intruders = [mavlink2.MAVLink(conn, 66, 1), mavlink2.MAVLink(conn, 255, 191)]
if mode == "signed":
    key = bytes.fromhex(key_hex)
    conn.setup_signing(key, sign_outgoing=True)
    unsigned = mavlink2.MAVLink(conn, 255, 190)
    forged = mavlink2.MAVLink(conn, 255, 190)
    forged.signing.secret_key = bytes(32)
    forged.signing.sign_outgoing = True
    forged.signing.link_id = conn.mav.signing.link_id
    forged.signing.timestamp = conn.mav.signing.timestamp + 10**9
    intruders += [unsigned, forged]
for mav in intruders:
    mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID,
                       0, 0, 0)
conn.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID,
                        0, 0, 0)
def doublet(t):
    if t_on - 1e-9 <= t < t_on + width - 1e-9:
        return amp
    if t_on + width - 1e-9 <= t < t_on + 2 * width - 1e-9:
        return -amp
    return 0.0
previous = None
while True:
    m = conn.recv_match(type="HIGHRES_IMU", blocking=True, timeout=10)
    if m is None:
        sys.exit("no telemetry within 10 s")
    t = m.time_usec * 1e-6
    if t >= t_end - 1e-9:
        break
    t_next = t + dt
    usec = int(round(t_next * 1e6))
    for mav in intruders:  # full deflection on every axis, before the ground's command
        mav.hil_actuator_controls_send(usec, [1.0, 1.0, 1.0, 1.0] + [0.0] * 12, 0, 0)
    if previous is not None:
        conn.write(previous)  # a replay of the ground's last packet
    de = de_trim + doublet(t_next)
    controls = [-da_trim / max_defl, -de / max_defl, -dr_trim / max_defl, throttle]
    packet = conn.mav.hil_actuator_controls_encode(usec, controls + [0.0] * 12, 0, 0).pack(
        conn.mav)
    conn.mav.seq = (conn.mav.seq + 1) % 256
    conn.write(packet)
    previous = packet if mode == "signed" else None
print(len(intruders))
'''


@pytest.fixture(scope="module")
def navion():
    """Trim and the elevator doublet flown directly (no link), 3 s at 50 Hz."""
    rate, duration = 50.0, 3.0
    tr = trim("navion", 1000.0, 50.0)
    amp, t_on, width = 2.0 * DEG, 0.5, 0.5
    n = int(duration * rate) + 1
    t = np.arange(n) / rate
    doublet = np.where((t >= t_on - 1e-9) & (t < t_on + width - 1e-9), amp,
                       np.where((t >= t_on + width - 1e-9) & (t < t_on + 2 * width - 1e-9),
                                -amp, 0.0))
    direct = fly("navion", tr, {"de": doublet}, duration_s=duration, rate_hz=rate)
    return tr, (amp, t_on, width), rate, duration, direct


@pytest.mark.parametrize("mode", ["plain", "signed"])
def test_other_senders_never_move_a_surface(tmp_path, navion, mode):
    tr, (amp, t_on, width), rate, duration, direct = navion
    key = bytes(range(1, 33))
    cfg = BridgeConfig(baud=None, ground_system=255, ground_component=190,
                       signing_key=key if mode == "signed" else None)
    sim = FlightCoreAdapter(Simulation("navion", rate_hz=rate), tr)
    held = {"de": tr.elevator, "da": tr.aileron, "dr": tr.rudder, "throttle": tr.throttle}
    initial = sim.reset(held)
    n = len(direct)
    pty = open_pty_pair()
    script = tmp_path / "client.py"
    script.write_text(CLIENT)
    client = subprocess.Popen(
        [sys.executable, str(script), pty.slave_path, mode, key.hex()]
        + [repr(x) for x in (tr.elevator, tr.aileron, tr.rudder, tr.throttle, amp, t_on, width,
                             cfg.servo_map.de_max, 1 / rate, duration)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        report, history = serve_simulation(sim, initial, pty.master_link(), cfg, steps=n - 1,
                                           lockstep=True, timeout=20.0, controls=held)
        out, err = client.communicate(timeout=30)
    finally:
        if client.poll() is None:
            client.kill()
        pty.close()
    assert client.returncode == 0, err
    assert report.controls_received == n - 1 and report.ended == ""
    for name in ("q", "theta", "de", "da", "dr", "alpha", "beta", "p", "r"):
        bridged = np.array([h[name] for h in history])
        np.testing.assert_allclose(bridged, direct[name], atol=1e-7, rtol=0,
                                   err_msg=f"{name} moved by an intruder ({mode})")
    assert np.ptp(direct["q"]) > 0.01
    # each intruder: one heartbeat and one command per step; the replays: one per step
    # after the first
    per_intruder = 1 + (n - 1)
    if mode == "plain":
        assert report.refused == {"other sender": 2 * per_intruder}
    else:
        assert report.refused == {"other sender": 2 * per_intruder,
                                  "unsigned": per_intruder, "bad signature": per_intruder,
                                  "replayed": n - 2}
    assert report.as_dict()["packets_refused"] == report.refused


def test_signing_keys_and_filter(tmp_path):
    raw_key = bytes(range(32))
    (tmp_path / "raw.key").write_bytes(raw_key)
    (tmp_path / "hex.key").write_text(raw_key.hex()[:40] + "\n" + raw_key.hex()[40:] + "\n")
    assert read_key(tmp_path / "raw.key") == raw_key == read_key(tmp_path / "hex.key")
    (tmp_path / "short.key").write_bytes(b"secret")
    with pytest.raises(ValueError, match="32 raw bytes or 64 hexadecimal digits"):
        read_key(tmp_path / "short.key")
    with pytest.raises(FileNotFoundError):
        read_key(tmp_path / "none.key")
    with pytest.raises(ValueError, match="1..255"):
        SenderFilter(ground_system=0)
    # a signed frame from pymavlink passes; one flipped signature byte does not
    mav = mavlink2.MAVLink(None, 255, 190)
    setup_outgoing(mav, raw_key)
    frame = mavlink2.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(mav)
    assert signature_valid(frame, raw_key) and not signature_valid(frame, bytes(32))
    bad = bytearray(frame)
    bad[-1] ^= 1
    check = SenderFilter(255, 190, raw_key)
    assert check.reason(bytes(bad), (255, 190)) == "bad signature"
    assert check.accept(frame, (255, 190)) and not check.accept(frame, (255, 190))
    assert check.rejected == {"replayed": 1}
