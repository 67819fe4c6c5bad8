"""``flightid bridge serve|record|fly`` and ``flightid convert``: the recorder bridge
(``flightid.sim.bridge``) on the command line.

Each command checks its options before any work (a flight, a trim, a link), parses them
into library calls and prints a readable report; a bad option or file raises ValueError
(or an OSError naming the file) with a specific message, which the error policy of
``flightid.cli.app`` prints as one line with exit 2 (docs/errors.md); a link on which no
ground station answers raises TimeoutError, exit 3.
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer

from flightid.channels import CHANNELS
from flightid.cli.checks import (
    Output,
    check_choice,
    check_count,
    check_number,
    check_paths,
    check_rate,
    check_size,
    check_suffix,
    estimated_bytes,
    read_record,
)
from flightid.files import write_text
from flightid.record import FlightRecord
from flightid.scenarios import cards
from flightid.sim.bridge.air.closed_loop import FlightCoreAdapter, serve_simulation
from flightid.sim.bridge.air.schedule import PROFILES
from flightid.sim.bridge.air.serve import BridgeConfig, serve_record
from flightid.sim.bridge.air.signing import SenderFilter, read_key, state_path
from flightid.sim.bridge.ground.gaps import MAX_GAP_SAMPLES
from flightid.sim.bridge.ground.recording import record_stream
from flightid.sim.bridge.ground.tlog import SEGMENTS, convert_tlog
from flightid.sim.bridge.link import (
    Link,
    LinkFaults,
    SerialLink,
    UdpLink,
    open_pty_pair,
    parse_hostport,
)
from flightid.sim.flight.simulation import Simulation
from flightid.sim.jsbsim.trim import trim

RECORD_SUFFIXES = (".parquet", ".csv", ".mat")
_AIRCRAFT_HELP = "project aircraft, jsbsim aircraft or XML path"
_SERIAL_HELP = "serial device (or 'pty' to create a pseudo-terminal; serve/fly only)"
_UDP_HELP = "loopback HOST:PORT (the recorder listens there)"

app = typer.Typer(
    help="MAVLink/serial recorder bridge: stream flights, record tlogs, fly in the loop.",
    no_args_is_help=True,
)


def _config(baud: int | None, faults: str, seed: int, realtime: bool, profile: str) -> BridgeConfig:
    if profile not in PROFILES:
        raise ValueError(f"--profile {profile!r} is not known; use {', '.join(PROFILES)}")
    try:
        parsed = LinkFaults.parse(faults)
    except ValueError as exc:
        raise ValueError(f"--faults: {exc}") from None
    return BridgeConfig(streams=PROFILES[profile](), baud=baud, faults=parsed, seed=seed,
                        realtime=realtime)


MAX_WAIT_S = 86_400.0  # a timeout, a duration or a delay beyond a day is a typing error


def _positive(option: str, value: float, unit: str = "s", high: float = MAX_WAIT_S) -> float:
    """A finite value in (0, high], else a ValueError naming the option (exit 2)."""
    return check_number(option, value, low=0.0, low_open=True, high=high, unit=unit)


def _check_link(serial: str | None, udp: str | None, baud: int, *,
                unlimited_baud: bool) -> None:
    """The link options, checked before any work: one of --serial / --udp, a loopback
    HOST:PORT with a port in 1..65535, a baud rate > 0 (or 0 = unlimited where allowed).
    Raises ValueError naming the option (exit 2)."""
    if (serial is None) == (udp is None):
        raise ValueError("give exactly one of --serial PORT or --udp HOST:PORT")
    if udp is not None:
        try:
            parse_hostport(udp)
        except ValueError as exc:
            raise ValueError(f"--udp: {exc}") from None
    if baud < 0 or (baud == 0 and not unlimited_baud):
        accepted = "> 0 bits/s (0 = unlimited)" if unlimited_baud else "> 0 bits/s"
        raise ValueError(f"--baud must be {accepted}, got {baud}")


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
    p = Path(path)
    if p.suffix.lower() in RECORD_SUFFIXES:
        if not p.exists():
            raise typer.BadParameter(f"{path}: no such file", param_hint="CARD_OR_RECORD")
        return read_record(path, "bridge serve")  # resource guard, unit check, jitter
    try:
        card = cards.load_card(cards.find_card(path))
    except cards.CardError as exc:
        raise typer.BadParameter(
            f"{exc} (expected a record {', '.join(RECORD_SUFFIXES)} or a flight card)",
            param_hint="CARD_OR_RECORD") from None
    typer.echo(f"flying card {card.name} ({card.aircraft}, {card.duration:g} s)")
    measured, _truth = cards.fly_card(card)
    return measured


@app.command("serve")
def serve(
    source: Annotated[str, typer.Argument(metavar="CARD_OR_RECORD",
                                          help="flight record (.parquet/.csv/.mat) or card")],
    serial: Annotated[str | None, typer.Option(help=_SERIAL_HELP)] = None,
    udp: Annotated[str | None, typer.Option(help=_UDP_HELP)] = None,
    baud: Annotated[int, typer.Option(help="link rate in bits/s (0 = unlimited)")] = 57600,
    realtime: Annotated[bool, typer.Option(help="pace the stream on the wall clock")] = False,
    faults: Annotated[str, typer.Option(
        help="e.g. corrupt=0.001,drop=0.05,latency=0.02,jitter=0.01 (corrupt per byte)")] = "",
    seed: Annotated[int, typer.Option(help="seed of the fault generator")] = 0,
    profile: Annotated[str, typer.Option(help="recorders: single or boomerang")] = "single",
    start_delay: Annotated[float, typer.Option(help="s to wait after creating a pty")] = 3.0,
    report: Annotated[str | None, typer.Option(help="write the air-side report (JSON)")] = None,
    force: Annotated[bool, typer.Option(
        "--force", help="write the output over an existing file of another kind")] = False,
) -> None:
    """Stream a flight as MAVLink 2 over a serial port, a pty or loopback UDP."""
    _check_link(serial, udp, baud, unlimited_baud=True)
    check_number("--start-delay", start_delay, low=0.0, high=MAX_WAIT_S, unit="s")
    config = _config(baud if baud > 0 else None, faults, seed, realtime, profile)
    check_paths({"CARD_OR_RECORD": source, "--serial": serial},
                [Output("--report", report, "json")], force)
    record = _load_source(source)
    link, close = _air_link(serial, udp, baud, start_delay)
    try:
        rep = serve_record(record, link, config, keep_fates=False)
    finally:
        close()
    typer.echo(rep.summary())
    if report:
        write_text(report, json.dumps(rep.as_dict(), indent=2, default=str))


def _ground_link(serial: str | None, udp: str | None, baud: int) -> Link:
    if (serial is None) == (udp is None):
        raise typer.BadParameter("give exactly one of --serial PORT or --udp HOST:PORT")
    try:
        if udp is not None:
            return UdpLink(parse_hostport(udp), listen=True)
        return SerialLink(serial, baud)
    except (OSError, ValueError) as exc:  # e.g. "port 14550 on 127.0.0.1 is in use"
        raise ValueError(f"{'--udp' if udp is not None else '--serial'}: {exc}") from None


@app.command("record")
def record(
    output: Annotated[str, typer.Option("-o", "--output", help="the .tlog to write")],
    serial: Annotated[str | None, typer.Option(help="serial device to read")] = None,
    udp: Annotated[str | None, typer.Option(help=_UDP_HELP)] = None,
    baud: Annotated[int, typer.Option(help="serial rate in bits/s")] = 57600,
    duration: Annotated[float | None, typer.Option(help="stop after this many s")] = None,
    idle_timeout: Annotated[float, typer.Option(help="stop after this many s without data")] = 10.0,
    first_timeout: Annotated[float, typer.Option(
        help="give up (exit 3) if nothing arrives within this many s")] = 30.0,
    force: Annotated[bool, typer.Option(
        "--force", help="write the output over an existing file of another kind")] = False,
) -> None:
    """Record a MAVLink stream into a .tlog (every intact packet; report in <tlog>.json)."""
    _check_link(serial, udp, baud, unlimited_baud=False)
    if duration is not None:
        _positive("--duration", duration, "s")
    _positive("--idle-timeout", idle_timeout, "s")
    _positive("--first-timeout", first_timeout, "s")
    check_paths({"--serial": serial}, [Output("--output", output, "tlog"),
                                       Output("--output (its report)", f"{output}.json",
                                              "json")], force)
    link = _ground_link(serial, udp, baud)
    typer.echo(f"recording {link.name} to {output}")
    try:
        rep = record_stream(link, output, duration=duration, idle_timeout=idle_timeout,
                            first_timeout=first_timeout)
    except KeyboardInterrupt:
        typer.echo("interrupted")
        raise typer.Exit(1) from None
    finally:
        link.close()
    typer.echo(rep.summary())


ALIGNMENTS = ("auto", "timesync", "xcorr", "none")


def _is_source(text: str) -> bool:
    """'SYSID/COMPID' with both in 0..255."""
    parts = text.split("/")
    return len(parts) == 2 and all(p.isdigit() and int(p) <= 255 for p in parts)


def convert_command(
    tlog: Annotated[str, typer.Argument(help="MAVLink .tlog")],
    output: Annotated[str, typer.Argument(help="flight record to write (.parquet or .csv)")],
    align: Annotated[str, typer.Option(help="auto, timesync, xcorr or none")] = "auto",
    reference: Annotated[str | None, typer.Option(help="clock source 'sysid/compid'")] = None,
    rate: Annotated[float | None, typer.Option(help="output rate, Hz")] = None,
    aircraft: Annotated[str, typer.Option(
        help="aircraft: adds its mass properties and geometry (MAVLink has none)")] = "",
    max_gap: Annotated[int, typer.Option(
        help="most missing samples of a channel interpolated over")] = MAX_GAP_SAMPLES,
    segment: Annotated[str, typer.Option(
        help="all (refuse a longer gap) or longest (keep the longest stretch without one)")
    ] = "all",
    force: Annotated[bool, typer.Option(
        "--force", help="write the output over an existing file of another kind")] = False,
) -> None:
    """Convert a MAVLink .tlog to a flight record (SI channels, aligned, uniform time)."""
    if Path(output).suffix.lower() not in (".parquet", ".csv"):
        raise typer.BadParameter(f"{output}: write .parquet or .csv", param_hint="OUTPUT")
    check_choice("--align", align, ALIGNMENTS)
    if reference is not None and not _is_source(reference):
        raise ValueError(f"--reference {reference!r} must be SYSID/COMPID, two numbers in "
                         "0..255 (e.g. 1/1)")
    if rate is not None:
        check_rate("--rate", rate)
    if max_gap < 0:
        raise ValueError(f"--max-gap must be >= 0 samples, got {max_gap}")
    if segment not in SEGMENTS:
        raise ValueError(f"--segment {segment!r} is not accepted; use one of "
                         f"{', '.join(SEGMENTS)}")
    if not Path(tlog).is_file():
        raise FileNotFoundError(f"{tlog}: no such file")
    check_paths({"TLOG": tlog, "--aircraft": aircraft or None}, [Output("OUTPUT", output)],
                force)
    # a damaged or unusable tlog raises ValueError: the error policy's one line, exit 2
    try:
        rec = convert_tlog(tlog, align=align, reference=reference, rate=rate,
                           aircraft=aircraft, max_gap=max_gap, segment=segment)
    except ValueError as exc:  # the message names the tlog it is about
        raise ValueError(str(exc) if str(tlog) in str(exc) else f"{tlog}: {exc}") from None
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
    for kind, u in b["untimed_messages"].items():
        typer.echo(f"  {kind} (no time field): {u['timed']} timed from the neighbouring "
                   f"messages (within {1e3 * u['max_bracket_s']:.0f} ms), {u['left_out']} "
                   "left out")
    if b["gaps"]["found"]:
        lo, hi = b["gaps"]["span_s"]
        typer.echo(f"  kept {lo:.3f} .. {hi:.3f} s, the longest stretch without a gap of more "
                   f"than {b['gaps']['max_gap_samples']} samples; "
                   f"{len(b['gaps']['found'])} gap(s): {'; '.join(b['gaps']['found'][:5])}")
    notes = b["read_notes"]
    if b["skipped_bytes"]:
        skips = sum("unreadable bytes" in n for n in notes)
        typer.echo(f"  {b['skipped_bytes']} unreadable bytes skipped in {skips} place(s) "
                   "(damaged packets; every intact packet kept)")
    for note in [n for n in notes if "unreadable bytes" not in n][:5]:
        typer.echo(f"  note: {note}")


@app.command("fly")
def fly(
    aircraft: Annotated[str, typer.Argument(help=_AIRCRAFT_HELP)],
    altitude: Annotated[float, typer.Option(help="trim altitude above sea level, m")],
    speed: Annotated[float, typer.Option(help="trim true airspeed, m/s")],
    serial: Annotated[str | None, typer.Option(help=_SERIAL_HELP)] = None,
    udp: Annotated[str | None, typer.Option(help=_UDP_HELP)] = None,
    baud: Annotated[int, typer.Option(help="link rate in bits/s (0 = unlimited)")] = 0,
    rate: Annotated[float, typer.Option(help="simulation/telemetry rate, Hz")] = 50.0,
    duration: Annotated[float, typer.Option(help="flight time, s")] = 30.0,
    lockstep: Annotated[bool, typer.Option(help="one step per control message")] = True,
    timeout: Annotated[float, typer.Option(help="s to wait for the ground station")] = 30.0,
    profile: Annotated[str, typer.Option(help="recorders: single or boomerang")] = "single",
    output: Annotated[str | None, typer.Option(help="write the flown record here")] = None,
    ground_system: Annotated[int, typer.Option(
        help="system id of the ground station allowed to fly (1..255)")] = 255,
    ground_component: Annotated[int | None, typer.Option(
        help="its component id (0..255; default: any component of that system)")] = None,
    signing_key: Annotated[str | None, typer.Option(
        help="file with the 32-byte MAVLink 2 signing key (raw or 64 hex digits): "
             "telemetry is signed, controls must be")] = None,
    force: Annotated[bool, typer.Option(
        "--force", help="write the output over an existing file of another kind")] = False,
) -> None:
    """Fly the JSBSim aircraft with controls received over the link (HIL_ACTUATOR_CONTROLS,
    SET_ACTUATOR_CONTROL_TARGET, MANUAL_CONTROL or RC_CHANNELS_OVERRIDE) from the ground
    station only (its ids; with a signing key, correctly signed packets only)."""
    _check_link(serial, udp, baud, unlimited_baud=True)
    check_count("--ground-system", ground_system, low=1, high=255)
    if ground_component is not None:
        check_count("--ground-component", ground_component, low=0, high=255)
    key = read_key(signing_key) if signing_key is not None else None
    check_rate("--rate", rate)
    _positive("--duration", duration, "s")
    check_size(f"--duration {duration:g} s at --rate {rate:g} Hz",
               estimated_bytes(duration * rate + 1, len(CHANNELS)), force)
    _positive("--timeout", timeout, "s")
    if duration * rate < 1:
        raise ValueError(f"--duration {duration:g} s at {rate:g} Hz is not one step")
    if profile not in PROFILES:
        raise ValueError(f"--profile {profile!r} is not known; use {', '.join(PROFILES)}")
    state = state_path(signing_key) if signing_key is not None else None
    check_suffix("--output", output, (".parquet", ".csv"))
    check_paths({"AIRCRAFT": aircraft, "--signing-key": signing_key, "--serial": serial},
                [Output("--output", output),
                 Output("--signing-key (its timestamp file)", state, "json")], force)
    # a damaged timestamp file is refused here, before the trim
    SenderFilter(ground_system, ground_component, key, state=state)
    tr = trim(aircraft, altitude, speed)
    sim = FlightCoreAdapter(Simulation(aircraft, rate_hz=rate), tr)
    held = {"de": tr.elevator, "da": tr.aileron, "dr": tr.rudder, "throttle": tr.throttle}
    initial = sim.reset(held)
    config = _config(baud if baud > 0 else None, "", 0, not lockstep, profile)
    config = replace(config, ground_system=ground_system, ground_component=ground_component,
                     signing_key=key, signing_state=state)
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
    if rep.refused:
        typer.echo(f"refused {sum(rep.refused.values())} packet(s) that may not fly the "
                   f"aircraft: {', '.join(f'{n} {k}' for k, n in rep.refused.items())}")
    if output:
        names = sorted(set.intersection(*(set(h) for h in history)))
        t = [k / rate for k in range(len(history))]
        FlightRecord(t, {n: [h[n] for h in history] for n in names},
                     sim.sim.meta({"bridge": "in the loop"})).write(output)
    if rep.ended:  # the steps flown are kept (written above); the exit says it stopped
        kept = f"; the {len(history)} samples flown are in {output}" if output else ""
        raise TimeoutError(f"the flight ended early: {rep.ended}{kept}")
