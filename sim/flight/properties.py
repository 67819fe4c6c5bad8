"""The JSBSim properties a flight reads (raw, JSBSim units) and their conversion to the
canonical SI channels: a table of the channels that are one property times a constant
(``scaled_channels``) and the few computed ones (lift and drag coefficients, wind,
turbulence in body axes, north and east). Floats or arrays alike.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from flightid.record import Reference
from flightid.sim.jsbsim.model import (
    SURFACES,
)
from flightid.units import EARTH_RADIUS_M, FT, LBF, PSF, SLUG, SLUG_FT2, SLUG_FT3

# departure only (not channels): the flight loop reads them only within NEAR_GROUND_FT
# of the trim's terrain (the height above sea level, read anyway, tells)
AGL, WOW = "position/h-agl-ft", "gear/wow"
NEAR_GROUND_FT = 300.0

# raw JSBSim properties of every sample, in row order (JSBSim units)
RAW = (
    "velocities/u-aero-fps", "velocities/v-aero-fps", "velocities/w-aero-fps",
    "velocities/p-rad_sec", "velocities/q-rad_sec", "velocities/r-rad_sec",
    "velocities/p-aero-rad_sec", "velocities/q-aero-rad_sec", "velocities/r-aero-rad_sec",
    "attitude/phi-rad", "attitude/theta-rad", "attitude/psi-rad",
    "aero/alpha-rad", "aero/beta-rad", "velocities/vt-fps", "aero/qbar-psf",
    "atmosphere/rho-slugs_ft3", "position/h-sl-ft", "velocities/mach",
    "forces/fbx-total-lbs", "forces/fby-total-lbs", "forces/fbz-total-lbs",
    "accelerations/pdot-rad_sec2", "accelerations/qdot-rad_sec2", "accelerations/rdot-rad_sec2",
    "fcs/elevator-pos-rad", "fcs/left-aileron-pos-rad", "fcs/rudder-pos-rad",
    "fcs/throttle-pos-norm", "forces/fbx-prop-lbs", "inertia/mass-slugs",
    "inertia/ixx-slugs_ft2", "inertia/iyy-slugs_ft2", "inertia/izz-slugs_ft2",
    "inertia/ixz-slugs_ft2",
    "forces/fbx-aero-lbs", "forces/fby-aero-lbs", "forces/fbz-aero-lbs",
    "moments/l-aero-lbsft", "moments/m-aero-lbsft", "moments/n-aero-lbsft",
    "moments/l-prop-lbsft", "moments/m-prop-lbsft", "moments/n-prop-lbsft",
    "atmosphere/total-wind-north-fps", "atmosphere/total-wind-east-fps",
    "atmosphere/total-wind-down-fps",
    "atmosphere/turb-north-fps", "atmosphere/turb-east-fps", "atmosphere/turb-down-fps",
    "position/lat-geod-rad", "position/long-gc-rad", AGL, WOW,
)
FLAP = "fcs/flap-pos-rad"
# rotation speed, first one the aircraft has: a JSBSim propeller, a JSBSim engine, or an
# FCS function (the Telemaster computes its propeller rpm from the throttle)
RPM = ("propulsion/engine[0]/propeller-rpm", "propulsion/engine[0]/engine-rpm",
        "fcs/propeller-rpm")
AXES = ("north", "east", "down")
GUST = tuple(f"atmosphere/gust-{a}-fps" for a in AXES)
STEADY_WIND = tuple(f"atmosphere/wind-{a}-fps" for a in AXES)
TOTAL_WIND = tuple(f"atmosphere/total-wind-{a}-fps" for a in AXES)
TURB = tuple(f"atmosphere/turb-{a}-fps" for a in AXES)
RATES = ("velocities/p-rad_sec", "velocities/q-rad_sec", "velocities/r-rad_sec")
AERO_RATES = ("velocities/p-aero-rad_sec", "velocities/q-aero-rad_sec",
               "velocities/r-aero-rad_sec")
# not read per sample when JSBSim's turbulence is off (FGAuxiliary: aero rates = body
# rates - turbulence rates; FGWinds: total wind = wind + gust + cosine gust + turbulence)
CALM_FILLED = AERO_RATES + TURB + TOTAL_WIND




def scaled_channels(ref: Reference) -> dict[str, tuple[str, float, str | None]]:
    """The channels that are one raw JSBSim property times a constant, or over a second one.

    SI value = raw * factor [/ divisor]. :func:`channels_from_raw` converts them with this
    table, and ``Simulation.stepper`` reads only the properties of the channels it is asked
    for.

    Parameters
    ----------
    ref : Reference
        Reference geometry (area, m^2; span, chord, m).

    Returns
    -------
    dict of str to tuple
        Channel -> (property, factor, divisor property or None).
    """
    qs = PSF * ref.area  # N per psf of dynamic pressure
    two_ft = 2.0 * FT  # phat = p b / 2V = p (b / 2 FT) / vt
    table: dict[str, tuple[str, float, str | None]] = {
        "u": ("velocities/u-aero-fps", FT, None), "v": ("velocities/v-aero-fps", FT, None),
        "w": ("velocities/w-aero-fps", FT, None),
        "p": ("velocities/p-rad_sec", 1.0, None), "q": ("velocities/q-rad_sec", 1.0, None),
        "r": ("velocities/r-rad_sec", 1.0, None),
        "phi": ("attitude/phi-rad", 1.0, None), "theta": ("attitude/theta-rad", 1.0, None),
        "psi": ("attitude/psi-rad", 1.0, None),
        "alpha": ("aero/alpha-rad", 1.0, None), "beta": ("aero/beta-rad", 1.0, None),
        "V": ("velocities/vt-fps", FT, None), "qbar": ("aero/qbar-psf", PSF, None),
        "rho": ("atmosphere/rho-slugs_ft3", SLUG_FT3, None),
        "h": ("position/h-sl-ft", FT, None), "mach": ("velocities/mach", 1.0, None),
        # specific force = non-gravitational force / mass (what an accelerometer reads)
        "ax": ("forces/fbx-total-lbs", FT, "inertia/mass-slugs"),
        "ay": ("forces/fby-total-lbs", FT, "inertia/mass-slugs"),
        "az": ("forces/fbz-total-lbs", FT, "inertia/mass-slugs"),
        "pdot": ("accelerations/pdot-rad_sec2", 1.0, None),
        "qdot": ("accelerations/qdot-rad_sec2", 1.0, None),
        "rdot": ("accelerations/rdot-rad_sec2", 1.0, None),
        "de": ("fcs/elevator-pos-rad", SURFACES["de"][1], None),
        "da": ("fcs/left-aileron-pos-rad", SURFACES["da"][1], None),
        "dr": ("fcs/rudder-pos-rad", SURFACES["dr"][1], None),
        "throttle": ("fcs/throttle-pos-norm", 1.0, None),
        "thrust": ("forces/fbx-prop-lbs", LBF, None),
        "L_prop": ("moments/l-prop-lbsft", LBF * FT, None),
        "M_prop": ("moments/m-prop-lbsft", LBF * FT, None),
        "N_prop": ("moments/n-prop-lbsft", LBF * FT, None),
        "mass": ("inertia/mass-slugs", SLUG, None),
        "Ixx": ("inertia/ixx-slugs_ft2", SLUG_FT2, None),
        "Iyy": ("inertia/iyy-slugs_ft2", SLUG_FT2, None),
        "Izz": ("inertia/izz-slugs_ft2", SLUG_FT2, None),
        # JSBSim reports the tensor element -Ixz; the channel is Etkin's Ixz
        "Ixz": ("inertia/ixz-slugs_ft2", -SLUG_FT2, None),
        "CX": ("forces/fbx-aero-lbs", LBF / qs, "aero/qbar-psf"),
        "CY": ("forces/fby-aero-lbs", LBF / qs, "aero/qbar-psf"),
        "CZ": ("forces/fbz-aero-lbs", LBF / qs, "aero/qbar-psf"),
        "Cl": ("moments/l-aero-lbsft", LBF * FT / (qs * ref.span), "aero/qbar-psf"),
        "Cm": ("moments/m-aero-lbsft", LBF * FT / (qs * ref.chord), "aero/qbar-psf"),
        "Cn": ("moments/n-aero-lbsft", LBF * FT / (qs * ref.span), "aero/qbar-psf"),
        "phat": ("velocities/p-aero-rad_sec", ref.span / two_ft, "velocities/vt-fps"),
        "qhat": ("velocities/q-aero-rad_sec", ref.chord / two_ft, "velocities/vt-fps"),
        "rhat": ("velocities/r-aero-rad_sec", ref.span / two_ft, "velocities/vt-fps"),
        "latitude": ("position/lat-geod-rad", 1.0, None),
        "longitude": ("position/long-gc-rad", 1.0, None),
    }
    return table


def channels_from_raw(c: Mapping[str, Any], table: Mapping[str, tuple[str, float, str | None]],
              lat0: float, lon0: float, rpm: str | None, sin: Callable, cos: Callable
              ) -> dict[str, Any]:
    """Canonical SI channels from raw JSBSim values: floats (math) or arrays (numpy).

    Parameters
    ----------
    c : Mapping of str to float or numpy.ndarray
        Raw JSBSim values by property.
    table : Mapping of str to tuple
        :func:`scaled_channels` of the aircraft's reference.
    lat0, lon0 : float
        Latitude and longitude of the origin of north/east, rad.
    rpm : str or None
        Property of the engine speed, or None.
    sin, cos : callable
        ``math`` or ``numpy`` functions, matching the values.

    Returns
    -------
    dict of str to float or numpy.ndarray
        Channels by name, SI.
    """
    out = {ch: c[p] * k if d is None else c[p] * k / c[d] for ch, (p, k, d) in table.items()}
    alpha, fx, fz = out["alpha"], out["CX"], out["CZ"]
    out["CL"] = fx * sin(alpha) - fz * cos(alpha)
    out["CD"] = -fx * cos(alpha) - fz * sin(alpha)
    for axis, total, turb in zip(AXES, TOTAL_WIND, TURB, strict=True):
        out[f"wind_{axis}"] = (c[total] - c[turb]) * FT
    out["turb_u"], out["turb_v"], out["turb_w"] = rotate_to_body(
        *(c[p] * FT for p in TURB), out["phi"], out["theta"], out["psi"], sin, cos)
    out["north"] = (out["latitude"] - lat0) * EARTH_RADIUS_M
    out["east"] = (out["longitude"] - lon0) * EARTH_RADIUS_M * math.cos(lat0)
    if FLAP in c:
        out["df"] = c[FLAP]
    if rpm is not None:
        out["rpm"] = c[rpm]
    return out


def rotate_to_body(n: Any, e: Any, d: Any, phi: Any, theta: Any, psi: Any,
                    sin: Callable, cos: Callable) -> tuple[Any, Any, Any]:
    """NED components into body axes with the 3-2-1 Euler angles (Etkin); floats or arrays.

    Parameters
    ----------
    n, e, d : float or numpy.ndarray
        North, east and down components.
    phi, theta, psi : float or numpy.ndarray
        Euler angles, rad.
    sin, cos : callable
        ``math`` or ``numpy`` functions, matching the values.

    Returns
    -------
    tuple
        (x, y, z) body components, unit of the input.
    """
    cf, sf, ct, st, cp, sp = cos(phi), sin(phi), cos(theta), sin(theta), cos(psi), sin(psi)
    x = ct * cp * n + ct * sp * e - st * d
    y = (sf * st * cp - cf * sp) * n + (sf * st * sp + cf * cp) * e + sf * ct * d
    z = (cf * st * cp + sf * sp) * n + (cf * st * sp - sf * cp) * e + cf * ct * d
    return x, y, z


def ned_to_body(vec: np.ndarray, phi: np.ndarray, theta: np.ndarray,
                 psi: np.ndarray) -> np.ndarray:
    """Rotate NED vectors into body axes with the 3-2-1 Euler angles (Etkin).

    Parameters
    ----------
    vec : numpy.ndarray
        NED vectors; shape (3, n).
    phi, theta, psi : numpy.ndarray
        Euler angles, rad; shape (n,).

    Returns
    -------
    numpy.ndarray
        Body-axis vectors, unit of ``vec``; shape (3, n).
    """
    return np.stack(rotate_to_body(*vec, phi, theta, psi, np.sin, np.cos))


def book_turbulence(ch: dict[str, np.ndarray], turb_ned: np.ndarray) -> None:
    """Book a turbulence schedule under turb_u/v/w, not wind_*.

    Parameters
    ----------
    ch : dict of str to numpy.ndarray
        The record's channels; wind_* and turb_* changed in place.
    turb_ned : numpy.ndarray
        Turbulence, NED, m/s; shape (n, 3).
    """
    for i, axis in enumerate(AXES):
        ch[f"wind_{axis}"] = ch[f"wind_{axis}"] - turb_ned[:, i]
    body = rotate_to_body(*turb_ned.T, ch["phi"], ch["theta"], ch["psi"], np.sin, np.cos)
    for axis, b in zip("uvw", body, strict=True):
        ch[f"turb_{axis}"] = ch[f"turb_{axis}"] + b


def divide(a: float, b: float) -> float:
    """a / b with numpy's answer for b = 0 (+-inf, or nan for 0 / 0), as records have.

    Parameters
    ----------
    a, b : float
        Numerator and denominator.

    Returns
    -------
    float
        The quotient.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.float64(a) / b)
