"""``flightid trim`` and ``flightid truth``: trim a JSBSim aircraft, print its trim or its
truth derivatives (printing only; the work is ``flightid.sim.jsbsim.trim`` and
``flightid.sim.jsbsim.truth``)."""

from __future__ import annotations

import json
import math
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.cli.checks import check_aircraft_xml
from flightid.sim.jsbsim.model import Model, load
from flightid.sim.jsbsim.trim import Trim, trim
from flightid.sim.jsbsim.truth import derivatives

_AIRCRAFT_HELP = "project aircraft, jsbsim aircraft or XML path"
_FORMATS = ("table", "json")


def _fail(message: str) -> ValueError:
    """Bad input: the app's error policy prints it as one line and exits 2."""
    return ValueError(message)


def _check_format(fmt: str) -> None:
    if fmt not in _FORMATS:
        raise _fail(f"unknown format {fmt!r}; use table or json")


def _trimmed(aircraft: str, altitude: float, speed: float, gamma_deg: float,
             bank_deg: float, flaps_deg: float) -> tuple[Model, Trim]:
    # UnknownAircraftError (a ValueError): exit 2; TrimError: exit 3, or 2 when its input
    # checks failed (the app's error policy)
    check_aircraft_xml(aircraft)
    model = load(aircraft)
    return model, trim(model, altitude, speed, math.radians(gamma_deg),
                       math.radians(bank_deg), math.radians(flaps_deg))


def trim_command(
    aircraft: Annotated[str, typer.Argument(help=_AIRCRAFT_HELP)],
    altitude: Annotated[float, typer.Option(help="altitude above sea level, m")],
    speed: Annotated[float, typer.Option(help="true airspeed, m/s")],
    gamma: Annotated[float, typer.Option(help="flight-path angle, deg")] = 0.0,
    bank: Annotated[float, typer.Option(help="bank angle, deg (coordinated turn)")] = 0.0,
    flaps: Annotated[float, typer.Option(help="flap deflection, deg")] = 0.0,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
) -> None:
    """Trim an aircraft with JSBSim and print alpha, attitude, surfaces and throttle."""
    _check_format(format)
    _, t = _trimmed(aircraft, altitude, speed, gamma, bank, flaps)
    rows = [
        ("alpha", t.alpha, "rad"), ("theta", t.theta, "rad"), ("phi", t.phi, "rad"),
        ("beta", t.beta, "rad"), ("elevator", t.elevator, "rad"),
        ("aileron", t.aileron, "rad"), ("rudder", t.rudder, "rad"),
        ("throttle", t.throttle, "-"),
    ]
    if format == "json":
        print(json.dumps({k: v for k, v, _ in rows} | {"condition": {
            "altitude_m": altitude, "speed_m_s": speed, "gamma_rad": t.gamma_rad,
            "bank_rad": t.bank_rad, "flaps_rad": t.flaps_rad}}, indent=1))
        return
    table = Table(title=f"{t.aircraft} trim: {altitude:g} m, {speed:g} m/s, gamma "
                        f"{gamma:g} deg, bank {bank:g} deg")
    for col in ("quantity", "value", "unit", "deg"):
        table.add_column(col, justify="right" if col != "quantity" else "left")
    for name, value, unit in rows:
        deg = f"{math.degrees(value):.3f}" if unit == "rad" else ""
        table.add_row(name, f"{value:.6g}", unit, deg)
    Console().print(table)


def truth_command(
    aircraft: Annotated[str, typer.Argument(help=_AIRCRAFT_HELP)],
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
    if axes not in ("body", "stability"):
        raise _fail(f"unknown axes {axes!r}; use body or stability")
    _check_format(format)
    model, t = _trimmed(aircraft, altitude, speed, 0.0, 0.0, flaps)
    truth = derivatives(model, t, axes=axes, propulsion=propulsion)
    if format == "json":
        print(json.dumps(truth.to_json_dict(), indent=1))
        return
    kind = "total (aero + propulsive)" if propulsion else "aerodynamic"
    table = Table(title=f"{t.aircraft} {kind} truth derivatives, {axes} axes (literature form: "
                        f"stability), {altitude:g} m, {speed:g} m/s, alpha "
                        f"{math.degrees(t.alpha):.2f} deg; per rad, rates per p b/2V, q c/2V")
    variables = ("0", "alpha", "beta", "p", "q", "r", "alphadot", "de", "da", "dr", "dt")
    coefs = ("X", "Y", "Z", "l", "m", "n", "L", "D") if axes == "body" else (
        "L", "D", "Y", "l", "m", "n")
    present = [v for v in variables if any(f"C{c}_{v}" in truth.values
                                            or f"C{c}_{v}" in truth.flags for c in coefs)]
    table.add_column("var")
    for c in coefs:
        table.add_column(f"C{c}", justify="right")
    for v in present:
        cells = []
        for c in coefs:
            name = f"C{c}_{v}"
            if name in truth.flags:
                k = truth.flags[name]
                cells.append(f"[yellow]{k.minus:.3g}|{k.plus:.3g}*[/yellow]")
            elif name in truth.values:
                cells.append(f"{truth.values[name]:.4g}")
            else:
                cells.append("")
        table.add_row(v, *cells)
    console = Console()
    console.print(table)
    if truth.flags:
        console.print("* kink at trim: left|right one-sided slopes (no single derivative)")
