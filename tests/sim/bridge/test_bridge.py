"""The recorder bridge end to end: record -> MAVLink over a pty / UDP -> tlog -> record.

Every test runs real bytes through a real pseudo-terminal or loopback socket; pymavlink's
own tools read the tlogs. Tolerances are the MAVLink fields' resolutions (float32 ulp,
integer scalings) and, for resampled channels, the linear-interpolation error bound
h^2/8 max|f''| of the signal (h = the message's sample interval).
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flightid.record import FlightRecord, RecordMeta
from flightid.sim.bridge.air.schedule import (
    MessageRate,
    StreamSpec,
    boomerang,
    plan_schedule,
    single_stream,
)
from flightid.sim.bridge.air.serve import BridgeConfig, serve_record
from flightid.sim.bridge.decoding import resolution
from flightid.sim.bridge.frames import read_tlog
from flightid.sim.bridge.ground.tlog import convert_tlog
from flightid.sim.bridge.ground.tlog_decode import decode_tlog
from flightid.sim.bridge.link import FdLink, LinkFaults, Transmitter, UdpLink, parse_hostport
from flightid.sim.bridge.loopback import record_bridged
from flightid.sim.bridge.messages import ServoMap
from flightid.units import DEG

BIN = Path(sys.executable).parent


def synthetic_record(seed: int, duration: float = 20.0, rate: float = 100.0) -> FlightRecord:
    """Smooth flight-like histories of the canonical channels (sums of sines, seeded)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * rate)) / rate

    def wave(amp, lo=0.1, hi=1.2):
        f = rng.uniform(lo, hi, 2)
        ph = rng.uniform(0, 2 * np.pi, 2)
        return amp * (0.7 * np.sin(2 * np.pi * f[0] * t + ph[0])
                      + 0.3 * np.sin(2 * np.pi * f[1] * t + ph[1]))

    ch = {
        "V": 35 + wave(3, 0.02, 0.1), "alpha": 0.06 + wave(0.04), "beta": wave(0.03),
        "p": wave(0.4), "q": wave(0.25), "r": wave(0.15),
        "phi": wave(0.4, 0.05, 0.3), "theta": 0.05 + wave(0.15, 0.05, 0.3),
        "psi": 0.5 + 0.06 * t + wave(0.1, 0.02, 0.1),
        "ax": wave(1.5), "ay": wave(0.8), "az": -9.8 + wave(3),
        "de": wave(12 * DEG, 0.2, 1.0), "da": wave(10 * DEG, 0.2, 1.0),
        "dr": wave(8 * DEG, 0.2, 1.0),
        "throttle": 0.55 + wave(0.3, 0.02, 0.2), "h": 400 + wave(30, 0.02, 0.1),
        "north": 30 * t, "east": 4 * t,
    }
    meta = RecordMeta(aircraft="synthetic", sample_rate=rate, provenance="test")
    return FlightRecord(t, ch, meta)


def _interp_bound(record: FlightRecord, name: str, h: float) -> float:
    """h^2/8 max|f''| for linear interpolation at spacing h (s), plus a margin of 10 %."""
    f = np.unwrap(record[name]) if name == "psi" else record[name]
    d2 = np.gradient(np.gradient(f, record.time), record.time)
    return 1.1 * h**2 / 8 * float(np.max(np.abs(d2)))


# -- link budget -----------------------------------------------------------------------


@pytest.mark.parametrize("baud", [9600, 57600, 115200, 921600, None])
@pytest.mark.parametrize("profile", [single_stream, boomerang])
def test_schedule_fits_the_link_and_keeps_the_essentials(baud, profile):
    sched = plan_schedule(profile(), 100.0, baud)
    assert sched.load <= sched.capacity
    for g in sched.grants:
        if g.name in ("HEARTBEAT", "SYSTEM_TIME"):
            assert g.status == "full"
        # rates are source / integer so that messages fall on samples
        if g.divisor:
            assert g.rate == pytest.approx(100.0 / g.divisor)
    if baud is None:
        assert all(g.status == "full" for g in sched.grants)


