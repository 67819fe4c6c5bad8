"""Recorder streams and the link budget: which message goes out how often.

A stream is one onboard recorder (as on the Monash Boomerang 60 UAV, c. 2008: the IMU
logger, the pilot-input recorder, the secondary recorder), with its own MAVLink
system/component id and its own clock (offset and drift against the simulation clock). All
streams share one link. A UART sends 10 bits per byte (start, 8 data, stop), so a link of
B baud carries B/10 bytes/s; the schedule grants each message a rate that is the source
rate divided by an integer, and when the requested rates do not fit in ``utilization *
B/10`` it reduces rates one divisor step at a time: first the redundant messages
(HIL_SENSOR, HIL_STATE_QUATERNION repeat the others), down to nothing; then the message
with the largest byte rate weighted by 2^importance, down to its floor (1 Hz by default);
at the floors, the least important message is dropped.
Frame sizes are the largest MAVLink 2 frames (payload truncation only helps).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from flightid.sim.bridge.air.signing import SIGNATURE_BYTES
from flightid.sim.bridge.messages import TELEMETRY, frame_size

#: default importance of each message (0 = never reduced; larger = reduced first)
PRIORITY = {
    "HEARTBEAT": 0,
    "SYSTEM_TIME": 0,
    "HIGHRES_IMU": 1,
    "SERVO_OUTPUT_RAW": 1,
    "ATTITUDE": 2,
    "AOA_SSA": 2,
    "VFR_HUD": 3,
    "GPS_RAW_INT": 3,
    "HIL_STATE_QUATERNION": 5,  # repeats ATTITUDE + GPS
    "HIL_SENSOR": 6,  # repeats HIGHRES_IMU
}
#: importance from which a message only repeats others (reduced first, down to nothing)
REDUNDANT = 5


@dataclass(frozen=True)
class MessageRate:
    """A message a stream sends, at ``rate`` (Hz) if the link allows, never below ``floor``."""

    name: str
    rate: float
    priority: int | None = None  # None: PRIORITY[name]
    floor: float | None = None  # None: 1 Hz, or 0 for redundant messages

    def importance(self) -> int:
        """Priority class (0 = never reduced, larger = reduced first)."""
        return PRIORITY.get(self.name, 4) if self.priority is None else self.priority

    def floor_for(self) -> float:
        """Lowest rate (Hz) before the message is dropped."""
        if self.floor is not None:
            return self.floor
        return 0.0 if self.importance() >= REDUNDANT else min(1.0, self.rate)


@dataclass(frozen=True)
class StreamSpec:
    """One onboard recorder: ids, messages and clock (t_local = offset + (1 + drift) t)."""

    name: str
    sysid: int = 1
    compid: int = 1
    messages: tuple[MessageRate, ...] = ()
    clock_offset: float = 0.0  # s, recorder clock at sim time 0 (>= 0: powered on before)
    clock_drift: float = 0.0  # fractional rate error, e.g. 150e-6
    mav_type: int = 1  # MAV_TYPE_FIXED_WING

    def __post_init__(self) -> None:
        for m in self.messages:
            if m.name not in TELEMETRY:
                raise ValueError(
                    f"stream {self.name!r}: message {m.name!r} is not one the bridge sends "
                    f"({', '.join(TELEMETRY)})"
                )
            if m.rate <= 0:
                raise ValueError(f"stream {self.name!r}: {m.name} rate must be > 0 Hz")
        if self.clock_offset < 0:
            raise ValueError(
                f"stream {self.name!r}: clock_offset {self.clock_offset} s < 0; a recorder "
                "clock counts from its own power-on, before the flight starts"
            )

    def local_time(self, t: float) -> float:
        """The recorder's clock (s) at sim time t (s)."""
        return self.clock_offset + (1.0 + self.clock_drift) * t


def _rates(**rates: float) -> tuple[MessageRate, ...]:
    return tuple(MessageRate(n.upper(), r) for n, r in rates.items())


def single_stream() -> tuple[StreamSpec, ...]:
    """One autopilot-like stream on the simulation clock with every telemetry message.

    Returns
    -------
    tuple of StreamSpec
        The single stream.
    """
    return (
        StreamSpec(
            "autopilot",
            messages=_rates(
                heartbeat=1, system_time=1, highres_imu=100, attitude=100, aoa_ssa=100,
                vfr_hud=20, servo_output_raw=100, gps_raw_int=5, hil_state_quaternion=50,
                hil_sensor=100,
            ),
        ),
    )


