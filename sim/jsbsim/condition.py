"""The flight condition: where and how fast an aircraft is trimmed (one type for cards,
trim, truth and the record's metadata)."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any


@dataclass(frozen=True)
class FlightCondition:
    """Trimmed start: altitude (m above sea level), true airspeed (m/s), flight-path angle,
    bank and flap deflection (rad)."""

    altitude_m: float
    speed_m_s: float
    gamma_rad: float = 0.0
    bank_rad: float = 0.0
    flaps_rad: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        """The condition as a plain dict (record metadata, JSON)."""
        return asdict(self)
