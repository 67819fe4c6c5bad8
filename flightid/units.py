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
