"""Unit sanity of a flight record, judged from the record itself: channels whose values
cannot be in their declared SI unit (angles in degrees, rates in deg/s, an airspeed in
knots, accelerations in g, a mass in slugs), each reported with the likely unit.

Two kinds of evidence, neither needing a channel the record may lack:

* limits: no airplane flies at an angle of attack, a sideslip or a surface deflection
  beyond 90 deg (pi/2 rad), no attitude angle exceeds pi (psi, which a record may unwrap,
  is not checked), no body rate exceeds 10 rad/s, no airspeed here exceeds 350 m/s;
* physics between channels, as ratios that are 1 in consistent SI units:

  - airspeed and dynamic pressure: 0.5 rho V^2 / qbar, with rho the record's density or,
    without one, the ISA density at the record's altitude (knots: 1.944^2 = 3.78, ft/s:
    10.8, km/h: 13.0; qbar in lbf/ft^2: 47.9);
  - airspeed and the body velocities: V / sqrt(u^2 + v^2 + w^2);
  - specific force and gravity: the median of |(ax, ay, az)| / g0 over the record, which
    is 1 in steady flight and stays near it through the maneuvers of an identification
    flight (g: 0.102, ft/s^2: 3.28);
  - rates and attitudes: (d phi/dt, d theta/dt) = s * (Euler kinematics of p, q, r) by
    least squares (Morelli & Klein 2016, sec. 10.2): deg/s give s = 1/57.3;
  - angle of attack and flight path: alpha = theta - gamma in wings-level flight, with
    gamma = asin(dh/dt / V) (Etkin 1972, sec. 4.2): alpha in degrees is 57.3 times
    theta - gamma;
  - mass and inertia against the airframe: the lift coefficient m |az| / (qbar S) between
    0.02 and 3 (a mass in slugs gives 1/14.6 of it), the radii of gyration I / (m b^2)
    between 0.002 and 0.2 (Roskam, Airplane Design VI, Table 4.x: 0.01-0.05 for every
    class; imperial mass and inertia give 10.8 times the value).

A check that lacks its channels, or whose signal does not move, is skipped. The tolerance
of each ratio is wide enough for the atmosphere off standard (about +-10 % in density),
turbulence and the maneuvers, and far from the nearest unit factor (docs/errors.md gives
the ratios measured on the library's flights and the NASA Twin Otter record).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flightid.atmosphere import isa_density
from flightid.record import FlightRecord
from flightid.units import DEG, FT, G0, KT, PSF, SLUG, SLUG_FT3

ANGLE_LIMITS: dict[str, float] = {
    "alpha": math.pi / 2, "beta": math.pi / 2, "de": math.pi / 2, "da": math.pi / 2,
    "dr": math.pi / 2, "df": math.pi / 2, "phi": math.pi, "theta": math.pi / 2,
}
RATE_LIMIT = 10.0  # rad/s, for p, q, r
SPEED_LIMIT = 350.0  # m/s: faster than sound near the ground, no flight-test airplane here
# accepted band of each ratio (1 in SI); outside it the nearest known unit factor is named
RATIO_BANDS: dict[str, tuple[float, float]] = {
    "airspeed_qbar": (0.6, 1.6), "airspeed_qbar_sea_level": (0.2, 1.6),
    "airspeed_uvw": (0.8, 1.25), "gravity": (0.6, 1.6),
    "euler_rates": (0.5, 2.0), "lift_coefficient": (0.08, 3.0), "gyration": (0.01, 0.4),
}
# ratio -> what it most likely means, per check
_AIRSPEED_UNITS = {"V looks like knots": (1 / KT) ** 2, "V looks like ft/s": (1 / FT) ** 2,
                   "V looks like km/h": 3.6 ** 2, "V looks like mph": (3600 / 1609.344) ** 2,
                   "qbar looks like lbf/ft^2 (psf)": PSF,
                   "qbar looks like kPa": 1000.0,
                   "rho looks like slug/ft^3": 1 / SLUG_FT3}
_UVW_UNITS = {"V looks like knots": 1 / KT, "V looks like ft/s": 1 / FT,
              "V looks like km/h": 3.6, "u, v, w look like knots": KT, "u, v, w look like "
              "ft/s": FT}
_GRAVITY_UNITS = {"ax, ay, az look like g": 1 / G0, "ax, ay, az look like ft/s^2": 1 / FT}
_EULER_UNITS = {"p, q, r look like deg/s": DEG, "phi, theta look like degrees": 1 / DEG}
_LIFT_UNITS = {"mass looks like slugs": 1 / SLUG}
# typical I/(m b^2) sums: 0.05-0.09 (the library's airplanes), about 0.2 for a fighter
_GYRATION_TYPICAL = 0.07
_GYRATION_UNITS = {"mass looks like slugs (or mass and inertias like slugs and slug ft^2)":
                   1 / (FT * FT)}
_LIFT_TYPICAL = 0.5
MIN_CORRELATION = 0.7  # of the Euler kinematics with the attitude rates, to judge a scale
_WINGS_LEVEL = 0.35  # rad (20 deg): median bank angle below which alpha = theta - gamma
_ALPHA_GAP = 0.15  # rad (8.6 deg): alpha - (theta - gamma) beyond this is not wind or lag


@dataclass(frozen=True)
class UnitRatio:
    """One physical ratio of a record: its name, its value (1 in SI), what it compares."""

    name: str
    value: float
    formula: str


def unit_ratios(record: FlightRecord) -> dict[str, UnitRatio]:
    """Every ratio of the module docstring that the record's channels allow, by name.

    Parameters
    ----------
    record : FlightRecord
        The flight, channels in their declared units.

    Returns
    -------
    dict of str to UnitRatio
        The ratios by name.
    """
    found = (_airspeed_qbar(record), _airspeed_uvw(record), _gravity(record),
             _euler(record), _lift_coefficient(record), _gyration(record))
    return {r.name: r for r in found if r is not None}


def implausible(record: FlightRecord, channels: list[str] | None = None) -> list[str]:
    """One message per channel whose magnitude is not plausible in its declared unit, and per
    physical ratio outside its band, naming the likely unit.

    Parameters
    ----------
    record : FlightRecord
        The flight, channels in their declared units.
    channels : list of str, optional
        The channels judged. Default all.

    Returns
    -------
    list of str
        The messages; [] when all are plausible.
    """
    names = [c for c in (channels if channels is not None else record.channels)
             if c in record]
    problems = []
    for name in names:
        values = record[name]
        finite = values[np.isfinite(values)]
        if finite.size == 0:
            continue
        peak = float(np.max(np.abs(finite)))
        unit = record.unit(name)
        if name in ANGLE_LIMITS and unit == "rad" and peak > ANGLE_LIMITS[name]:
            problems.append(
                f"{name} looks like degrees ({name} reaches {peak:.4g} rad, "
                f"{math.degrees(peak):.0f} deg, beyond {ANGLE_LIMITS[name]:.3g} rad); "
                "convert it to rad")
        elif name in ("p", "q", "r") and unit == "rad/s" and peak > RATE_LIMIT:
            problems.append(
                f"{name} looks like deg/s ({name} reaches {peak:.4g} rad/s, beyond "
                f"{RATE_LIMIT:g} rad/s); convert it to rad/s")
        elif name == "V" and unit == "m/s" and peak > SPEED_LIMIT:
            problems.append(f"V looks like knots, ft/s or km/h (V reaches {peak:.4g} m/s, "
                            f"beyond {SPEED_LIMIT:g} m/s); convert it to m/s")
    if problems:  # one wrong unit explains the ratios that follow from it
        return problems
    for ratio in unit_ratios(record).values():
        # the lift coefficient judges the mass once az and qbar are known to be in SI
        if ratio.name != "lift_coefficient" or not problems:
            problems.extend(_judge(ratio))
    problems.extend(_alpha_flight_path(record))
    return problems


def check_units(record: FlightRecord, channels: list[str] | None = None,
                purpose: str = "identification") -> None:
    """Raise ValueError ("units look wrong: ...") listing every implausible channel and
    ratio with its likely unit.

    Parameters
    ----------
    record : FlightRecord
        The flight, channels in their declared units.
    channels : list of str, optional
        The channels judged. Default all.
    purpose : str, optional
        What the record is for, named in the error. Default "identification".

    Raises
    ------
    ValueError
        When any channel or ratio is implausible.
    """
    problems = implausible(record, channels)
    if problems:
        raise ValueError(f"units look wrong for {purpose}: " + "; ".join(problems))


def euler_rate_scale(record: FlightRecord) -> float | None:
    """The least-squares scale s of (dphi/dt, dtheta/dt) = s * (Euler kinematics of p, q, r).

    1 when attitudes and rates share their unit, 1/57.3 when the rates are in deg/s with
    attitudes in rad, 57.3 in the reverse case (Morelli & Klein 2016, sec. 10.2, the
    kinematic equations used for data compatibility).

    Parameters
    ----------
    record : FlightRecord
        The flight, channels in their declared units.

    Returns
    -------
    float or None
        The scale, 1; None when the channels are missing, the attitude does not move, or its
        motion does not follow the rates.
    """
    need = ("phi", "theta", "p", "q", "r")
    if any(c not in record for c in need) or len(record) < 10:
        return None
    t = record.time
    phi, theta, p, q, r = (record[c] for c in need)
    if not all(np.all(np.isfinite(x)) for x in (phi, theta, p, q, r)):
        return None
    phi_dot, theta_dot = np.gradient(phi, t), np.gradient(theta, t)
    # evaluated with the attitudes as given: for small attitudes the trigonometry hardly
    # depends on their unit, the scale is carried by the rates
    phi_k = p + np.tan(theta) * (q * np.sin(phi) + r * np.cos(phi))
    theta_k = q * np.cos(phi) - r * np.sin(phi)
    model = np.concatenate([phi_k, theta_k])
    measured = np.concatenate([phi_dot, theta_dot])
    energy, measured_energy = float(model @ model), float(measured @ measured)
    if energy <= 0 or measured_energy <= 1e-12 * len(measured):
        return None
    # a scale means something only where the attitude's motion follows the rates (a
    # quiet record's drift and noise do not)
    if float(model @ measured) / np.sqrt(energy * measured_energy) < MIN_CORRELATION:
        return None
    return float(model @ measured) / energy


# -- the ratios ---------------------------------------------------------------------------

def _median(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else math.nan


def _density(record: FlightRecord) -> tuple[np.ndarray, str]:
    """The record's density, else the ISA's at its altitude channel, else at the altitude
    of its flight condition, else at sea level (then the ratio is at most 1 in SI units
    and still 2.5 for knots at 4 km)."""
    if "rho" in record:
        return record["rho"], "rho"
    if "h" in record:
        return isa_density(record["h"]), "rho of the ISA at h"
    condition = record.meta.condition or {}
    altitude = next((condition[k] for k in ("altitude_m", "h") if isinstance(
        condition.get(k), int | float)), None)
    if altitude is not None:
        return (isa_density(np.full(len(record), float(altitude))),
                f"rho of the ISA at the condition's {float(altitude):g} m")
    return isa_density(np.zeros(len(record))), "rho of the ISA at sea level"


def _airspeed_qbar(record: FlightRecord) -> UnitRatio | None:
    if "V" not in record or "qbar" not in record:
        return None
    rho = _density(record)
    v, qbar = record["V"], record["qbar"]
    ok = (qbar > 0) & (rho[0] > 0) & (v > 0)
    if ok.sum() < 3:
        return None
    value = _median(0.5 * rho[0][ok] * v[ok] ** 2 / qbar[ok])
    name = "airspeed_qbar_sea_level" if rho[1].endswith("sea level") else "airspeed_qbar"
    return UnitRatio(name, value, f"0.5 rho V^2 / qbar ({rho[1]})")


def _airspeed_uvw(record: FlightRecord) -> UnitRatio | None:
    if any(c not in record for c in ("V", "u", "v", "w")):
        return None
    speed = np.sqrt(record["u"] ** 2 + record["v"] ** 2 + record["w"] ** 2)
    ok = speed > 0
    if ok.sum() < 3:
        return None
    return UnitRatio("airspeed_uvw", _median(record["V"][ok] / speed[ok]),
                     "V / sqrt(u^2 + v^2 + w^2)")


def _gravity(record: FlightRecord) -> UnitRatio | None:
    if any(c not in record for c in ("ax", "ay", "az")):
        return None
    force = np.sqrt(record["ax"] ** 2 + record["ay"] ** 2 + record["az"] ** 2)
    return UnitRatio("gravity", _median(force) / G0, "|(ax, ay, az)| / g0")


def _euler(record: FlightRecord) -> UnitRatio | None:
    scale = euler_rate_scale(record)
    if scale is None:
        return None
    return UnitRatio("euler_rates", scale,
                     "(dphi/dt, dtheta/dt) / Euler kinematics of (p, q, r)")


def _lift_coefficient(record: FlightRecord) -> UnitRatio | None:
    ref = record.meta.reference
    if ref is None or any(c not in record for c in ("mass", "az", "qbar")):
        return None
    qbar = _median(record["qbar"])
    if not qbar > 0 or not ref.area > 0:
        return None
    value = _median(record["mass"]) * abs(_median(record["az"])) / (qbar * ref.area)
    return UnitRatio("lift_coefficient", value, "mass |az| / (qbar S)")


def _gyration(record: FlightRecord) -> UnitRatio | None:
    ref = record.meta.reference
    axes = ("Ixx", "Iyy", "Izz")
    if ref is None or any(c not in record for c in ("mass", *axes)) or not ref.span > 0:
        return None
    mass = _median(record["mass"])
    if not mass > 0:
        return None
    value = sum(_median(record[c]) for c in axes) / (mass * ref.span ** 2)
    return UnitRatio("gyration", value, "(Ixx + Iyy + Izz) / (mass b^2)")


def _judge(ratio: UnitRatio) -> list[str]:
    band = RATIO_BANDS[ratio.name]
    if not math.isfinite(ratio.value) or band[0] <= ratio.value <= band[1]:
        return []
    if ratio.value <= 0:
        return [f"the units or signs of {ratio.formula} look wrong ({ratio.formula} = "
                f"{ratio.value:.3g}, expected {band[0]:g}-{band[1]:g} in SI units)"]
    factors = {"airspeed_qbar": _AIRSPEED_UNITS, "airspeed_qbar_sea_level": _AIRSPEED_UNITS,
               "airspeed_uvw": _UVW_UNITS,
               "gravity": _GRAVITY_UNITS, "euler_rates": _EULER_UNITS,
               "lift_coefficient": _LIFT_UNITS}.get(ratio.name, _GYRATION_UNITS)
    nominal = {"lift_coefficient": _LIFT_TYPICAL, "gyration": _GYRATION_TYPICAL
               }.get(ratio.name, 1.0)
    likely = min(factors, key=lambda k: abs(math.log(ratio.value / (nominal * factors[k]))))
    if abs(math.log(ratio.value / (nominal * factors[likely]))) > math.log(1.5):
        likely = f"the units of {ratio.formula.split(' (rho')[0]} look wrong"
    return [f"{likely} ({ratio.formula} = {ratio.value:.3g}, expected "
            f"{band[0]:g}-{band[1]:g} in SI units)"]


def _alpha_flight_path(record: FlightRecord) -> list[str]:
    """alpha against theta - gamma in wings-level flight (gamma from the climb rate)."""
    if any(c not in record for c in ("alpha", "theta", "h", "V")) or len(record) < 10:
        return []
    if "phi" in record and abs(_median(record["phi"])) > _WINGS_LEVEL:
        return []
    v = record["V"]
    if not _median(v) > 0:
        return []
    climb = np.gradient(record["h"], record.time)
    gamma = np.arcsin(np.clip(climb / np.maximum(v, 1e-3), -1, 1))
    alpha, kinematic = _median(record["alpha"]), _median(record["theta"] - gamma)
    gap = abs(alpha - kinematic)
    if gap > _ALPHA_GAP and abs(alpha * DEG - kinematic) < gap / 3:
        return [f"alpha looks like degrees (median alpha {alpha:.3g}, theta - gamma "
                f"{kinematic:.3g} rad; alpha * pi/180 = {alpha * DEG:.3g})"]
    return []
