"""Unit conversions to SI, applied once at the boundary (JSBSim, SIDPAC, MAVLink)."""

from __future__ import annotations

import math

FT = 0.3048  # m per ft (exact)
IN = 0.0254  # m per in (exact)
LBF = 4.4482216152605  # N per lbf
SLUG = 14.593902937206364  # kg per slug (lbf s^2 / ft)
SLUG_FT2 = SLUG * FT**2  # kg m^2 per slug ft^2
PSF = LBF / FT**2  # Pa per lbf/ft^2
SLUG_FT3 = SLUG / FT**3  # kg/m^3 per slug/ft^3
G0 = 9.80665  # m/s^2 per g (standard gravity)
KT = 1852.0 / 3600.0  # m/s per knot
DEG = math.pi / 180.0  # rad per deg
LBF_FT = LBF * FT  # N m per lbf ft
EARTH_RADIUS_M = 6_378_137.0  # WGS84 equatorial radius (m): positions from latitude/longitude
LBM = 0.45359237  # kg per pound mass (exact)
FT2 = FT**2  # m^2 per ft^2

# unit names as a flight-test file writes them (lower case, no spaces) -> (SI unit of
# flightid.channels, factor to it); "lb" is force or mass by the channel it is given for
UNIT_NAMES: dict[str, tuple[tuple[str, float], ...]] = {
    "s": (("s", 1.0),), "sec": (("s", 1.0),), "ms": (("s", 1e-3),),
    "rad": (("rad", 1.0),), "deg": (("rad", DEG),),
    "rad/s": (("rad/s", 1.0),), "deg/s": (("rad/s", DEG),),
    "rad/s^2": (("rad/s^2", 1.0),), "deg/s^2": (("rad/s^2", DEG),),
    "m/s": (("m/s", 1.0),), "kt": (("m/s", KT),), "kts": (("m/s", KT),),
    "knots": (("m/s", KT),), "ft/s": (("m/s", FT),), "fps": (("m/s", FT),),
    "km/h": (("m/s", 1 / 3.6),),
    "m": (("m", 1.0),), "ft": (("m", FT),), "in": (("m", IN),), "km": (("m", 1000.0),),
    "m^2": (("m^2", 1.0),), "ft^2": (("m^2", FT2),),
    "m/s^2": (("m/s^2", 1.0),), "g": (("m/s^2", G0),), "ft/s^2": (("m/s^2", FT),),
    "pa": (("Pa", 1.0),), "hpa": (("Pa", 100.0),), "mbar": (("Pa", 100.0),),
    "kpa": (("Pa", 1000.0),), "psf": (("Pa", PSF),), "lbf/ft^2": (("Pa", PSF),),
    "n": (("N", 1.0),), "lbf": (("N", LBF),), "kn": (("N", 1000.0),),
    "lb": (("N", LBF), ("kg", LBM)), "lbs": (("N", LBF), ("kg", LBM)),
    "kg": (("kg", 1.0),), "slug": (("kg", SLUG),), "lbm": (("kg", LBM),),
    "kg*m^2": (("kg*m^2", 1.0),), "kgm^2": (("kg*m^2", 1.0),),
    "slug*ft^2": (("kg*m^2", SLUG_FT2),), "slugft^2": (("kg*m^2", SLUG_FT2),),
    "kg/m^3": (("kg/m^3", 1.0),), "slug/ft^3": (("kg/m^3", SLUG_FT3),),
    "nm": (("N m", 1.0),), "n*m": (("N m", 1.0),), "lbf*ft": (("N m", LBF_FT),),
    "ft*lbf": (("N m", LBF_FT),),
    "1/min": (("1/min", 1.0),), "rpm": (("1/min", 1.0),),
    "-": (("-", 1.0),), "": (("-", 1.0),), "1": (("-", 1.0),), "nd": (("-", 1.0),),
}


def unit_key(text: str) -> str:
    """A unit name as :data:`UNIT_NAMES` spells it.

    Lower case, without spaces, brackets or a dot for a product ('[M/S2]' -> 'm/s^2',
    'slug ft2' -> 'slug*ft^2').

    Parameters
    ----------
    text : str
        Unit name as written.

    Returns
    -------
    str
        The normalized key.
    """
    key = text.strip().strip("[]()").strip().lower().replace("²", "^2").replace("³", "^3")
    key = key.replace("**", "^").replace("·", "*").replace(".", "*")
    key = "*".join(key.split())
    for power in ("2", "3"):  # 'm/s2', 'ft2' -> 'm/s^2', 'ft^2'
        for base in ("s", "m", "ft"):
            if key.endswith(base + power) and not key.endswith("^" + power):
                key = key[: -len(base + power)] + f"{base}^{power}"
    return key


def to_si(text: str, si_unit: str | None = None) -> tuple[str, float]:
    """(SI unit, factor) of a unit name ('DEG' -> ('rad', pi/180)).

    Parameters
    ----------
    text : str
        Unit name as written.
    si_unit : str, optional
        The unit of the quantity it is given for; decides between force and mass ('lb') and
        is checked.

    Returns
    -------
    tuple of (str, float)
        SI unit and the factor that converts a value to it.

    Raises
    ------
    ValueError
        Naming both units when ``text`` is a unit of another quantity than ``si_unit``.
    KeyError
        Naming the known units when ``text`` is unknown.
    """
    key = unit_key(text)
    if key not in UNIT_NAMES:
        raise KeyError(f"unknown unit {text!r}; known units: "
                       f"{', '.join(k for k in UNIT_NAMES if k)}")
    options = UNIT_NAMES[key]
    if si_unit is None:
        return options[0]
    for unit, factor in options:
        if unit == si_unit:
            return unit, factor
    raise ValueError(f"unit {text!r} is a unit of {' or '.join(u for u, _ in options)}, "
                     f"not of {si_unit}")
