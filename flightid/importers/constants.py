"""An aircraft's constants for an imported record: mass and inertias, reference geometry,
sensor positions, as a weight-and-balance sheet gives them. A TOML file::

    name = "DLR ATTAS"
    [mass_properties]          # numbers in SI (kg, kg*m^2) or "VALUE UNIT" text
    mass = "9800 kg"
    Ixx = "45000 slug*ft^2"
    Iyy = 58000.0
    Izz = 98000.0
    Ixz = 0.0                  # positive as in Etkin
    [reference]                # m^2 and m, or "VALUE UNIT"
    area = "420 ft^2"
    span = 21.5
    chord = 2.15
    [sensors]                  # body axes from the CG (x forward, y right, z down), m
    alpha_vane = [4.6, 0.0, -0.3]
    accelerometers = ["1.2 ft", "0 ft", "0 ft"]

The same constants from a project or JSBSim aircraft name are the command line's
(``flightid.sim.jsbsim.model``, a layer above this one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from flightid.files import read_toml
from flightid.flight_record import FlightRecord, Reference
from flightid.units import to_si

MASS_PROPERTIES = {"mass": "kg", "Ixx": "kg*m^2", "Iyy": "kg*m^2", "Izz": "kg*m^2",
                   "Ixz": "kg*m^2"}
REFERENCE = {"area": "m^2", "span": "m", "chord": "m"}
# the sensor positions a record's meta.extra['sensor_positions'] holds and the standard data
# reduction corrects (docs/record.md, identification.data.reduction)
SENSOR_POSITIONS = ("accelerometers", "alpha_vane", "beta_vane")


@dataclass
class AircraftConstants:
    """Mass (kg), inertias (kg m^2, Ixz positive as in Etkin), reference geometry and
    sensor positions (m, body axes from the CG) of an aircraft, and where they came from."""

    name: str = ""
    mass_properties: dict[str, float] = field(default_factory=dict)
    reference: Reference | None = None
    sensors: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    source: str = ""

    def apply(self, record: FlightRecord) -> FlightRecord:
        """``record`` with the mass properties as constant channels (a channel the record
        already has is kept), the reference geometry, the aircraft name and the sensor
        positions (``meta.extra['sensor_positions']``, m) in its metadata; a reference
        condition without a mass gets the mass."""
        n = len(record)
        added = {k: np.full(n, v) for k, v in self.mass_properties.items()
                 if k not in record}
        extra = dict(record.meta.extra)
        if self.sensors:
            extra["sensor_positions"] = {k: list(v) for k, v in self.sensors.items()}
        if self.source:
            extra["constants"] = self.source
        condition = dict(record.meta.condition or {})
        if condition and "mass" not in condition and "mass" in added:
            condition["mass"] = float(added["mass"][0])  # the reference condition's mass
        meta = replace(record.meta, aircraft=record.meta.aircraft or self.name,
                       reference=self.reference or record.meta.reference, extra=extra,
                       condition=condition or record.meta.condition)
        return FlightRecord(record.time, {**record.channels, **added}, meta)


def quantity(value: Any, si_unit: str, where: str) -> float:
    """A number (already SI) or 'VALUE UNIT' text converted to ``si_unit``.

    Parameters
    ----------
    value : int, float or str
        The number, or text such as '12.5 ft'.
    si_unit : str
        SI unit of the quantity, e.g. "kg", "m".
    where : str
        Names the entry in error messages.

    Returns
    -------
    float
        The value in ``si_unit``.

    Raises
    ------
    ValueError
        Naming ``where`` for a value that is not a finite number or has a wrong unit.
    """
    if isinstance(value, bool):
        raise ValueError(f"{where}: {value!r} is not a number")
    if isinstance(value, int | float):
        number, factor = float(value), 1.0
    elif isinstance(value, str):
        text, _, unit = value.strip().partition(" ")
        try:
            number = float(text)
        except ValueError:
            raise ValueError(f"{where}: {value!r} must be a number or 'VALUE UNIT' "
                             f"(e.g. '12.5 {si_unit}')") from None
        try:
            factor = to_si(unit, si_unit)[1] if unit.strip() else 1.0
        except (KeyError, ValueError) as exc:
            raise ValueError(f"{where}: {exc.args[0]}") from None
    else:
        raise ValueError(f"{where}: {value!r} must be a number or 'VALUE UNIT'")
    if not math.isfinite(number):
        raise ValueError(f"{where}: {value!r} is not finite")
    return number * factor


def read_constants(path: str | Path) -> AircraftConstants:
    """Aircraft constants from a TOML file (format in the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The constants file.

    Returns
    -------
    AircraftConstants
        Name, mass properties, reference geometry and sensor positions, SI.

    Raises
    ------
    ValueError
        Naming the file and entry for an unknown entry or an invalid value.
    """
    path = Path(path)
    data = read_toml(path, "aircraft constants file", "TOML file")
    unknown = sorted(set(data) - {"name", "mass_properties", "reference", "sensors"})
    if unknown:
        raise ValueError(f"{path}: unknown entries {', '.join(unknown)}; an aircraft "
                         "constants file has name, [mass_properties], [reference], [sensors]")
    out = AircraftConstants(name=str(data.get("name", "")), source=f"constants file {path}")
    for key, value in data.get("mass_properties", {}).items():
        if key not in MASS_PROPERTIES:
            raise ValueError(f"{path} [mass_properties] {key}: unknown; use "
                             f"{', '.join(MASS_PROPERTIES)}")
        out.mass_properties[key] = quantity(value, MASS_PROPERTIES[key],
                                            f"{path} [mass_properties] {key}")
    if "mass" in out.mass_properties and not out.mass_properties["mass"] > 0:
        raise ValueError(f"{path} [mass_properties] mass must be > 0 kg")
    ref = data.get("reference")
    if ref is not None:
        missing = [k for k in REFERENCE if k not in ref]
        if missing or set(ref) - set(REFERENCE):
            raise ValueError(f"{path} [reference] needs exactly area, span and chord "
                             f"(missing: {', '.join(missing) or 'none'})")
        values = {k: quantity(ref[k], u, f"{path} [reference] {k}") for k, u in
                  REFERENCE.items()}
        if not all(v > 0 for v in values.values()):
            raise ValueError(f"{path} [reference]: area, span and chord must be > 0")
        out.reference = Reference(**values)
    for name, position in data.get("sensors", {}).items():
        if name not in SENSOR_POSITIONS:
            raise ValueError(f"{path} [sensors] {name}: not a sensor the data reduction "
                             f"corrects; valid: {', '.join(SENSOR_POSITIONS)}")
        if not isinstance(position, list) or len(position) != 3:
            raise ValueError(f"{path} [sensors] {name}: give [x, y, z] (m, body axes "
                             "from the CG)")
        x, y, z = (quantity(v, "m", f"{path} [sensors] {name}") for v in position)
        out.sensors[name] = (x, y, z)
    return out
