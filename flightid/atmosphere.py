"""The ISA standard atmosphere (ICAO Doc 7488 / ISO 2533), troposphere: what a record
without a density channel is assumed to have flown in."""

from __future__ import annotations

import numpy as np

from flightid.units import G0

# sea-level constants and the troposphere's temperature lapse
P0, T0, RHO0, LAPSE, R_AIR = 101325.0, 288.15, 1.225, 0.0065, 287.05287
_EXP = G0 / (LAPSE * R_AIR)  # 5.2559


def isa(h: float) -> tuple[float, float, float]:
    """ISA troposphere at altitude h: static pressure, temperature and density.

    Parameters
    ----------
    h : float
        Altitude, m.

    Returns
    -------
    tuple of float
        (static pressure, Pa; temperature, K; density, kg/m^3).
    """
    temp = T0 - LAPSE * h
    p = P0 * (temp / T0) ** _EXP
    return p, temp, p / (R_AIR * temp)


def isa_density(h: np.ndarray | float) -> np.ndarray:
    """ISA density at altitudes h, troposphere (0-11 km; clipped to it).

    Parameters
    ----------
    h : numpy.ndarray or float
        Altitude, m; clipped to -1000..11000 m.

    Returns
    -------
    numpy.ndarray
        Density, kg/m^3; same shape as ``h``.
    """
    temp = T0 - LAPSE * np.clip(np.asarray(h, dtype=float), -1000.0, 11000.0)
    return P0 * (temp / T0) ** _EXP / (R_AIR * temp)


def isa_pressure_altitude(p: np.ndarray | float) -> np.ndarray:
    """Altitude of the ISA troposphere at static pressure p.

    The inverse of :func:`isa`'s pressure (what an altimeter set to 1013.25 hPa reads).

    Parameters
    ----------
    p : numpy.ndarray or float
        Static pressure, Pa.

    Returns
    -------
    numpy.ndarray
        Pressure altitude, m; same shape as ``p``.
    """
    return T0 / LAPSE * (1.0 - (np.asarray(p, dtype=float) / P0) ** (1.0 / _EXP))
