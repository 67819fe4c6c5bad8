"""The ``flightid`` command line: thin wiring from commands to library functions."""

from __future__ import annotations

from typing import Annotated

import typer

app = typer.Typer(
    pretty_exceptions_enable=False,
    help="flightid: aircraft system identification testbed (JSBSim truth flights, "
    "flight-test inputs, identification scored against known derivatives).",
    no_args_is_help=True,
    add_completion=False,
)


@app.callback()
def _main() -> None:
    """flightid: aircraft system identification testbed."""


@app.command()
def version() -> None:
    """Print the flightid version."""
    from flightid import __version__

    typer.echo(__version__)


@app.command()
def demo(
    card: Annotated[str, typer.Option(help="library card name or TOML path")] = "navion-demo",
    seed: Annotated[int | None, typer.Option(help="random seed (default: the card's)")] = None,
    report: Annotated[str, typer.Option(help="HTML report to write")] = "flightid-demo.html",
) -> None:
    """The main job: fly the built-in Navion card, identify by output error, score, report."""
    from flightid.scenarios.demo import run_cli as demo_cli

    demo_cli(card, seed, report)


@app.command()
def identify(
    record: Annotated[str, typer.Argument(help="flight record: .parquet, .csv or SIDPAC .mat")],
    method: Annotated[str, typer.Option(help="ee, swr, ... (dispatch.METHODS)")] = "ee",
    model: Annotated[
        str, typer.Option(help="preset (lat[eral], lon[gitudinal], short_period, 6dof, all) "
                          "or 'Cn=beta+phat+rhat; ...' (ee, swr)")
    ] = "lateral",
    coefficient: Annotated[
        list[str] | None, typer.Option(help="restrict to this coefficient (repeatable)")
    ] = None,
    truth: Annotated[str | None, typer.Option(help="JSON of true derivative values")] = None,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
    report: Annotated[str | None, typer.Option(help="write an HTML report here")] = None,
    option: Annotated[list[str] | None, typer.Option(
        help="method option KEY=VALUE (repeatable), e.g. colored=true, "
             "initial_state=estimate")] = None,
    multistep_input: Annotated[list[str] | None, typer.Option(
        help="input channel flown as a multistep (doublet, 3211, pulse) whose measurement "
             "is noisy: --method oe estimates its levels and sub-sample edge times with the "
             "derivatives, the other methods take it made piecewise constant (repeatable)")
    ] = None,
) -> None:
    """Identify stability and control derivatives from a flight record."""
    from flightid.identification.dispatch import run_cli

    run_cli(record, method, model, coefficient or [], truth, format, report, option or [],
            multistep_input or [])


@app.command("frequency-response")
def frequency_response_command(
    record: Annotated[str, typer.Argument(help="flight record: .parquet, .csv or SIDPAC .mat")],
    input: Annotated[str, typer.Option("--input", help="input channel, e.g. de")],
    output: Annotated[str, typer.Option("--output", help="output channel, e.g. q")],
    condition_on: Annotated[
        list[str] | None, typer.Option(help="other input to condition on (repeatable)")
    ] = None,
    window: Annotated[
        list[float] | None, typer.Option(help="window length in s (repeatable; composite)")
    ] = None,
    f_min: Annotated[float | None, typer.Option(help="lowest frequency, Hz")] = None,
    f_max: Annotated[float | None, typer.Option(help="highest frequency, Hz")] = None,
    plot: Annotated[str | None, typer.Option(help="write a Bode/coherence PNG here")] = None,
) -> None:
    """Frequency response output/input with coherence and random error (CIFER style)."""
    from flightid.identification.frequency_response import run_cli as fr_cli

    fr_cli(record, input, output, condition_on or [], window or [], f_min, f_max, plot)


@app.command("trim")
def trim_command(
    aircraft: Annotated[str, typer.Argument(help="project aircraft, jsbsim aircraft or XML path")],
    altitude: Annotated[float, typer.Option(help="altitude above sea level, m")],
    speed: Annotated[float, typer.Option(help="true airspeed, m/s")],
    gamma: Annotated[float, typer.Option(help="flight-path angle, deg")] = 0.0,
    bank: Annotated[float, typer.Option(help="bank angle, deg (coordinated turn)")] = 0.0,
    flaps: Annotated[float, typer.Option(help="flap deflection, deg")] = 0.0,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
) -> None:
    """Trim an aircraft with JSBSim and print alpha, attitude, surfaces and throttle."""
    from flightid.sim.commands import trim_cli

    trim_cli(aircraft, altitude, speed, gamma, bank, flaps, format)


@app.command("truth")
def truth_command(
    aircraft: Annotated[str, typer.Argument(help="project aircraft, jsbsim aircraft or XML path")],
    altitude: Annotated[float, typer.Option(help="altitude above sea level, m")],
    speed: Annotated[float, typer.Option(help="true airspeed, m/s")],
    axes: Annotated[str, typer.Option(help="stability (literature form) or body")] = "stability",
    flaps: Annotated[float, typer.Option(help="flap deflection, deg")] = 0.0,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
    propulsion: Annotated[bool, typer.Option(
        help="total derivatives: aero + propulsive at trim engine state (what flight "
             "data without a propulsion model identifies)")] = False,
) -> None:
    """Truth stability and control derivatives of the JSBSim model at level trim."""
    from flightid.sim.commands import truth_cli

    truth_cli(aircraft, altitude, speed, axes, format, flaps, propulsion)


