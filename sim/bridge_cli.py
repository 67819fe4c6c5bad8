"""Command-line glue of the recorder bridge (``flightid bridge ...``, ``flightid convert``).

Each function parses the options into library calls and prints a readable report;
errors are raised as ``typer.BadParameter`` / ``SystemExit`` with a specific message.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import typer

from flightid.sim.bridge import BridgeConfig
from flightid.sim.bridge_link import (
    Link,
    LinkFaults,
    SerialLink,
    UdpLink,
    open_pty_pair,
    parse_hostport,
)
from flightid.sim.bridge_schedule import PROFILES

RECORD_SUFFIXES = (".parquet", ".csv", ".mat")


def _config(baud: int | None, faults: str, seed: int, realtime: bool, profile: str) -> BridgeConfig:
    if profile not in PROFILES:
        raise typer.BadParameter(f"unknown profile {profile!r}; use {', '.join(PROFILES)}")
    try:
        parsed = LinkFaults.parse(faults)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--faults") from None
    return BridgeConfig(streams=PROFILES[profile](), baud=baud, faults=parsed, seed=seed,
                        realtime=realtime)


def _air_link(serial: str | None, udp: str | None, baud: int, start_delay: float):
    """Open the air side's link; returns (link, closer)."""
    if (serial is None) == (udp is None):
        raise typer.BadParameter("give exactly one of --serial PORT or --udp HOST:PORT")
    if udp is not None:
        try:
            link = UdpLink(parse_hostport(udp), listen=False)
        except ValueError as exc:
            raise typer.BadParameter(str(exc), param_hint="--udp") from None
        return link, link.close
    if serial == "pty":
        pty = open_pty_pair()
        typer.echo(f"pseudo-terminal ready: record with  flightid bridge record --serial "
                   f"{pty.slave_path} -o flight.tlog")
        if start_delay > 0:
            typer.echo(f"starting in {start_delay:g} s")
            time.sleep(start_delay)
        return pty.master_link(), pty.close
    try:
        link = SerialLink(serial, baud)
    except OSError as exc:
        raise typer.BadParameter(str(exc), param_hint="--serial") from None
    return link, link.close


def _load_source(path: str):
    """A flight record from a record file, or the measured record of a flight card
    (a .toml file or a library card name, flown with the card's own seed)."""
    from flightid.record import read

    p = Path(path)
    if p.suffix.lower() in RECORD_SUFFIXES:
        if not p.exists():
            raise typer.BadParameter(f"{path}: no such file", param_hint="CARD_OR_RECORD")
        return read(p)
    from flightid.scenarios import cards

    try:
        card = cards.load_card(cards.find_card(path))
    except cards.CardError as exc:
        raise typer.BadParameter(
            f"{exc} (expected a record {', '.join(RECORD_SUFFIXES)} or a flight card)",
            param_hint="CARD_OR_RECORD") from None
    typer.echo(f"flying card {card.name} ({card.aircraft}, {card.duration:g} s)")
    measured, _truth = cards.fly_card(card)
    return measured


def serve_cli(source: str, serial: str | None, udp: str | None, baud: int, realtime: bool,
              faults: str, seed: int, profile: str, start_delay: float,
              report: str | None) -> None:
    """``flightid bridge serve``: stream a record (or card) as MAVLink over a link."""
    from flightid.sim.bridge import serve_record

    record = _load_source(source)
    config = _config(baud if baud > 0 else None, faults, seed, realtime, profile)
    link, close = _air_link(serial, udp, baud, start_delay)
    try:
        rep = serve_record(record, link, config, keep_fates=False)
    finally:
        close()
    typer.echo(rep.summary())
    if report:
        Path(report).write_text(json.dumps(rep.as_dict(), indent=2, default=str))