def boomerang(
    input_offset: float = 0.84, input_drift: float = 150e-6,
    secondary_offset: float = 2.31, secondary_drift: float = -80e-6,
) -> tuple[StreamSpec, ...]:
    """The three recorders of the Monash Boomerang 60 UAV (c. 2008), each with its own clock.

    IMU logger (reference clock), FMA Co-Pilot servo recorder, Eagle Tree secondary
    recorder. The clock numbers are illustrative, not from the paper (it says nothing about
    clocks).

    Parameters
    ----------
    input_offset : float, optional
        Servo recorder's clock offset, s. Default 0.84.
    input_drift : float, optional
        Servo recorder's clock drift, fraction (s/s). Default 150e-6.
    secondary_offset : float, optional
        Secondary recorder's clock offset, s. Default 2.31.
    secondary_drift : float, optional
        Secondary recorder's clock drift, fraction (s/s). Default -80e-6.

    Returns
    -------
    tuple of StreamSpec
        The IMU, input and secondary recorder streams.
    """
    return (
        StreamSpec(
            "imu", 1, 1,
            _rates(heartbeat=1, system_time=1, highres_imu=100, attitude=50, aoa_ssa=50,
                   vfr_hud=10, gps_raw_int=1),
        ),
        StreamSpec(
            "input_recorder", 1, 25,
            _rates(heartbeat=1, system_time=1, servo_output_raw=50),
            input_offset, input_drift, mav_type=0,
        ),
        StreamSpec(
            "secondary_recorder", 1, 26,
            _rates(heartbeat=1, system_time=1, servo_output_raw=20, vfr_hud=10, attitude=20),
            secondary_offset, secondary_drift, mav_type=0,
        ),
    )


PROFILES = {"single": single_stream, "boomerang": boomerang}


@dataclass
class Grant:
    """The rate a message of a stream actually gets."""

    stream: str
    name: str
    requested: float  # Hz
    divisor: int  # sent every ``divisor`` source samples; 0 = not sent
    source_rate: float  # Hz
    frame_bytes: int
    importance: int
    nominal: int = 1  # the divisor closest to the requested rate

    @property
    def rate(self) -> float:
        """Granted rate (Hz)."""
        return self.source_rate / self.divisor if self.divisor else 0.0

    @property
    def bytes_per_s(self) -> float:
        """Link load of this message (bytes/s)."""
        return self.rate * self.frame_bytes

    @property
    def status(self) -> str:
        """'full', 'reduced' or 'dropped'."""
        if not self.divisor:
            return "dropped"
        return "full" if self.divisor <= self.nominal else "reduced"


@dataclass
class Schedule:
    """Granted rates for every stream and message, and the budget they were fitted to."""

    grants: list[Grant]
    source_rate: float
    baud: int | None
    utilization: float
    notes: list[str] = field(default_factory=list)

    @property
    def capacity(self) -> float:
        """Usable link capacity (bytes/s); infinite without a baud rate."""
        return float("inf") if self.baud is None else self.utilization * self.baud / 10.0

    @property
    def load(self) -> float:
        """Scheduled load (bytes/s)."""
        return sum(g.bytes_per_s for g in self.grants)

    def due(self, tick: int) -> list[Grant]:
        """Grants that send at source sample number ``tick``, most important first."""
        return [g for g in self.grants if g.divisor and tick % g.divisor == 0]

    def as_dict(self) -> dict:
        """Plain-data form for reports and record metadata."""
        return {
            "source_rate_hz": self.source_rate,
            "baud": self.baud,
            "capacity_bytes_per_s": None if self.baud is None else self.capacity,
            "load_bytes_per_s": self.load,
            "messages": [
                {"stream": g.stream, "message": g.name, "requested_hz": g.requested,
                 "granted_hz": g.rate, "bytes_per_s": g.bytes_per_s, "status": g.status}
                for g in self.grants
            ],
            "notes": list(self.notes),
        }

    def table(self) -> str:
        """Human-readable table of requested vs granted rates."""
        cap = "unlimited" if self.baud is None else f"{self.capacity:.0f} B/s"
        lines = [f"link {self.baud or '-'} baud, usable {cap}, scheduled {self.load:.0f} B/s"]
        lines.append(f"{'stream':<20}{'message':<22}{'asked Hz':>9}{'got Hz':>9}{'B/s':>8}  status")
        for g in self.grants:
            lines.append(
                f"{g.stream:<20}{g.name:<22}{g.requested:>9.2f}{g.rate:>9.2f}"
                f"{g.bytes_per_s:>8.0f}  {g.status}"
            )
        return "\n".join(lines + self.notes)


