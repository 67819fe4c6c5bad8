"""Recorder bridge timing: real-time delivery latency/jitter over loopback UDP, and the
throughput of the fast (as-fast-as-possible) pty path and of tlog conversion.

Run:  .venv/bin/python benchmarks/bridge_timing.py   (writes benchmarks/results/bridge_timing.json)
Wall-clock numbers depend on the machine; that is why they live here and not in tests.
"""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import numpy as np

from flightid.record import FlightRecord
from flightid.sim.bridge.air.serve import BridgeConfig, serve_record
from flightid.sim.bridge.decoding import message_time
from flightid.sim.bridge.frames import read_tlog
from flightid.sim.bridge.ground.recording import record_stream
from flightid.sim.bridge.ground.tlog import convert_tlog
from flightid.sim.bridge.link import LinkFaults, UdpLink
from flightid.sim.bridge.loopback import record_bridged

OUT = Path(__file__).parent / "results" / "bridge_timing.json"


def smooth_record(duration: float, rate: float = 100.0) -> FlightRecord:
    """Sines on the canonical channels (enough for timing)."""
    t = np.arange(int(duration * rate)) / rate
    s = np.sin(2 * np.pi * 0.5 * t)
    ch = {n: 0.1 * s for n in ("alpha", "beta", "p", "q", "r", "phi", "theta", "psi",
                               "ax", "ay", "de", "da", "dr")}
    ch.update(V=30 + s, az=-9.8 + s, h=300 + 10 * s, throttle=0.5 + 0.2 * s,
              north=25 * t, east=0 * t)
    return FlightRecord(t, ch)


def realtime_latency(latency: float, jitter: float, duration: float = 5.0) -> dict:
    """Real-time stream over loopback UDP; delay of HIGHRES_IMU arrivals vs their time."""
    rec = smooth_record(duration)
    ground = UdpLink(("127.0.0.1", 0), listen=True)
    air = UdpLink(ground.local_address, listen=False)
    tlog = OUT.with_name("bridge_timing_rt.tlog")
    stop = threading.Event()
    thread = threading.Thread(
        target=lambda: record_stream(ground, tlog, stop=stop, idle_timeout=5.0), daemon=True)
    thread.start()
    baud = 115200
    cfg = BridgeConfig(baud=baud, realtime=True, faults=LinkFaults(latency=latency, jitter=jitter))
    report = serve_record(rec, air, cfg)
    stop.set()
    thread.join(30)
    ground.close()
    air.close()
    entries = read_tlog(tlog).entries
    arrivals = {(f.seq, f.t): f.arrive for f in report.transmit.fates if f.msgid == 105}
    delays, model = [], []
    for e in entries:
        if e.frame.msg.get_type() != "HIGHRES_IMU":
            continue
        t_msg = message_time(e.frame.msg)
        delays.append(e.t_recv - t_msg)
        model.append(arrivals[(e.frame.msg.get_seq(), round(t_msg, 6))] - t_msg)
    delays = np.array(delays)
    # the wall-clock anchor of sim time 0 is unknown to the ground; take the smallest
    # modelled-minus-measured difference as the common constant
    offset = np.min(delays - np.array(model))
    measured = delays - offset
    return {
        "latency_s": latency, "jitter_s": jitter, "baud": baud,
        "packets": len(delays),
        "modelled_delay_mean_s": float(np.mean(model)),
        "modelled_delay_std_s": float(np.std(model)),
        "measured_delay_mean_s": float(np.mean(measured)),
        "measured_delay_std_s": float(np.std(measured)),
        "measured_minus_modelled_p99_s": float(np.percentile(measured - np.array(model), 99)),
        "note": "measured delays are anchored so that the least-delayed packet matches the "
                "model (the ground does not know the air side's wall-clock origin)",
    }


def throughput(duration: float = 60.0) -> dict:
    """Fast pty path and conversion speed for a 100 Hz record."""
    rec = smooth_record(duration)
    tlog = OUT.with_name("bridge_timing_fast.tlog")
    t0 = time.perf_counter()
    air, ground = record_bridged(rec, tlog, BridgeConfig(baud=None))
    t1 = time.perf_counter()
    convert_tlog(tlog)
    t2 = time.perf_counter()
    return {"flight_s": duration, "packets": air.transmit.packets,
            "bridge_wall_s": t1 - t0, "packets_per_s": air.transmit.packets / (t1 - t0),
            "convert_wall_s": t2 - t1}


def main() -> None:
    results = {
        "realtime": [realtime_latency(0.0, 0.0), realtime_latency(0.05, 0.01)],
        "throughput": throughput(),
    }
    OUT.write_text(json.dumps(results, indent=2))
    for p in OUT.parent.glob("bridge_timing_*.tlog*"):
        p.unlink()
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
