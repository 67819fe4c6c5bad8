"""The flight card's type and fields: ``Card``, ``CardError``, the fields a card may have,
and the TOML path of a field (``maneuver[2].amplitude_deg``)."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from flightid.scenarios.input_design import InputDesign
from flightid.sim.jsbsim.condition import FlightCondition

TOP_FIELDS = ("name", "description", "source", "aircraft", "duration", "rate", "seed",
              "condition", "maneuver", "sensors", "disturbance", "effect", "a_priori")
A_PRIORI_FIELDS = ("value", "std", "source")
CONDITION_FIELDS = ("altitude", "speed", "gamma", "bank", "flaps")
NO_SENSORS = "none"


class CardError(ValueError):
    """A mistake in a flight card: ``path``, ``line`` (1-based or None) and ``field``."""

    def __init__(self, path: str, line: int | None, field: str | None, message: str) -> None:
        where = f"{path}:{line}" if line else str(path)
        what = f"field '{field}': " if field and f"'{field}'" not in message else ""
        super().__init__(f"{where}: {what}{message}")
        self.path = str(path)
        self.line = line
        self.field = field
        self.message = message


# a card's [condition] table (altitude, speed, gamma, bank, flaps in card units) is read
# into the one flight-condition type of flightid.sim.jsbsim.condition
Condition = FlightCondition


@dataclass
class Card:
    """A validated flight card; ``data`` is the card as parsed (plain dict, card units)."""

    name: str
    aircraft: str
    condition: FlightCondition
    duration: float
    rate: float
    seed: int
    maneuvers: tuple[InputDesign, ...] = ()
    sensors: Any = None  # flightid.sim.sensors.suites.SensorSuite or None
    disturbances: tuple[Any, ...] = ()
    # airframe and actuator effects ([[effect]]), flown in an augmented aircraft
    augmentation: tuple[Any, ...] = ()
    description: str = ""
    source: str = ""
    path: str = ""
    data: dict[str, Any] = field(default_factory=dict)
    # parameters an identification holds fixed: {name: {"value", "std", "source"}}
    a_priori: dict[str, dict[str, Any]] = field(default_factory=dict)
    # each card field that injects an effect -> its catalogue entry, e.g.
    # {"sensors.channels.q[1]": "noise", "disturbance[0]": "turbulence"}
    effects: dict[str, str] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The card as written (a JSON-able dict), for record metadata."""
        return plain(self.data)


def plain(x: Any) -> Any:
    """A copy of a parsed card as plain dicts and lists (tuples become lists).

    Parameters
    ----------
    x : Any
        Parsed card or a part of it.

    Returns
    -------
    Any
        The plain copy.
    """
    if isinstance(x, dict):
        return {k: plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [plain(v) for v in x]
    return x


def field_path(field_name: str) -> tuple:
    """'maneuver[2].amplitude_deg' -> ('maneuver', 2, 'amplitude_deg').

    Parameters
    ----------
    field_name : str
        Dotted field name with optional ``[i]`` indices.

    Returns
    -------
    tuple
        Path of keys (str) and indices (int).
    """
    out: list = []
    for part in field_name.split("."):
        m = re.fullmatch(r"([^\[\]]+)((?:\[\d+\])*)", part)
        if not m:
            out.append(part)
            continue
        out.append(m.group(1))
        out.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(out)