def plan_schedule(
    streams: tuple[StreamSpec, ...], source_rate: float, baud: int | None,
    utilization: float = 0.85, signed: bool = False,
) -> Schedule:
    """Fit the streams' requested rates into the link.

    A message can go at source_rate / k for integer k. Importance-0 messages are kept at
    their rate; the others are reduced least important first, the largest byte rate first
    within a class.

    Parameters
    ----------
    streams : tuple of StreamSpec
        The streams and their requested message rates.
    source_rate : float
        Rate of the samples the bridge gets, Hz.
    baud : int or None
        Link capacity, bits/s; None = unlimited.
    utilization : float, optional
        Fraction of the link capacity to use, in (0, 1]. Default 0.85.
    signed : bool, optional
        Every frame carries the 13-byte MAVLink 2 signature. Default False.

    Returns
    -------
    Schedule
        The granted rates, load and notes on what was changed.

    Raises
    ------
    ValueError
        For a source rate, baud or utilization out of range.
    """
    if source_rate <= 0:
        raise ValueError(f"source rate must be > 0 Hz, got {source_rate}")
    if baud is not None and baud <= 0:
        raise ValueError(f"baud must be > 0, got {baud}")
    if not 0 < utilization <= 1:
        raise ValueError(f"utilization must be in (0, 1], got {utilization}")
    grants, notes = [], []
    for st in streams:
        for m in st.messages:
            k = max(1, round(source_rate / m.rate))
            g = Grant(st.name, m.name, m.rate, k, source_rate,
                      frame_size(m.name) + (SIGNATURE_BYTES if signed else 0),
                      m.importance(), k)
            if abs(g.rate - m.rate) > 1e-9 * m.rate and m.rate <= source_rate:
                notes.append(f"{st.name}/{m.name}: {m.rate:g} Hz is not source/k; "
                             f"sending at {g.rate:g} Hz")
            if m.rate > source_rate:
                notes.append(f"{st.name}/{m.name}: {m.rate:g} Hz exceeds the source rate "
                             f"{source_rate:g} Hz")
            grants.append(g)
    sched = Schedule(grants, source_rate, baud, utilization, notes)
    floors = {(st.name, m.name): m.floor_for() for st in streams for m in st.messages}
    while sched.load > sched.capacity:
        movable = [g for g in grants if g.importance > 0 and g.divisor]
        if not movable:
            notes.append(
                f"essential messages alone need {sched.load:.0f} B/s > {sched.capacity:.0f} "
                "B/s; the link will overflow"
            )
            break
        redundant = [g for g in movable if g.importance >= REDUNDANT]
        above = [g for g in movable
                 if source_rate / (g.divisor + 1) >= floors[(g.stream, g.name)]]
        if redundant:  # repeats of other messages go first, down to nothing
            g = max(redundant, key=lambda g: (g.importance, g.bytes_per_s))
            nxt = g.divisor + 1
            g.divisor = nxt if source_rate / nxt >= max(floors[(g.stream, g.name)], 0.05) else 0
        elif above:  # then everyone, weighted by importance (each class counts double)
            g = max(above, key=lambda g: g.bytes_per_s * 2.0**g.importance)
            g.divisor += 1
        else:  # all at their floors: drop the least important
            g = max(movable, key=lambda g: (g.importance, g.bytes_per_s))
            g.divisor = 0
    for g in grants:
        if g.status == "dropped":
            notes.append(f"{g.stream}/{g.name}: dropped to fit the link")
    return sched


def with_rates(stream: StreamSpec, **rates: float) -> StreamSpec:
    """A copy of a stream with some message rates changed, e.g. ``highres_imu=50``.

    Parameters
    ----------
    stream : StreamSpec
        The stream to copy.
    **rates : float
        Message name (any case) to rate, Hz; a message not in the stream is added.

    Returns
    -------
    StreamSpec
        The changed copy.
    """
    by_name = {n.upper(): r for n, r in rates.items()}
    msgs = tuple(replace(m, rate=by_name.pop(m.name, m.rate)) for m in stream.messages)
    msgs += tuple(MessageRate(n, r) for n, r in by_name.items())
    return replace(stream, messages=msgs)