def test_57600_baud_cannot_carry_everything_at_100_hz():
    # 57,600 baud = 5,760 bytes/s; HIGHRES_IMU alone (75-byte frames) needs 7,500 at 100 Hz
    sched = plan_schedule(single_stream(), 100.0, 57600)
    status = {g.name: g.status for g in sched.grants}
    assert status["HIL_SENSOR"] == "dropped" and status["HIL_STATE_QUATERNION"] == "dropped"
    assert status["HIGHRES_IMU"] == "reduced"
    assert all(status[m] != "dropped" for m in ("HIGHRES_IMU", "ATTITUDE", "AOA_SSA",
                                                "SERVO_OUTPUT_RAW", "GPS_RAW_INT", "VFR_HUD"))
    assert "dropped to fit the link" in sched.table()


def test_bad_configuration_is_named():
    with pytest.raises(ValueError, match="NOT_A_MESSAGE"):
        StreamSpec("x", messages=(MessageRate("NOT_A_MESSAGE", 10),))
    with pytest.raises(ValueError, match="clock_offset"):
        StreamSpec("x", clock_offset=-1.0)
    with pytest.raises(ValueError, match="unknown fault 'dorp'"):
        LinkFaults.parse("dorp=0.1")
    with pytest.raises(ValueError, match="probability"):
        LinkFaults.parse("drop=1.5")
    with pytest.raises(ValueError, match="not a loopback"):
        parse_hostport("8.8.8.8:14550")
    rec = synthetic_record(1, 1.0)
    uneven = FlightRecord(rec.time ** 1.01 + 0.0, rec.channels, rec.meta)
    with pytest.raises(ValueError, match="not uniformly sampled"):
        serve_record(uneven, UdpLink(("127.0.0.1", 9), listen=False))
    assert LinkFaults.parse("corrupt=0.1, drop=0.05,latency=0.02,jitter=0.01") == LinkFaults(
        0.1, 0.05, 0.02, 0.01)


# -- end to end ----------------------------------------------------------------------------


@pytest.mark.parametrize("seed,baud", [(1, 57600), (2, 921600)])
def test_pty_end_to_end_equals_the_direct_record(tmp_path, seed, baud):
    rec = synthetic_record(seed)
    tlog = tmp_path / "flight.tlog"
    air, ground = record_bridged(rec, tlog, BridgeConfig(baud=baud, seed=seed))
    assert air.transmit.sent_intact == air.transmit.packets == ground.scan["frames"]
    assert ground.scan["rejected"] == 0 and ground.scan["junk_bytes"] == 0

    data = decode_tlog(tlog)
    servo = ServoMap()
    granted = {g.name: g for g in air.schedule.grants}
    checked = 0
    for (_, message, channel), ser in data.series.items():
        # each message arrives exactly as often as the schedule granted
        g = granted[message]
        assert len(ser.t) == len(range(0, len(rec), g.divisor)), message
        if channel not in rec.channels:
            continue
        k = np.round(ser.t * 100.0).astype(int)  # time stamps are the sim clock
        np.testing.assert_allclose(ser.t, rec.time[k], atol=1e-6)  # us / ms resolution
        truth = rec[channel][k]
        if channel == "psi":
            err = np.abs((ser.v - truth + np.pi) % (2 * np.pi) - np.pi)
        else:
            err = np.abs(ser.v - truth)
        tol = np.array([resolution(channel, message, x, servo) for x in truth])
        assert np.all(err <= tol * 0.5 + 1e-12 + 1e-9 * np.abs(truth)), (
            f"{channel} from {message}: max error {err.max():.3g}, resolution {tol.max():.3g}")
        checked += 1
    assert checked >= 15

    out = convert_tlog(tlog)
    assert out.meta.extra["bridge"]["losses"]["1/1"]["lost"] == 0
    inside = (out.time > 0.3) & (out.time < rec.time[-1] - 0.3)
    for name, label in out.meta.extra["bridge"]["sources"].items():
        if name not in rec.channels:
            continue
        message = label.split()[1]
        h = granted[message].divisor / 100.0
        truth = np.interp(out.time, rec.time, np.unwrap(rec[name]) if name == "psi" else rec[name])
        got = out[name]
        if name == "psi":
            got = truth + (got - truth + np.pi) % (2 * np.pi) - np.pi
        tol = _interp_bound(rec, name, h) + resolution(name, message, np.max(np.abs(truth)), servo)
        err = np.max(np.abs(got - truth)[inside])
        assert err <= tol, f"{name}: {err:.3g} > {tol:.3g} (from {label} at {1 / h:g} Hz)"
    assert "linear interpolation" in out.meta.extra["bridge"]["resampling"]["method"]
    back = FlightRecord.__module__ and out.write(tmp_path / "flight.parquet")
    assert back.exists()


