"""In the loop: an external pymavlink client flies the JSBSim aircraft through the bridge.

The client is a separate Python process that knows nothing of flightid: it opens the
pty by name with ``mavutil.mavlink_connection``, waits for each HIGHRES_IMU sample and
answers with HIL_ACTUATOR_CONTROLS (lock-step). The bridged flight must match the same
doublet flown directly with ``flight.fly``: the only difference is the float32
transport of the normalised commands (|de error| <= 30 deg * 2^-24 = 3e-8 rad).
"""

import subprocess
import sys

import numpy as np
import pytest

from flightid.sim.bridge.air.closed_loop import FlightCoreAdapter, serve_simulation
from flightid.sim.bridge.air.serve import BridgeConfig
from flightid.sim.bridge.link import open_pty_pair
from flightid.sim.flight.simulation import Simulation, fly
from flightid.sim.jsbsim.trim import trim
from flightid.units import DEG

CLIENT = r'''
import os, sys
os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil
port = sys.argv[1]
de_trim, da_trim, dr_trim, throttle, amp, t_on, width, max_defl, dt, t_end = map(
    float, sys.argv[2:])
conn = mavutil.mavlink_connection(port, baud=115200, dialect="ardupilotmega",
                                  source_system=255, source_component=190)
conn.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID,
                        0, 0, 0)
def doublet(t):
    if t_on - 1e-9 <= t < t_on + width - 1e-9:
        return amp
    if t_on + width - 1e-9 <= t < t_on + 2 * width - 1e-9:
        return -amp
    return 0.0
while True:
    m = conn.recv_match(type="HIGHRES_IMU", blocking=True, timeout=10)
    if m is None:
        sys.exit("no telemetry within 10 s")
    t = m.time_usec * 1e-6
    if t >= t_end - 1e-9:
        break
    t_next = t + dt  # the control answering sample t_k acts at t_(k+1)
    de = de_trim + doublet(t_next)
    # normalised: roll, pitch, yaw moments (+ = right, nose up, nose right), throttle
    controls = [-da_trim / max_defl, -de / max_defl, -dr_trim / max_defl, throttle]
    conn.mav.hil_actuator_controls_send(int(round(t_next * 1e6)), controls + [0.0] * 12, 0, 0)
'''


@pytest.mark.parametrize("aircraft,amp_deg", [("navion", 2.0), ("telemaster", -3.0)])
def test_external_client_flies_a_doublet_in_lock_step(tmp_path, aircraft, amp_deg):
    rate, duration = 50.0, 6.0
    tr = trim(aircraft, 300.0 if aircraft == "telemaster" else 1000.0,
              20.0 if aircraft == "telemaster" else 50.0)
    amp, t_on, width = amp_deg * DEG, 1.0, 0.5
    n = int(duration * rate) + 1
    t = np.arange(n) / rate
    doublet = np.where((t >= t_on - 1e-9) & (t < t_on + width - 1e-9), amp,
                       np.where((t >= t_on + width - 1e-9) & (t < t_on + 2 * width - 1e-9),
                                -amp, 0.0))
    direct = fly(aircraft, tr, {"de": doublet}, duration_s=duration, rate_hz=rate)

    cfg = BridgeConfig(baud=None)  # one servo limit for all surfaces (ServoMap default)
    assert cfg.servo_map.de_max == cfg.servo_map.da_max == cfg.servo_map.dr_max
    sim = FlightCoreAdapter(Simulation(aircraft, rate_hz=rate), tr)
    held = {"de": tr.elevator, "da": tr.aileron, "dr": tr.rudder, "throttle": tr.throttle}
    initial = sim.reset(held)
    pty = open_pty_pair()
    script = tmp_path / "client.py"
    script.write_text(CLIENT)
    client = subprocess.Popen(
        [sys.executable, str(script), pty.slave_path]
        + [repr(x) for x in (tr.elevator, tr.aileron, tr.rudder, tr.throttle, amp, t_on, width,
                             cfg.servo_map.de_max, 1 / rate, duration)],
        stderr=subprocess.PIPE, text=True)
    try:
        report, history = serve_simulation(
            sim, initial, pty.master_link(), cfg, steps=n - 1, lockstep=True, timeout=20.0,
            controls=held)
        client.wait(timeout=30)
    finally:
        if client.poll() is None:
            client.kill()
        pty.close()
    assert client.returncode == 0, client.stderr.read()
    assert report.controls_received == n - 1
    assert len(history) == n
    for name in ("q", "theta", "de", "alpha"):
        bridged = np.array([h[name] for h in history])
        # float32 command transport: <= 3e-8 rad of de; the responses of these stable
        # aircraft to such a step stay below 1e-7 over 6 s (measured: ~3e-9)
        np.testing.assert_allclose(bridged, direct[name], atol=1e-7, rtol=0,
                                   err_msg=f"{name} differs between bridge and direct flight")
    # the doublet did excite the aircraft (the comparison is not trivially flat)
    assert np.ptp(direct["q"]) > 0.01
