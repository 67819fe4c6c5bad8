"""Servo outputs (PWM, us) as control-surface commands: which output drives which surface,
its trim and its throws, as an RC aircraft's set-up sheet gives them. A TOML file::

    [da]                 # surface: a flightid control channel (de, da, dr, df)
    channel = 1          # servo output (RCOU C1..C14 of ArduPilot, 1-based)
    trim = 1500          # PWM at zero deflection (us)
    throw = "25 deg"     # deflection at trim + 500 us, in flightid's sign (channels.py)
    throw_low = "20 deg" # optional: deflection per 500 us below trim, its size (default: throw)
    [throttle]
    channel = 3
    low = 1000           # PWM at throttle 0 and 1 (us)
    high = 2000

The default is ArduPlane's output order (1 aileron, 2 elevator, 3 throttle, 4 rudder)
with 1500 us trims and 30 deg throws, the outputs not reversed: an aileron, elevator or
rudder output above trim asks for a right roll, nose up or nose right, which is a negative
da, de or dr (throw -30 deg). The values are commands: what the autopilot sent
to the servos, not where the surfaces went.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flightid.files import read_toml
from flightid.importers.constants import quantity
from flightid.importers.dataflash_formats import SERVO_DEFLECTION_SIGN
from flightid.units import DEG

SURFACES = ("de", "da", "dr", "df")
MAX_OUTPUT = 14  # ArduPilot's RCOU logs C1..C14
HALF_RANGE_US = 500.0  # throws are given per 500 us from trim


@dataclass(frozen=True)
class Servo:
    """One surface servo: output number (1-based), trim PWM (us), and the deflection (rad,
    canonical sign) per 500 us above trim (``throw``) and below it (``throw_low``)."""

    channel: int
    trim: float = 1500.0
    throw: float = 30 * DEG
    throw_low: float | None = None

    def deflection(self, pwm: np.ndarray) -> np.ndarray:
        """Commanded deflection (rad) of PWM values (us)."""
        pwm = np.asarray(pwm, dtype=float)
        low = self.throw if self.throw_low is None else self.throw_low
        return (pwm - self.trim) / HALF_RANGE_US * np.where(pwm >= self.trim, self.throw, low)

    def pwm(self, deflection: np.ndarray, whole: bool = True) -> np.ndarray:
        """PWM (us) commanding ``deflection`` (rad): the inverse of :meth:`deflection`,
        rounded to the microsecond as a servo output is unless ``whole`` is False."""
        d = np.asarray(deflection, dtype=float)
        low = self.throw if self.throw_low is None else self.throw_low
        above = d / self.throw >= 0
        pwm = self.trim + HALF_RANGE_US * d / np.where(above, self.throw, low)
        return np.round(pwm) if whole else pwm


@dataclass(frozen=True)
class Throttle:
    """The throttle output: number (1-based) and the PWM (us) at throttle 0 and 1."""

    channel: int = 3
    low: float = 1000.0
    high: float = 2000.0

    def value(self, pwm: np.ndarray) -> np.ndarray:
        """Throttle (0..1) of PWM values (us)."""
        return (np.asarray(pwm, dtype=float) - self.low) / (self.high - self.low)

    def pwm(self, throttle: np.ndarray) -> np.ndarray:
        """PWM (us, whole) of throttle values (0..1)."""
        return np.round(self.low + (self.high - self.low) * np.asarray(throttle, dtype=float))


def _default_surfaces() -> dict[str, Servo]:
    """ArduPlane's default outputs, not reversed: an output above trim is a negative
    deflection (``dataflash_formats.SERVO_DEFLECTION_SIGN``)."""
    return {name: Servo(n, throw=SERVO_DEFLECTION_SIGN[name] * 30 * DEG)
            for name, n in (("da", 1), ("de", 2), ("dr", 4))}


@dataclass(frozen=True)
class ServoMapping:
    """Surfaces and throttle by servo output (module docstring)."""

    surfaces: dict[str, Servo] = field(default_factory=_default_surfaces)
    throttle: Throttle | None = field(default_factory=Throttle)
    # a second servo of a surface (a PX4 right aileron beside the left one): the surface's
    # command is the mean of the two deflections
    partners: dict[str, Servo] = field(default_factory=dict)

    def outputs(self) -> dict[str, int]:
        """Channel -> servo output number (1-based)."""
        out = {name: s.channel for name, s in self.surfaces.items()}
        if self.throttle is not None:
            out["throttle"] = self.throttle.channel
        return out

    def as_dict(self) -> dict:
        """Plain data (for a record's metadata)."""
        out: dict = {name: {"channel": s.channel, "trim_us": s.trim, "throw_rad": s.throw,
                            "throw_low_rad": s.throw_low} for name, s in self.surfaces.items()}
        for name, s in self.partners.items():
            out[f"{name} (second servo)"] = {"channel": s.channel, "trim_us": s.trim,
                                             "throw_rad": s.throw, "throw_low_rad": s.throw_low}
        if self.throttle is not None:
            out["throttle"] = {"channel": self.throttle.channel, "low_us": self.throttle.low,
                               "high_us": self.throttle.high}
        return out


def _output(value: object, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_OUTPUT:
        raise ValueError(f"{where}: channel {value!r} is not a servo output; use 1..{MAX_OUTPUT}")
    return value


def _pwm(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not \
            math.isfinite(value) or not 500 <= value <= 2500:
        raise ValueError(f"{where}: {value!r} is not a PWM value; use 500..2500 us")
    return float(value)


def read_servo_map(path: str | Path) -> ServoMapping:
    """A ServoMapping from a TOML file (format in the module docstring).

    A surface that is not a flightid control channel, or an output outside 1..14, is refused
    naming the valid ones.

    Parameters
    ----------
    path : str or pathlib.Path
        The servo mapping file.

    Returns
    -------
    ServoMapping
        Surfaces (output, trim PWM, throw in rad) and the throttle, if given.
    """
    path = Path(path)
    data = read_toml(path, "servo mapping file", "TOML file")
    surfaces: dict[str, Servo] = {}
    throttle = None
    for name, table in data.items():
        where = f"{path} [{name}]"
        if name not in (*SURFACES, "throttle"):
            raise ValueError(f"{where}: {name!r} is not a control channel; valid: "
                             f"{', '.join((*SURFACES, 'throttle'))}")
        if not isinstance(table, dict) or "channel" not in table:
            raise ValueError(f"{where}: give at least channel = N (servo output 1..14)")
        if name == "throttle":
            unknown = set(table) - {"channel", "low", "high"}
            if unknown:
                raise ValueError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}; use "
                                 "channel, low, high")
            throttle = Throttle(_output(table["channel"], where),
                                _pwm(table.get("low", 1000), f"{where} low"),
                                _pwm(table.get("high", 2000), f"{where} high"))
            if throttle.high == throttle.low:
                raise ValueError(f"{where}: low and high must differ")
            continue
        unknown = set(table) - {"channel", "trim", "throw", "throw_low"}
        if unknown:
            raise ValueError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}; use "
                             "channel, trim, throw, throw_low")
        throw = quantity(table.get("throw", 30 * DEG), "rad", f"{where} throw")
        low = table.get("throw_low")
        if low is not None:  # a magnitude: the sign is the throw's
            low = math.copysign(quantity(low, "rad", f"{where} throw_low"), throw)
        servo = Servo(_output(table["channel"], where), _pwm(table.get("trim", 1500),
                                                             f"{where} trim"), throw, low)
        if servo.throw == 0 or servo.throw_low == 0:
            raise ValueError(f"{where}: a throw of 0 maps every PWM to no deflection")
        surfaces[name] = servo
    mapping = ServoMapping(surfaces, throttle)
    outputs = list(mapping.outputs().values())
    if len(set(outputs)) != len(outputs):
        raise ValueError(f"{path}: two channels on one servo output ({mapping.outputs()})")
    return mapping
