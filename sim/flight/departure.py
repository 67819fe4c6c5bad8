"""Departure from the valid envelope: the limits (``Limits``), the envelope they give for a
trim, the reason a sample left it, and ``DepartureError``."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from flightid.record import FlightRecord
from flightid.sim.flight.properties import AGL, WOW
from flightid.sim.jsbsim.model import Model
from flightid.sim.jsbsim.trim import Trim
from flightid.units import FT


class DepartureError(RuntimeError):
    """The flight left the valid envelope; ``reason``, ``time`` (s) and ``record`` say how."""

    def __init__(self, reason: str, time: float, record: FlightRecord | None = None) -> None:
        super().__init__(f"departure at t = {time:.3f} s: {reason}")
        self.reason = reason
        self.time = time
        self.record = record


@dataclass(frozen=True)
class Limits:
    """Departure limits; None picks the default from the model and trim."""

    alpha_rad: tuple[float, float] | None = None  # default: <alphalimits> +-5 deg, else -20..30
    max_speed_m_s: float | None = None  # default: 2 x trim speed
    min_speed_m_s: float | None = None  # default: 0.3 x trim speed


def envelope(limits: Limits, model: Model, trim: Trim) -> tuple[float, float, float, float]:
    """The alpha and airspeed limits in JSBSim's units, so the flight loop compares raw values.

    Parameters
    ----------
    limits : Limits
        Departure limits; None entries take defaults from the model and trim.
    model : Model
        The loaded JSBSim model (its alpha limits).
    trim : Trim
        The trim (its airspeed).

    Returns
    -------
    tuple of float
        (lowest alpha, highest alpha) in rad and (lowest, highest) airspeed in ft/s.
    """
    if limits.alpha_rad is not None:
        a_lo, a_hi = limits.alpha_rad
    elif model.alpha_limits is not None:
        a_lo = model.alpha_limits[0] - math.radians(5)
        a_hi = model.alpha_limits[1] + math.radians(5)
    else:
        a_lo, a_hi = math.radians(-20), math.radians(30)
    v_hi = limits.max_speed_m_s if limits.max_speed_m_s is not None else 2.0 * trim.speed_m_s
    v_lo = limits.min_speed_m_s if limits.min_speed_m_s is not None else 0.3 * trim.speed_m_s
    return a_lo, a_hi, v_lo / FT, v_hi / FT


def departure_reason(row: Sequence[float], col: Mapping[str, int],
                     bounds: tuple[float, float, float, float], agl_node: Any,
                     wow_node: Any) -> str | None:
    """Why the sample ``row`` left the envelope ``bounds``, or None.

    The height above ground and weight on wheels are read from their property nodes when the
    row lacks them.

    Parameters
    ----------
    row : sequence of float
        Raw JSBSim values of one sample.
    col : Mapping of str to int
        Column index of each property in ``row``.
    bounds : tuple of float
        Alpha (rad) and airspeed (ft/s) limits from :func:`envelope`.
    agl_node : JSBSim property node
        Height above ground, ft.
    wow_node : JSBSim property node
        Weight on wheels.

    Returns
    -------
    str or None
        The reason (SI units in the text), or None inside the envelope.
    """
    if not all(map(math.isfinite, row)):
        bad = [p for p, i in col.items() if not math.isfinite(row[i])]
        return f"state is not finite ({', '.join(bad[:4])})"
    alpha, vt = row[col["aero/alpha-rad"]], row[col["velocities/vt-fps"]]
    a_lo, a_hi, v_lo, v_hi = bounds
    agl = row[col[AGL]] if AGL in col else agl_node.get_double_value()
    wow = row[col[WOW]] if WOW in col else wow_node.get_double_value()
    if agl <= 0 or wow > 0:
        return f"ground contact (altitude AGL {agl * FT:.1f} m)"
    if not a_lo <= alpha <= a_hi:
        return (f"alpha {math.degrees(alpha):.1f} deg left the range "
                f"{math.degrees(a_lo):.1f}..{math.degrees(a_hi):.1f} deg")
    if vt > v_hi:
        return f"over-speed: {vt * FT:.1f} m/s > {v_hi * FT:.1f} m/s"
    if vt < v_lo:
        return f"airspeed {vt * FT:.1f} m/s fell below {v_lo * FT:.1f} m/s"
    return None