# -- the recorder bridge (sim/bridge*.py, sim/recorder.py) -------------------------------
bridge_app = typer.Typer(
    help="MAVLink/serial recorder bridge: stream flights, record tlogs, fly in the loop.",
    no_args_is_help=True,
)
app.add_typer(bridge_app, name="bridge")

_SERIAL_HELP = "serial device (or 'pty' to create a pseudo-terminal; serve/fly only)"
_UDP_HELP = "loopback HOST:PORT (the recorder listens there)"


@bridge_app.command("serve")
def bridge_serve(
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
) -> None:
    """Stream a flight as MAVLink 2 over a serial port, a pty or loopback UDP."""
    from flightid.sim.bridge_cli import serve_cli

    serve_cli(source, serial, udp, baud, realtime, faults, seed, profile, start_delay, report)


@bridge_app.command("record")
def bridge_record(
    output: Annotated[str, typer.Option("-o", "--output", help="the .tlog to write")],
    serial: Annotated[str | None, typer.Option(help="serial device to read")] = None,
    udp: Annotated[str | None, typer.Option(help=_UDP_HELP)] = None,
    baud: Annotated[int, typer.Option(help="serial rate in bits/s")] = 57600,
    duration: Annotated[float | None, typer.Option(help="stop after this many s")] = None,
    idle_timeout: Annotated[float, typer.Option(help="stop after this many s without data")] = 10.0,
) -> None:
    """Record a MAVLink stream into a .tlog (every intact packet; report in <tlog>.json)."""
    from flightid.sim.bridge_cli import record_cli

    record_cli(serial, udp, baud, output, duration, idle_timeout)


@bridge_app.command("fly")
def bridge_fly(
    aircraft: Annotated[str, typer.Argument(help="project aircraft, jsbsim aircraft or XML path")],
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
) -> None:
    """Fly the JSBSim aircraft with controls received over the link (HIL_ACTUATOR_CONTROLS,
    SET_ACTUATOR_CONTROL_TARGET, MANUAL_CONTROL or RC_CHANNELS_OVERRIDE)."""
    from flightid.sim.bridge_cli import fly_cli

    fly_cli(aircraft, altitude, speed, serial, udp, baud, rate, duration, lockstep, timeout,
            profile, output)


@app.command("convert")
def convert_command(
    tlog: Annotated[str, typer.Argument(help="MAVLink .tlog")],
    output: Annotated[str, typer.Argument(help="flight record to write (.parquet or .csv)")],
    align: Annotated[str, typer.Option(help="auto, timesync, xcorr or none")] = "auto",
    reference: Annotated[str | None, typer.Option(help="clock source 'sysid/compid'")] = None,
    rate: Annotated[float | None, typer.Option(help="output rate, Hz")] = None,
    aircraft: Annotated[str, typer.Option(
        help="aircraft: adds its mass properties and geometry (MAVLink has none)")] = "",
) -> None:
    """Convert a MAVLink .tlog to a flight record (SI channels, aligned, uniform time)."""
    from flightid.sim.bridge_cli import convert_cli

    convert_cli(tlog, output, align, reference, rate, aircraft)


@app.command("simulate")
def simulate_command(
    card: Annotated[str | None, typer.Argument(help="card file or library card name")] = None,
    output: Annotated[str | None, typer.Option("-o", "--output",
                                               help="measured record (.parquet or .csv)")] = None,
    truth: Annotated[str | None, typer.Option(help="also write the truth record here")] = None,
    plot: Annotated[str | None, typer.Option(help="write a PNG of inputs and responses")] = None,
    seed: Annotated[int | None, typer.Option(help="random seed (default: the card's)")] = None,
    list_cards: Annotated[bool, typer.Option("--list", help="list the library cards")] = False,
) -> None:
    """Fly a flight card (file or library name) and write the measured record."""
    from flightid.scenarios.simulate import run_cli as simulate_cli

    simulate_cli(card, output, truth, plot, seed, list_cards)


@app.command("compatibility")
def compatibility_command(
    record: Annotated[str, typer.Argument(help="flight record: .parquet, .csv or SIDPAC .mat")],
    output: Annotated[str | None, typer.Option("-o", "--output",
                                               help="write the corrected record here")] = None,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
) -> None:
    """Data compatibility: flight path reconstruction of sensor biases, scale factors and
    vane calibration; optionally write the corrected record."""
    from flightid.identification.compatibility import run_cli as compatibility_cli

    compatibility_cli(record, output, format)


def main() -> None:
    """The console entry point: bad input ends in one clear line and exit code 2."""
    import sys

    try:
        app()
    except (ValueError, KeyError, FileNotFoundError, NotADirectoryError, IsADirectoryError) as exc:
        command = " ".join(a for a in sys.argv[1:2] if not a.startswith("-"))
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"flightid {command}: {message}".replace("  ", " "), file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
