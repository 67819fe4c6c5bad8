"""``flightid import``: flight data from elsewhere (delimited text, ArduPilot DataFlash
``.bin``) into a flight record, through a column or servo map and the aircraft's
constants, then the unit check and the time-base re-grid that every command applies when
it reads a record (``flightid.cli.checks``)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flightid.cli.checks import check_suffix, check_writable, printed_warnings
from flightid.identification.data import time_base
from flightid.identification.data.unit_sanity import check_units
from flightid.importers.ascii import read_delimited
from flightid.importers.constants import AircraftConstants, read_constants
from flightid.importers.dataflash import read_dataflash
from flightid.importers.mapping import ColumnMap, parse_map, read_map
from flightid.importers.servos import read_servo_map
from flightid.importers.ulog import read_ulog
from flightid.record import FlightRecord
from flightid.sim.jsbsim.model import load

RECORD_SUFFIXES = (".parquet", ".csv")
LOG_READERS = {".bin": (read_dataflash, "dataflash"), ".ulg": (read_ulog, "ulog")}


def aircraft_constants(aircraft: str) -> AircraftConstants:
    """Constants from a TOML file (``flightid.importers.constants``) or from a project or
    JSBSim aircraft (name or XML path): its mass, inertias and reference geometry as
    loaded (no sensor positions: JSBSim's are not the data system's)."""
    if aircraft.lower().endswith(".toml"):
        return read_constants(aircraft)
    model = load(aircraft)  # an unknown name: ValueError naming the known ones
    return AircraftConstants(name=aircraft, mass_properties=model.mass_properties(),
                             reference=model.reference,
                             source=f"mass properties and reference geometry of {aircraft!r}")


def column_map(mapping: str | None, maps: list[str], units: list[str]) -> ColumnMap:
    """The TOML mapping file's entries with the ``--map`` and ``--unit`` ones over them."""
    base = read_map(mapping) if mapping else ColumnMap()
    return base.merged(parse_map(maps, units))


def finish(record: FlightRecord, source: str, constants: AircraftConstants | None
           ) -> FlightRecord:
    """The aircraft's constants added, the unit check (units look wrong: exit 2) and a
    jittered time base re-gridded (a warning says so)."""
    if constants is not None:
        record = constants.apply(record)
    check_units(record, None, f"import ({source})")
    return time_base.regrid_jitter(record)


def import_command(
    file: Annotated[str, typer.Argument(
        help="flight data: ArduPilot DataFlash .bin, PX4 ULog .ulg, or delimited text "
             "(.csv, .txt, .dat, ...)")],
    output: Annotated[str, typer.Option("-o", "--output",
                                        help="flight record to write (.parquet or .csv)")],
    map_: Annotated[list[str] | None, typer.Option(
        "--map", help="COLUMN=channel,... (repeatable; 'time' for the time column)")] = None,
    mapping: Annotated[str | None, typer.Option(
        help="TOML mapping file: a columns table (COLUMN = channel) and a units table "
             "(COLUMN = unit); docs/import.md")
    ] = None,
    unit: Annotated[list[str] | None, typer.Option(
        "--unit", help="COLUMN=unit,... over the file's units row (deg, kt, ft, g, psf, ...)")
    ] = None,
    aircraft: Annotated[str | None, typer.Option(
        help="aircraft constants: a TOML file, or a project or JSBSim aircraft name")] = None,
    servos: Annotated[str | None, typer.Option(
        help="DataFlash and ULog: TOML servo mapping (output, trim, throws per surface; "
             "default: a DataFlash log's SERVOn_ parameters, else ArduPlane's order; 30 deg "
             "throws); docs/import.md")] = None,
) -> None:
    """Import flight data from elsewhere into a flight record (SI units, canonical names)."""
    check_suffix("--output", output, RECORD_SUFFIXES)
    check_writable("--output", output)
    if Path(output).resolve() == Path(file).resolve():
        raise ValueError(f"--output {output} is the input file; an output never replaces "
                         "an input: write elsewhere")
    log_reader = LOG_READERS.get(Path(file).suffix.lower())
    if log_reader and (map_ or mapping or unit):
        raise ValueError("--map, --mapping and --unit are for delimited text; a DataFlash "
                         "or ULog log takes --servos")
    if servos and not log_reader:
        raise ValueError("--servos is for a DataFlash (.bin) or ULog (.ulg) log")
    cmap = column_map(mapping, map_ or [], unit or [])
    servo_map = read_servo_map(servos) if servos else None
    if not Path(file).is_file():
        raise FileNotFoundError(f"{file}: no such file")
    constants = aircraft_constants(aircraft) if aircraft else None
    with printed_warnings("import"):
        raw = log_reader[0](file, servo_map) if log_reader else read_delimited(file, cmap)
        record = finish(raw, file, constants)
        record.write(output)
    if log_reader:
        _report_log(output, record, constants, log_reader[1])
        return
    info = record.meta.extra["import"]
    mapped = [f"{c}->{v['channel']}" for c, v in info["columns"].items() if v["channel"]]
    typer.echo(f"{output}: {len(record)} samples at {record.meta.sample_rate:.6g} Hz, "
               f"{len(mapped)} mapped column(s): {', '.join(mapped)}")
    if info["kept"]:
        typer.echo(f"  kept under their own names: {', '.join(info['kept'])}")
    if constants is not None:
        typer.echo(f"  constants: {constants.source}")
    for line in (*info["dropped"], *info["notes"]):
        typer.echo(f"  note: {line}")
    typer.echo("  units checked against physics (unit_sanity): plausible")


def _report_log(output: str, record: FlightRecord, constants: AircraftConstants | None,
                key: str) -> None:
    info = record.meta.extra[key]
    typer.echo(f"{output}: {len(record)} samples at {record.meta.sample_rate:.6g} Hz from "
               f"{info['span_s'][0]:.3f} to {info['span_s'][1]:.3f} s after boot, channels "
               f"{', '.join(sorted(record.channels))}")
    used = ("IMU", "ATT", "RCOU", "ARSP", "CTUN", "AOA", "BARO", "GPS")
    counts = info["counts"]
    kept = [f"{k} {n}" for k, n in counts.items() if key == "ulog" or k in used]
    typer.echo(f"  {'messages' if key == 'dataflash' else 'topics'}: {', '.join(kept)}")
    source = "RCOU" if key == "dataflash" else info["commands_from"]
    outputs = ", ".join(f"{name} output {v['channel']}" for name, v in info["servos"].items())
    typer.echo(f"  surfaces and throttle are servo commands ({source}: {outputs}), not "
               "surface positions (meta.extra surfaces = command)")
    if constants is not None:
        typer.echo(f"  constants: {constants.source}")
    for line in info["notes"]:
        typer.echo(f"  note: {line}")
    typer.echo("  units checked against physics (unit_sanity): plausible")
