"""Unit sanity of a flight record: channels whose magnitudes cannot be in their declared
SI unit (angles in degrees where rad is declared, rates in deg/s, speeds in knots or ft/s
where m/s is declared), each reported with the likely cause.

The limits are physical, not statistical: no airplane flies at an angle of attack, a
sideslip or a surface deflection beyond 90 deg (pi/2 rad), no attitude angle exceeds pi
(psi, which a record may unwrap, is not checked), no body rate of a flying airplane
exceeds 10 rad/s (573 deg/s), and the airspeed must agree with the dynamic pressure
(qbar = rho V^2 / 2) when both are recorded. Small values in the wrong unit (a sideslip
of a few degrees, rates of a few deg/s) pass the limits; the kinematic check catches
rates and attitudes whose units disagree: the rates of change of phi and theta must be
the Euler kinematics of p, q, r (Morelli & Klein 2016, ch. 10).
"""

from __future__ import annotations

import math

import numpy as np

from flightid.record import FlightRecord
from flightid.units import DEG, FT, KT

# channel -> (largest plausible |value| in SI, what a bigger value most likely is)
ANGLE_LIMITS: dict[str, float] = {
    "alpha": math.pi / 2, "beta": math.pi / 2, "de": math.pi / 2, "da": math.pi / 2,
    "dr": math.pi / 2, "df": math.pi / 2, "phi": math.pi, "theta": math.pi / 2,
}
RATE_LIMIT = 10.0  # rad/s, for p, q, r
SPEED_LIMIT = 350.0  # m/s: faster than sound near the ground, no flight-test airplane here
# V / sqrt(2 qbar / rho) of a speed in another unit: knots, ft/s, km/h
_SPEED_FACTORS = {"knots": 1 / KT, "ft/s": 1 / FT, "km/h": 3.6}


def implausible(record: FlightRecord, channels: list[str] | None = None) -> list[str]:
    """One message per channel (of ``channels``, default all) whose magnitude is not
    plausible in its declared unit, naming the likely cause; [] when all are plausible."""
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
                f"{name} reaches {peak:.4g} rad ({math.degrees(peak):.0f} deg), beyond "
                f"{ANGLE_LIMITS[name]:.3g} rad: it is probably in degrees; convert it to rad")
        elif name in ("p", "q", "r") and unit == "rad/s" and peak > RATE_LIMIT:
            problems.append(
                f"{name} reaches {peak:.4g} rad/s, beyond {RATE_LIMIT:g} rad/s: it is "
                "probably in deg/s; convert it to rad/s")
        elif name == "V" and unit == "m/s":
            problems.extend(_speed(record, peak))
    if any(c in names for c in ("p", "q", "r", "phi", "theta")):
        problems.extend(_attitude_rates(record))
    return problems


def _attitude_rates(record: FlightRecord) -> list[str]:
    scale = euler_rate_scale(record)
    if scale is None:
        return []
    if abs(scale * (1 / DEG) - 1) < 0.15:  # rates 57.3 times too big
        return ["p, q, r are about 57.3 times the rates of change of phi and theta: the "
                "rates are probably in deg/s (or the attitudes in rad where they are not); "
                "convert them to rad/s"]
    if abs(scale * DEG - 1) < 0.15:
        return ["phi and theta change about 57.3 times faster than p, q, r say: the "
                "attitudes are probably in degrees; convert them to rad"]
    return []


def _speed(record: FlightRecord, peak: float) -> list[str]:
    if peak > SPEED_LIMIT:
        return [f"V reaches {peak:.4g} m/s, beyond {SPEED_LIMIT:g} m/s: it is probably in "
                "knots, ft/s or km/h; convert it to m/s"]
    if "qbar" not in record or "rho" not in record:
        return []
    v, qbar, rho = record["V"], record["qbar"], record["rho"]
    ok = np.isfinite(v) & np.isfinite(qbar) & np.isfinite(rho) & (qbar > 0) & (rho > 0)
    if ok.sum() < 3:
        return []
    ratio = float(np.median(v[ok] / np.sqrt(2 * qbar[ok] / rho[ok])))
    for unit, factor in _SPEED_FACTORS.items():
        if abs(ratio / factor - 1) < 0.05:
            return [f"V is {ratio:.3g} times the airspeed of qbar and rho "
                    f"(sqrt(2 qbar / rho)): it is probably in {unit}; convert it to m/s"]
    return []


def check_units(record: FlightRecord, channels: list[str] | None = None,
                purpose: str = "identification") -> None:
    """Raise ValueError listing every implausible channel and its likely cause."""
    problems = implausible(record, channels)
    if problems:
        raise ValueError(f"the record's units look wrong for {purpose}: "
                         + "; ".join(problems))


def euler_rate_scale(record: FlightRecord) -> float | None:
    """The least-squares scale s of (dphi/dt, dtheta/dt) = s * (Euler kinematics of p, q,
    r): 1 when attitudes and rates share their unit, 1/57.3 when the rates are in deg/s
    with attitudes in rad, 57.3 in the reverse case (Morelli & Klein 2016, sec. 10.2, the
    kinematic equations used for data compatibility). None when the channels are missing
    or the attitude does not move."""
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
    energy = float(model @ model)
    if energy <= 0 or float(measured @ measured) <= 1e-12 * len(measured):
        return None
    return float(model @ measured) / energy