def test_pymavlink_mavlogdump_reads_the_tlog(tmp_path):
    rec = synthetic_record(3, 5.0)
    tlog = tmp_path / "flight.tlog"
    _, ground = record_bridged(rec, tlog, BridgeConfig(baud=115200))
    done = subprocess.run([sys.executable, str(BIN / "mavlogdump.py"), str(tlog)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    lines = [ln for ln in done.stdout.splitlines() if ln.strip()]
    assert len(lines) == ground.scan["frames"]
    kinds = {re.search(r": ([A-Z_0-9]+) \{", ln).group(1) for ln in lines}
    assert {"HIGHRES_IMU", "ATTITUDE", "AOA_SSA", "SERVO_OUTPUT_RAW", "GPS_RAW_INT"} <= kinds


def _lost_between(air, intact_fate="sent"):
    """Per source, packets not delivered intact between the first and last intact one."""
    out = {}
    for src in {f.source for f in air.transmit.fates}:
        fates = [f.fate for f in air.transmit.fates if f.source == src]
        idx = [i for i, x in enumerate(fates) if x == intact_fate]
        out[src] = sum(1 for x in fates[idx[0]:idx[-1] + 1] if x != intact_fate) if idx else 0
    return out


@pytest.mark.parametrize("seed,drop", [(4, 0.05), (5, 0.02)])
def test_mavloss_reports_the_injected_packet_loss(tmp_path, seed, drop):
    rec = synthetic_record(seed, 15.0)
    tlog = tmp_path / "lossy.tlog"
    air, ground = record_bridged(rec, tlog, BridgeConfig(baud=None, seed=seed,
                                                         faults=LinkFaults(drop=drop)))
    done = subprocess.run([sys.executable, str(BIN / "mavloss.py"), str(tlog)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    m = re.search(r"Total: (\d+) packets, (\d+) lost ([\d.]+)%", done.stdout)
    assert m, done.stdout
    received, lost, pct = int(m.group(1)), int(m.group(2)), float(m.group(3))
    assert abs(pct - 100 * drop) < 1.0
    # and exactly what the air side dropped between the first and last packet received
    assert lost == sum(_lost_between(air).values())
    assert received == air.transmit.sent_intact
    assert ground.sources["1/1"]["lost"] == lost


@pytest.mark.parametrize("seed", [6, 7])
def test_ten_percent_corrupt_bytes_keeps_every_intact_message(tmp_path, seed):
    rec = synthetic_record(seed, 20.0)
    tlog = tmp_path / "noisy.tlog"
    cfg = BridgeConfig(streams=boomerang(), baud=None, seed=seed,
                       faults=LinkFaults(corrupt=0.10))
    air, ground = record_bridged(rec, tlog, cfg)
    tx = air.transmit
    assert tx.corrupted > 0.8 * tx.packets  # 10 % of bytes hits most 20-80 byte packets
    intact = [(f.source, f.seq, f.msgid) for f in tx.fates if f.fate == "sent"]
    got = [(e.frame.source, e.frame.msg.get_seq(), e.frame.msg.get_msgId())
           for e in read_tlog(tlog).entries]
    assert got == intact  # every intact message, in order, and nothing else
    expected = _lost_between(air)
    for src, n in expected.items():
        assert ground.sources[f"{src[0]}/{src[1]}"]["lost"] == n
        assert ground.sources[f"{src[0]}/{src[1]}"]["received"] == sum(
            1 for s, _, _ in intact if s == src)
    assert ground.scan["rejected"] > 0 and ground.scan["junk_bytes"] > 0


def test_truncated_tlog_is_read_to_the_last_good_message(tmp_path):
    rec = synthetic_record(8, 3.0)
    tlog = tmp_path / "full.tlog"
    record_bridged(rec, tlog, BridgeConfig(baud=115200))
    full = read_tlog(tlog)
    data = tlog.read_bytes()
    ends = np.cumsum([8 + len(e.frame.raw) for e in full.entries])
    assert ends[-1] == len(data) and full.truncated_bytes == 0
    for cut in (len(data) - 1, int(ends[-40]) + 5, int(ends[-200]) + 9, int(ends[100]) + 30):
        part = tmp_path / f"cut{cut}.tlog"
        part.write_bytes(data[:cut])
        got = read_tlog(part)
        complete = int(np.searchsorted(ends, cut, side="right"))
        assert len(got.entries) == complete
        assert got.truncated_bytes == cut - ends[complete - 1]
        assert any("could not be read" in n for n in got.notes)
        out = convert_tlog(part)
        assert out.meta.extra["bridge"]["truncated_bytes"] == got.truncated_bytes
    # damage in the middle: the reader skips it and goes on
    bad = bytearray(data)
    bad[int(ends[50]) + 3:int(ends[50]) + 20] = b"\x00" * 17
    (tmp_path / "bad.tlog").write_bytes(bytes(bad))
    got = read_tlog(tmp_path / "bad.tlog")
    assert len(got.entries) == len(full.entries) - 1
    assert got.skipped_bytes == ends[51] - ends[50]


@pytest.mark.parametrize("align", ["timesync", "xcorr"])
@pytest.mark.parametrize("seed,clocks", [(9, (0.84, 150e-6, 2.31, -80e-6)),
                                         (10, (3.7, -220e-6, 0.15, 60e-6))])
def test_separately_clocked_recorders_are_aligned(tmp_path, align, seed, clocks):
    rec = synthetic_record(seed, 30.0)
    tlog = tmp_path / "three.tlog"
    streams = boomerang(*clocks)
    record_bridged(rec, tlog, BridgeConfig(streams=streams, baud=115200, seed=seed))
    out = convert_tlog(tlog, align=align)
    found = out.meta.extra["bridge"]["alignment"]
    truth = {f"{s.sysid}/{s.compid}": (s.clock_offset, s.clock_drift) for s in streams}
    for name, (offset, drift) in truth.items():
        if align == "timesync":
            # SYSTEM_TIME carries the recorder clock in whole ms
            assert found[name]["offset_s"] == pytest.approx(offset, abs=1e-3)
            assert found[name]["drift_ppm"] == pytest.approx(drift * 1e6, abs=10)
        else:
            # least squares on smooth 20-50 Hz signals: well below a sample interval;
            # 20 ppm over 30 s is 0.6 ms of clock error at the end
            assert found[name]["offset_s"] == pytest.approx(offset, abs=1e-3)
            assert found[name]["drift_ppm"] == pytest.approx(drift * 1e6, abs=20)
    # the pilot inputs (input recorder) land on the IMU clock: de matches the truth
    inside = (out.time > 1.0) & (out.time < 28.0)
    assert out.meta.extra["bridge"]["sources"]["de"].startswith("1/25")
    de = np.interp(out.time, rec.time, rec["de"])
    tol = _interp_bound(rec, "de", 0.02) + ServoMap().resolution("de") + 2e-3 * np.max(
        np.abs(np.gradient(rec["de"], rec.time)))
    assert np.max(np.abs(out["de"] - de)[inside]) <= tol


def test_udp_loopback_end_to_end(tmp_path):
    rec = synthetic_record(11, 5.0)
    tlog = tmp_path / "udp.tlog"
    air, ground = record_bridged(rec, tlog, BridgeConfig(baud=None), transport="udp")
    assert ground.scan["frames"] == air.transmit.packets
    out = convert_tlog(tlog)
    k = np.searchsorted(rec.time, out.time)
    np.testing.assert_allclose(out["q"], rec["q"][k], rtol=1e-6, atol=1e-7)


def test_command_line_serve_record_convert(tmp_path):
    """The three commands as a user runs them: recorder on loopback UDP, bridge, convert."""
    rec = synthetic_record(12, 4.0)
    rec.write(tmp_path / "flight.parquet")
    flightid = str(BIN / "flightid")
    probe = UdpLink(("127.0.0.1", 0), listen=True)  # a free port for the recorder
    port = probe.local_address[1]
    probe.close()
    recorder = subprocess.Popen(
        [flightid, "bridge", "record", "--udp", f"127.0.0.1:{port}", "-o",
         str(tmp_path / "flight.tlog"), "--idle-timeout", "2"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert recorder.stdout.readline().startswith("recording")  # bound and listening
        served = subprocess.run(
            [flightid, "bridge", "serve", str(tmp_path / "flight.parquet"), "--udp",
             f"127.0.0.1:{port}", "--baud", "115200", "--faults", "drop=0.1", "--seed", "2"],
            capture_output=True, text=True, timeout=60)
        assert served.returncode == 0, served.stderr
        assert "dropped" in served.stdout
        out, err = recorder.communicate(timeout=60)
    finally:
        if recorder.poll() is None:
            recorder.kill()
    assert recorder.returncode == 0, err
    assert "lost" in out
    done = subprocess.run([flightid, "convert", str(tmp_path / "flight.tlog"),
                           str(tmp_path / "back.parquet")], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    assert "source 1/1" in done.stdout
    bad = subprocess.run([flightid, "bridge", "serve", str(tmp_path / "flight.parquet"),
                          "--udp", "127.0.0.1:9", "--faults", "drop=2"],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode != 0 and "probability" in bad.stderr


def test_uart_model_latency_jitter_and_overflow():
    """The transmitter's timing model: 10 bits per byte, latency + Gaussian jitter, FIFO."""
    sink = FdLink(os.open(os.devnull, os.O_WRONLY))
    baud, n, size = 57600, 4000, 40
    tx = Transmitter(sink, LinkFaults(latency=0.05, jitter=0.004), baud, seed=13)
    tx.start()
    for k in range(n):  # 100 packets/s of 40 bytes: 4000 B/s < 5760 B/s
        tx.send(bytes(size), k / 100.0, (1, 1), k % 256, 0)
    tx.close()
    sink.close()
    t = np.array([f.t for f in tx.report.fates])
    arrive = np.array([f.arrive for f in tx.report.fates])
    assert np.all(np.diff(arrive) >= 0)  # a serial line keeps the order
    delay = arrive - t - size * 10 / baud
    # mean and spread of the injected delay; 5 standard errors
    assert np.mean(delay) == pytest.approx(0.05, abs=5 * 0.004 / np.sqrt(n) + 1e-4)
    assert np.std(delay) == pytest.approx(0.004, rel=0.1)
    assert tx.report.overflow == 0

    # offered twice what 9600 baud carries: the buffer fills and the excess is lost
    sink = FdLink(os.open(os.devnull, os.O_WRONLY))
    tx = Transmitter(sink, LinkFaults(), 9600, seed=1, buffer_bytes=1024)
    tx.start()
    for k in range(2000):
        tx.send(bytes(96), k / 100.0, (1, 1), k % 256, 0)  # 9600 B/s offered, 960 carried
    tx.close()
    sink.close()
    sent = [f for f in tx.report.fates if f.fate == "sent"]
    assert tx.report.overflow > 0
    carried = len(sent) * 96 / (sent[-1].arrive - sent[0].t)
    assert carried == pytest.approx(960, rel=0.02)