def _ground_link(serial: str | None, udp: str | None, baud: int) -> Link:
    if (serial is None) == (udp is None):
        raise typer.BadParameter("give exactly one of --serial PORT or --udp HOST:PORT")
    try:
        if udp is not None:
            return UdpLink(parse_hostport(udp), listen=True)
        return SerialLink(serial, baud)
    except (OSError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from None


def record_cli(serial: str | None, udp: str | None, baud: int, output: str,
               duration: float | None, idle_timeout: float) -> None:
    """``flightid bridge record``: write every intact packet of a stream to a .tlog."""
    from flightid.sim.recorder import record_stream

    link = _ground_link(serial, udp, baud)
    typer.echo(f"recording {link.name} to {output}")
    try:
        rep = record_stream(link, output, duration=duration, idle_timeout=idle_timeout)
    except KeyboardInterrupt:
        typer.echo("interrupted")
        raise typer.Exit(1) from None
    finally:
        link.close()
    typer.echo(rep.summary())


def convert_cli(tlog: str, output: str, align: str, reference: str | None,
                rate: float | None, aircraft: str) -> None:
    """``flightid convert``: a .tlog to a flight record (.parquet or .csv)."""
    from flightid.sim.recorder import convert_tlog

    if Path(output).suffix.lower() not in (".parquet", ".csv"):
        raise typer.BadParameter(f"{output}: write .parquet or .csv", param_hint="OUTPUT")
    try:
        rec = convert_tlog(tlog, align=align, reference=reference, rate=rate, aircraft=aircraft)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="TLOG") from None
    rec.write(output)
    b = rec.meta.extra["bridge"]
    typer.echo(f"{output}: {len(rec)} samples at {rec.meta.sample_rate:g} Hz, "
               f"channels {', '.join(sorted(rec.channels))}")
    for src, loss in b["losses"].items():
        typer.echo(f"  source {src}: {loss['received']} packets, {loss['lost']} lost "
                   f"({100 * loss['loss_rate']:.2f} %)")
    for src, m in b["alignment"].items():
        if m["method"] != "reference":
            typer.echo(f"  clock {src}: offset {m['offset_s']:+.4f} s, drift "
                       f"{m['drift_ppm']:+.1f} ppm ({m['method']}, {m['via']})")
    for note in b["read_notes"]:
        typer.echo(f"  note: {note}")


def fly_cli(aircraft: str, altitude: float, speed: float, serial: str | None, udp: str | None,
            baud: int, rate: float, duration: float, lockstep: bool, timeout: float,
            profile: str, output: str | None) -> None:
    """``flightid bridge fly``: fly the JSBSim aircraft with controls from the link."""
    from flightid.record import FlightRecord
    from flightid.sim.bridge import FlightCoreAdapter, serve_simulation
    from flightid.sim.flight import Simulation
    from flightid.sim.trim import trim

    tr = trim(aircraft, altitude, speed)
    sim = FlightCoreAdapter(Simulation(aircraft, rate_hz=rate), tr)
    held = {"de": tr.elevator, "da": tr.aileron, "dr": tr.rudder, "throttle": tr.throttle}
    initial = sim.reset(held)
    config = _config(baud if baud > 0 else None, "", 0, not lockstep, profile)
    link, close = _air_link(serial, udp, baud, 0.0)
    typer.echo(f"trimmed {aircraft} at {altitude:g} m, {speed:g} m/s: de {tr.elevator:+.5f}, "
               f"da {tr.aileron:+.5f}, dr {tr.rudder:+.5f} rad, throttle {tr.throttle:.4f}; "
               "waiting for a ground station HEARTBEAT")
    try:
        rep, history = serve_simulation(sim, initial, link, config,
                                        steps=int(round(duration * rate)), lockstep=lockstep,
                                        timeout=timeout, controls=held)
    finally:
        close()
    typer.echo(rep.summary())
    typer.echo(f"{rep.controls_received} control messages received")
    if output:
        names = sorted(set.intersection(*(set(h) for h in history)))
        t = [k / rate for k in range(len(history))]
        FlightRecord(t, {n: [h[n] for h in history] for n in names},
                     sim.sim.meta({"bridge": "in the loop"})).write(output)
