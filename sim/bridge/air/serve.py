"""The air side of the recorder bridge: a flight as MAVLink 2 bytes on a real link.

The bridge makes a simulated aircraft look like the instrumented Boomerang 60 of the
Monash paper (c. 2008) to the ground: one or more recorders (``schedule.StreamSpec``),
each with its own system/component id, sequence numbers and clock, send HEARTBEAT,
SYSTEM_TIME, HIGHRES_IMU, ATTITUDE, AOA_SSA, VFR_HUD, SERVO_OUTPUT_RAW, GPS_RAW_INT,
HIL_SENSOR and HIL_STATE_QUATERNION (``messages``) at rates that fit the link budget, through
injectable faults (``link``). Time stamps come from the simulation clock mapped
through each recorder's clock (offset, drift); SYSTEM_TIME pairs the recorder clock
with the common (GPS) time.

Sources: a FlightRecord replayed sample by sample (:func:`serve_record`), or a stepping
simulation flown by controls received over the same link (``closed_loop.serve_simulation``),
in lock-step (one step per control message) or in real time (latest control held).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from flightid.record import FlightRecord
from flightid.sim.bridge.air.schedule import Schedule, StreamSpec, plan_schedule, single_stream
from flightid.sim.bridge.air.signing import SenderFilter, setup_outgoing
from flightid.sim.bridge.link import Link, LinkFaults, Transmitter
from flightid.sim.bridge.messages import (
    EncodeContext,
    GeoOrigin,
    ServoMap,
    TelemetryState,
    encode,
)

#: unix time of sim time 0 unless told otherwise (June 2008, the Boomerang 60's flight tests)
DEFAULT_EPOCH = 1_213_488_000.0


@dataclass
class BridgeConfig:
    """Everything the air side needs besides the source and the link."""

    streams: tuple[StreamSpec, ...] = field(default_factory=single_stream)
    baud: int | None = 57600  # bits/s of the link being emulated; None = unlimited
    faults: LinkFaults = field(default_factory=LinkFaults)
    seed: int = 0
    realtime: bool = False
    servo_map: ServoMap = field(default_factory=ServoMap)
    origin: GeoOrigin = field(default_factory=GeoOrigin)
    epoch_unix: float = DEFAULT_EPOCH
    utilization: float = 0.85
    buffer_bytes: int = 4096
    ground_system: int = 255  # who may send controls (the ground station's system id)
    ground_component: int | None = None  # its component id; None = any component
    signing_key: bytes | None = None  # 32 bytes: sign telemetry, accept signed controls only
    # file keeping the last signing timestamp of each stream across runs (signing.state_path)
    signing_state: str | Path | None = None

    def sender_filter(self) -> SenderFilter:
        """The check every received packet passes before it may move a surface."""
        return SenderFilter(self.ground_system, self.ground_component, self.signing_key,
                            state=self.signing_state)


@dataclass
class BridgeReport:
    """What the air side sent: schedule, per-source packet counts, faults applied."""

    schedule: Schedule
    transmit: Any  # link.TransmitReport
    samples: int = 0
    duration: float = 0.0
    servo_saturated: int = 0
    controls_received: int = 0
    faults: LinkFaults = field(default_factory=LinkFaults)
    refused: dict[str, int] = field(default_factory=dict)  # packets refused, by reason
    ended: str = ""  # why a flight in the loop ended before its last step ("" = it did not)

    def per_source(self) -> dict[tuple[int, int], dict[str, int]]:
        """Per (sysid, compid): packets produced and their fates."""
        out: dict[tuple[int, int], dict[str, int]] = {}
        for f in self.transmit.fates:
            d = out.setdefault(f.source, {"packets": 0, "sent": 0, "corrupted": 0,
                                          "dropped": 0, "overflow": 0})
            d["packets"] += 1
            d[f.fate] += 1
        return out

    def as_dict(self) -> dict:
        """Plain-data summary."""
        return {
            "samples": self.samples,
            "duration_s": self.duration,
            "servo_saturated": self.servo_saturated,
            "controls_received": self.controls_received,
            "packets_refused": dict(self.refused),
            "ended_early": self.ended,
            "faults": vars(self.faults),
            "transmit": self.transmit.as_dict(),
            "schedule": self.schedule.as_dict(),
        }

    def summary(self) -> str:
        """Readable summary: the schedule table and the packet fates."""
        tx = self.transmit
        return (
            f"{self.schedule.table()}\n"
            f"sent {self.samples} samples ({self.duration:.2f} s): {tx.packets} packets, "
            f"{tx.sent_intact} intact, {tx.corrupted} corrupted, {tx.dropped} dropped, "
            f"{tx.overflow} lost to UART overflow; {self.servo_saturated} servo values clipped"
        )


class AirSide:
    """Turns samples into scheduled MAVLink packets and hands them to a transmitter."""

    def __init__(self, config: BridgeConfig, source_rate: float, link: Link,
                 keep_fates: bool = True) -> None:
        self.config = config
        self.schedule = plan_schedule(config.streams, source_rate, config.baud,
                                      config.utilization, signed=config.signing_key is not None)
        self.tx = Transmitter(link, config.faults, config.baud, config.seed,
                              config.realtime, config.buffer_bytes, keep_fates)
        self.link = link
        self.mavs = {s.name: mavlink2.MAVLink(None, s.sysid, s.compid) for s in config.streams}
        if config.signing_key is not None:
            for mav in self.mavs.values():
                setup_outgoing(mav, config.signing_key)
        epoch = int(round(config.epoch_unix * 1e6))
        self.ctx = {s.name: EncodeContext(config.servo_map, epoch, s.mav_type)
                    for s in config.streams}
        self.streams = {s.name: s for s in config.streams}
        self.state = TelemetryState(config.origin)
        self.samples = 0
        self.last_t = 0.0
        self.first_t: float | None = None

    def emit(self, tick: int, t: float, channels: dict[str, float]) -> int:
        """Send the messages due at source sample ``tick`` (sim time t, s); returns count."""
        if self.first_t is None:
            self.first_t = t
            self.tx.start(t)
        sample = self.state.sample(t, channels)
        n = 0
        for g in self.schedule.due(tick):
            stream = self.streams[g.stream]
            mav = self.mavs[g.stream]
            msg = encode(g.name, sample, t, stream.local_time(t), self.ctx[g.stream])
            packet = msg.pack(mav)
            self.tx.send(packet, t, (stream.sysid, stream.compid), mav.seq, msg.get_msgId())
            mav.seq = (mav.seq + 1) % 256
            n += 1
        self.samples += 1
        self.last_t = t
        return n

    def heartbeat(self, t: float) -> None:
        """A HEARTBEAT from every stream at sim time t (s), outside the schedule."""
        if self.first_t is None:
            self.tx.start(t)
        for stream in self.streams.values():
            mav = self.mavs[stream.name]
            msg = encode("HEARTBEAT", {}, t, stream.local_time(t), self.ctx[stream.name])
            self.tx.send(msg.pack(mav), t, (stream.sysid, stream.compid), mav.seq, 0)
            mav.seq = (mav.seq + 1) % 256

    def finish(self) -> BridgeReport:
        """Flush the link and return the report."""
        self.tx.close()
        return BridgeReport(
            self.schedule, self.tx.report, self.samples,
            self.last_t - (self.first_t or 0.0),
            sum(c.saturated for c in self.ctx.values()), faults=self.config.faults,
        )


def source_rate_of(record: FlightRecord) -> float:
    """Sample rate of a uniformly sampled record.

    Parameters
    ----------
    record : FlightRecord
        The flight; at least two samples.

    Returns
    -------
    float
        Sample rate, Hz.

    Raises
    ------
    ValueError
        If the record has fewer than two samples or is not uniformly sampled.
    """
    if len(record) < 2:
        raise ValueError("a record needs at least two samples to be streamed")
    dt = np.diff(record.time)
    if np.ptp(dt) > 1e-6 * np.mean(dt) + 1e-9:
        raise ValueError(
            f"record is not uniformly sampled (dt from {dt.min():.6g} to {dt.max():.6g} s); "
            "resample it before streaming"
        )
    return 1.0 / float(np.mean(dt))


def serve_record(record: FlightRecord, link: Link, config: BridgeConfig | None = None,
                 keep_fates: bool = True) -> BridgeReport:
    """Stream a uniformly sampled record over ``link``; real time if ``config.realtime``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniformly sampled.
    link : Link
        The link to send on.
    config : BridgeConfig, optional
        Bridge settings; default ``BridgeConfig()``.
    keep_fates : bool, optional
        Keep each packet's fate (sent, dropped, corrupted...) in the transmit report.
        Default True.

    Returns
    -------
    BridgeReport
        Schedule, per-source packet counts and the faults applied.
    """
    config = config or BridgeConfig()
    air = AirSide(config, source_rate_of(record), link, keep_fates)
    names = list(record.channels)
    data = np.column_stack([record[n] for n in names]) if names else np.zeros((len(record), 0))
    t0 = float(record.time[0])
    for k, t in enumerate(record.time):
        if config.realtime and air.first_t is not None:
            # keep the producer near real time so that the queue stays short
            lead = air.tx.wall_time(float(t)) - time.monotonic()
            if lead > 0.05:
                time.sleep(lead - 0.05)
        air.emit(k, float(t) - t0, dict(zip(names, data[k], strict=True)))
    return air.finish()
