"""The air side in the loop: :func:`serve_simulation` flies a stepping simulation by the
controls received over the link, in lock-step or in real time (latest control held).

Controls accepted (canonical signs, ``ServoMap`` limits):
- HIL_ACTUATOR_CONTROLS / SET_ACTUATOR_CONTROL_TARGET: controls[0..3] = roll, pitch,
  yaw (-1..1, positive = right roll, nose up, nose right moment) and throttle (0..1):
  da = -roll * da_max, de = -pitch * de_max, dr = -yaw * dr_max;
- MANUAL_CONTROL: x = pitch stick (+1000 forward: nose down, de = x/1000 * de_max),
  y = roll stick (+ right: da = -y/1000 * da_max), z = throttle (0..1000),
  r = yaw (+ right pedal: dr = -r/1000 * dr_max);
- RC_CHANNELS_OVERRIDE: surface PWM on the SERVO_OUTPUT_RAW channels (same mapping;
  0 and UINT16_MAX leave a channel unchanged).
"""

from __future__ import annotations

import math
import time
from typing import Protocol

from flightid.sim.bridge.air.serve import AirSide, BridgeConfig, BridgeReport
from flightid.sim.bridge.air.signing import SenderFilter
from flightid.sim.bridge.frames import FrameScanner
from flightid.sim.bridge.link import Link
from flightid.sim.bridge.messages import ServoMap

#: messages that carry controls to the bridge
CONTROL_MESSAGES = (
    "HIL_ACTUATOR_CONTROLS",
    "SET_ACTUATOR_CONTROL_TARGET",
    "MANUAL_CONTROL",
    "RC_CHANNELS_OVERRIDE",
)


def controls_from_message(msg, servo_map: ServoMap) -> dict[str, float] | None:
    """Canonical controls from a control message, None if it is not one.

    Parameters
    ----------
    msg : pymavlink message
        HIL_ACTUATOR_CONTROLS, SET_ACTUATOR_CONTROL_TARGET (group 0), MANUAL_CONTROL or
        RC_CHANNELS_OVERRIDE.
    servo_map : ServoMap
        Surface limits and PWM mapping.

    Returns
    -------
    dict of str to float or None
        Surface deflections (rad) and throttle (0..1) by channel name.
    """
    kind = msg.get_type()
    m = servo_map
    if kind in ("HIL_ACTUATOR_CONTROLS", "SET_ACTUATOR_CONTROL_TARGET"):
        if kind == "SET_ACTUATOR_CONTROL_TARGET" and msg.group_mlx != 0:
            return None
        roll, pitch, yaw, thr = (float(c) for c in msg.controls[:4])
        return {"da": -roll * m.da_max, "de": -pitch * m.de_max, "dr": -yaw * m.dr_max,
                "throttle": min(max(thr, 0.0), 1.0)}
    if kind == "MANUAL_CONTROL":
        return {"de": msg.x / 1000.0 * m.de_max, "da": -msg.y / 1000.0 * m.da_max,
                "dr": -msg.r / 1000.0 * m.dr_max, "throttle": min(max(msg.z / 1000.0, 0.0), 1.0)}
    if kind == "RC_CHANNELS_OVERRIDE":
        out = {}
        for ch, num in m.channels().items():
            pwm = getattr(msg, f"chan{num}_raw")
            if pwm not in (0, 65535):
                out[ch] = m.from_pwm(ch, pwm)
        return out
    return None


class SteppingSimulation(Protocol):
    """What the bridge needs from a simulation: a fixed step and one step per call."""

    dt: float

    def step(self, controls: dict[str, float]) -> dict[str, float]:
        """Advance one step with the given controls; return canonical channels."""
        ...


class _ControlReader:
    """Parses control messages arriving on the link (uplink: no faults injected); only
    packets that pass ``senders`` (the ground station's ids, its signature) count."""

    def __init__(self, link: Link, servo_map: ServoMap, senders: SenderFilter) -> None:
        self.link, self.servo_map, self.senders = link, servo_map, senders
        self.scanner = FrameScanner()
        self.received = 0
        self.heard = False  # any intact message from the ground yet
        self.closed = False
        self._pending: list[dict[str, float]] = []

    def poll(self, timeout: float) -> list[dict[str, float]]:
        """Controls received within ``timeout`` s (may be empty)."""
        if self._pending:
            out, self._pending = self._pending, []
            return out
        data = self.link.read(timeout)
        if data is None:
            self.closed = True
            return []
        frames = self.scanner.feed(data)
        if self.link.datagrams:
            frames += self.scanner.flush()
        out = []
        frames = [fr for fr in frames if self.senders.accept(fr.raw, fr.source)]
        self.heard = self.heard or bool(frames)
        for fr in frames:
            c = controls_from_message(fr.msg, self.servo_map)
            if c is not None and not all(math.isfinite(v) for v in c.values()):
                self.senders.refuse("not finite")  # NaN is not "hold the trim"
            elif c is not None:
                out.append(c)
        self.received += len(out)
        return out

    def next(self, timeout: float) -> dict[str, float] | None:
        """The next control message, waiting at most ``timeout`` s in total."""
        end = time.monotonic() + timeout
        while not self.closed:
            got = self.poll(max(0.0, min(0.05, end - time.monotonic())))
            if got:
                self._pending = got[1:]
                return got[0]
            if time.monotonic() >= end:
                return None
        return None


