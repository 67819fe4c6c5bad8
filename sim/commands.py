"""Command-line front ends of ``flightid trim`` and ``flightid truth`` (printing only)."""

from __future__ import annotations

import json
import math
import sys

from flightid.sim.model import UnknownAircraftError, load
from flightid.sim.trim import Trim, TrimError, trim


def _fail(message: str) -> None:
    print(f"error: {message}", file=sys.stderr)
    raise SystemExit(2)


def _trimmed(aircraft: str, altitude: float, speed: float, gamma_deg: float,
             bank_deg: float, flaps_deg: float) -> tuple[object, Trim]:
    try:
        model = load(aircraft)
        return model, trim(model, altitude, speed, math.radians(gamma_deg),
                           math.radians(bank_deg), math.radians(flaps_deg))
    except (UnknownAircraftError, TrimError) as exc:
        _fail(str(exc))
    raise AssertionError("unreachable")


def trim_cli(aircraft: str, altitude: float, speed: float, gamma_deg: float = 0.0,
             bank_deg: float = 0.0, flaps_deg: float = 0.0, fmt: str = "table") -> None:
    """Print the trim of an aircraft at altitude (m), speed (m/s), gamma and bank (deg)."""
    _, t = _trimmed(aircraft, altitude, speed, gamma_deg, bank_deg, flaps_deg)
    rows = [
        ("alpha", t.alpha, "rad"), ("theta", t.theta, "rad"), ("phi", t.phi, "rad"),
        ("beta", t.beta, "rad"), ("elevator", t.elevator, "rad"),
        ("aileron", t.aileron, "rad"), ("rudder", t.rudder, "rad"),
        ("throttle", t.throttle, "-"),
    ]
    if fmt == "json":
        print(json.dumps({k: v for k, v, _ in rows} | {"condition": {
            "altitude_m": altitude, "speed_m_s": speed, "gamma_rad": t.gamma_rad,
            "bank_rad": t.bank_rad, "flaps_rad": t.flaps_rad}}, indent=1))
        return
    if fmt != "table":
        _fail(f"unknown format {fmt!r}; use table or json")
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{t.aircraft} trim: {altitude:g} m, {speed:g} m/s, gamma "
                        f"{gamma_deg:g} deg, bank {bank_deg:g} deg")
    for col in ("quantity", "value", "unit", "deg"):
        table.add_column(col, justify="right" if col != "quantity" else "left")
    for name, value, unit in rows:
        deg = f"{math.degrees(value):.3f}" if unit == "rad" else ""
        table.add_row(name, f"{value:.6g}", unit, deg)
    Console().print(table)


def truth_cli(aircraft: str, altitude: float, speed: float, axes: str = "stability",
              fmt: str = "table", flaps_deg: float = 0.0, propulsion: bool = False) -> None:
    """Print the truth derivatives at a straight-and-level trim (table or flat JSON);
    ``propulsion``: total (aerodynamic + propulsive, engines at trim) derivatives."""
    from flightid.sim.truth import derivatives

    if axes not in ("body", "stability"):
        _fail(f"unknown axes {axes!r}; use body or stability")
    model, t = _trimmed(aircraft, altitude, speed, 0.0, 0.0, flaps_deg)
    truth = derivatives(model, t, axes=axes, propulsion=propulsion)
    if fmt == "json":
        print(json.dumps(truth.to_json_dict(), indent=1))
        return
    if fmt != "table":
        _fail(f"unknown format {fmt!r}; use table or json")
    from rich.console import Console
    from rich.table import Table

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