class FlightCoreAdapter:
    """The flight core (``flightid.sim.flight.simulation.Simulation``) flown by absolute controls.

    The link carries absolute surface positions (rad) and throttle (0..1), as an onboard
    computer commands them; the flight core takes increments on its trim. Increments
    below 1e-6 (rad, or throttle fraction; some 30 float32 steps of a normalised command)
    are taken as zero, so the trim commands are kept exactly when the ground sends the
    trim values back through float32 fields.
    """

    def __init__(self, sim, trim) -> None:
        self.sim, self.trim = sim, trim
        self.dt = 1.0 / sim.rate_hz
        self._trim = {"de": trim.elevator, "da": trim.aileron, "dr": trim.rudder,
                      "throttle": trim.throttle}

    def increments(self, controls: dict[str, float]) -> dict[str, float]:
        """Absolute controls -> increments on trim (only the controls given)."""
        out = {}
        for c, v in controls.items():
            inc = v - self._trim[c]
            out[c] = inc if abs(inc) > 1e-6 * max(1.0, abs(self._trim[c])) else 0.0
        return out

    def reset(self, controls: dict[str, float] | None = None) -> dict[str, float]:
        """Back to trim (t = 0) with absolute controls; the first sample."""
        return self.sim.reset(self.trim, self.increments(controls or {}))

    def step(self, controls: dict[str, float]) -> dict[str, float]:
        """One step with absolute controls."""
        return self.sim.step(self.increments(controls))


def serve_simulation(
    sim: SteppingSimulation, initial: dict[str, float], link: Link,
    config: BridgeConfig | None = None, *, steps: int, lockstep: bool = True,
    timeout: float = 5.0, controls: dict[str, float] | None = None,
) -> tuple[BridgeReport, list[dict[str, float]]]:
    """Fly ``sim`` with controls received over ``link``, telemetry going back the same way.

    The flight starts when the ground station first speaks (a HEARTBEAT, as MAVLink ground
    stations send at 1 Hz); until then the bridge sends heartbeats. Lock-step: after each
    telemetry sample the bridge waits for one control message, applies it for exactly one
    step and sends the next sample: the control answering the sample at t_k is the surface
    position at t_(k+1) (the flight core's ``step`` semantics), so a ground station sends
    u(t_k + dt). Real time: the simulation steps on the wall clock and uses the latest control
    received. Lock-step needs a loss-free downlink, so link faults that lose packets are
    refused.

    Parameters
    ----------
    sim : SteppingSimulation
        The simulation to fly; its step ``dt`` (s) sets the telemetry rate.
    initial : dict of str to float
        The channels at the start (time 0), SI.
    link : Link
        The link to the ground station.
    config : BridgeConfig, optional
        Bridge settings; default ``BridgeConfig()``.
    steps : int
        Number of simulation steps.
    lockstep : bool, optional
        Lock-step (default) or real time.
    timeout : float, optional
        Longest wait for a control message in lock-step, s. Default 5.
    controls : dict of str to float, optional
        Control values (rad, throttle 0..1) held until the first control message.

    Returns
    -------
    tuple of (BridgeReport, list of dict)
        The report and the channel history (one dict of SI channels per step).

    Raises
    ------
    ValueError
        For lock-step with packet-losing faults, or a step that is not > 0 s.
    """
    config = config or BridgeConfig()
    if lockstep and config.faults.damaging:
        raise ValueError(
            "lock-step needs every step's telemetry to arrive; drop/corrupt faults would "
            "stall the client (use real time for a lossy link)"
        )
    if not math.isfinite(sim.dt) or sim.dt <= 0:
        raise ValueError(f"simulation step must be > 0 s, got {sim.dt}")
    air = AirSide(config, 1.0 / sim.dt, link)
    reader = _ControlReader(link, config.servo_map, config.sender_filter())
    try:
        return _fly(sim, initial, link, config, air, reader, steps=steps, lockstep=lockstep,
                    timeout=timeout, controls=controls)
    finally:
        reader.senders.save()  # the signing timestamps seen, for the next run


def _fly(sim: SteppingSimulation, initial: dict[str, float], link: Link,
         config: BridgeConfig, air: AirSide, reader: _ControlReader, *, steps: int,
         lockstep: bool, timeout: float, controls: dict[str, float] | None,
         ) -> tuple[BridgeReport, list[dict[str, float]]]:
    """The flight of :func:`serve_simulation`, after its checks."""
    held = dict(controls or {})
    history = [dict(initial)]
    t = 0.0
    # handshake: heartbeats (2 Hz) until the ground station speaks (its HEARTBEAT, or a
    # control); only then does the flight start, so nothing is sent into an unopened port
    end = time.monotonic() + timeout
    while not reader.heard:
        air.heartbeat(0.0)
        for got in reader.poll(0.5):
            held.update(got)
        if reader.closed or time.monotonic() > end:
            air.finish()
            refused = reader.senders.rejected
            why = (f" (refused {sum(refused.values())} packet(s): "
                   f"{', '.join(f'{n} {k}' for k, n in refused.items())})" if refused else "")
            raise TimeoutError(f"no ground station answered on {getattr(link, 'name', link)} "
                               f"within {timeout} s{why}")
    air.emit(0, t, initial)
    start = time.monotonic()
    ended = ""
    for k in range(1, steps + 1):
        if lockstep:
            got = reader.next(timeout)
            if got is None:
                ended = (f"the link closed after step {k - 1} of {steps}" if reader.closed
                         else f"no control within {timeout:g} s after step {k - 1} of {steps}")
                break
            held.update(got)
        else:
            for got in reader.poll(0.0):
                held.update(got)
            lead = start + k * sim.dt - time.monotonic()
            if lead > 0:
                time.sleep(lead)
        channels = sim.step(dict(held))
        t = k * sim.dt
        history.append(dict(channels))
        air.emit(k, t, channels)
    report = air.finish()
    report.controls_received = reader.received
    report.refused = dict(reader.senders.rejected)
    report.ended = ended
    return report, history
