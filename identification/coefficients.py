"""Nondimensional force and moment coefficients from a measured flight record.

The "measured" coefficients that equation error and stepwise regression fit are
computed from the specific forces, angular rates and accelerations, mass, inertia,
thrust and dynamic pressure with the rigid-body equations (Morelli & Klein 2016,
ch. 3 and 5; SIDPAC ``compfmc``), body axes, about the CG:

    CX = (m ax - T) / (qbar S)       CY = m ay / (qbar S)      CZ = m az / (qbar S)
    Cl = [Ixx pdot - Ixz (rdot + p q) + (Izz - Iyy) q r] / (qbar S b)
    Cm = [Iyy qdot + (Ixx - Izz) p r + Ixz (p^2 - r^2)] / (qbar S cbar)
    Cn = [Izz rdot - Ixz (pdot - q r) + (Iyy - Ixx) p q] / (qbar S b)

with thrust T along body x, and in stability axes CL = -CZ cos(alpha) + CX sin(alpha),
CD = -CX cos(alpha) - CZ sin(alpha). Angular accelerations come from the record when it
has them, otherwise from smoothed numerical differentiation of the rates
(Savitzky-Golay local polynomial fit, the "smoothed differentiation" of Morelli & Klein
ch. 11).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter

from flightid.record import FlightRecord

MASS_PROPERTIES = ("mass", "Ixx", "Iyy", "Izz", "Ixz")
COEFFICIENT_CHANNELS = ("CX", "CY", "CZ", "Cl", "Cm", "Cn", "CL", "CD")


def smoothed_derivative(
    x: np.ndarray, dt: float, window_s: float = 0.2, order: int = 2
) -> np.ndarray:
    """Time derivative of x (units of x per s) by a local polynomial (Savitzky-Golay) fit.

    window_s is the span of the local fit in s (rounded to an odd number of samples, at
    least order + 2); the fit smooths noise above roughly 1 / window_s Hz.
    """
    x = np.asarray(x, dtype=float)
    if dt <= 0:
        raise ValueError(f"sample interval must be positive, got {dt} s")
    n = max(int(round(window_s / dt)) | 1, order + 2 | 1)
    if x.size < n:
        raise ValueError(
            f"{x.size} samples are too few for a {n}-sample differentiation window "
            f"({window_s} s at {dt} s)"
        )
    return savgol_filter(x, n, order, deriv=1, delta=dt, mode="interp")


def nondimensional_rates(record: FlightRecord) -> dict[str, np.ndarray]:
    """phat = p b/2V, qhat = q cbar/2V, rhat = r b/2V (dimensionless) from p, q, r and V."""
    ref = _reference(record)
    two_v = 2.0 * record["V"]
    return {
        "phat": record["p"] * ref.span / two_v,
        "qhat": record["q"] * ref.chord / two_v,
        "rhat": record["r"] * ref.span / two_v,
    }


def angular_accelerations(record: FlightRecord, window_s: float = 0.2) -> dict[str, np.ndarray]:
    """pdot, qdot, rdot (rad/s^2): the record's channels, or smoothed derivatives of p, q, r."""
    out = {}
    for rate in ("p", "q", "r"):
        name = rate + "dot"
        if name in record:
            out[name] = record[name]
        else:
            out[name] = smoothed_derivative(record[rate], record.dt, window_s)
    return out


def mass_properties(record: FlightRecord) -> dict[str, np.ndarray]:
    """mass (kg) and Ixx Iyy Izz Ixz (kg m^2): record channels, else meta.extra values."""
    out = {}
    for name in MASS_PROPERTIES:
        if name in record:
            out[name] = record[name]
        elif name in record.meta.extra:
            out[name] = np.full(len(record), float(record.meta.extra[name]))
        else:
            raise ValueError(
                f"record has no {name!r}: coefficients need mass and inertia as channels "
                "or in meta.extra (SI units)"
            )
    return out


def force_moment_coefficients(
    record: FlightRecord, include_thrust: bool = True, window_s: float = 0.2
) -> dict[str, np.ndarray]:
    """CX CY CZ Cl Cm Cn (body axes, about the CG) and CL CD (stability axes), dimensionless.

    include_thrust subtracts the record's ``thrust`` channel (N, along body x) from the
    x force, so CX and CD are aerodynamic only.
    """
    ref = _reference(record)
    mp = mass_properties(record)
    acc = angular_accelerations(record, window_s)
    qs = record["qbar"] * ref.area
    if np.any(qs <= 0):
        i = int(np.argmax(qs <= 0))
        raise ValueError(f"dynamic pressure is not positive at sample {i} (t = {record.time[i]} s)")
    m = mp["mass"]
    thrust = np.zeros(len(record))
    if include_thrust:
        if "thrust" not in record:
            raise ValueError(
                "record has no 'thrust' channel; pass include_thrust=False to compute CX, CD "
                "including the propulsive force"
            )
        thrust = record["thrust"]
    p, q, r = record["p"], record["q"], record["r"]
    pdot, qdot, rdot = acc["pdot"], acc["qdot"], acc["rdot"]
    ixx, iyy, izz, ixz = mp["Ixx"], mp["Iyy"], mp["Izz"], mp["Ixz"]

    cx = (m * record["ax"] - thrust) / qs
    cy = m * record["ay"] / qs
    cz = m * record["az"] / qs
    cl = (ixx * pdot - ixz * (rdot + p * q) + (izz - iyy) * q * r) / (qs * ref.span)
    cm = (iyy * qdot + (ixx - izz) * p * r + ixz * (p * p - r * r)) / (qs * ref.chord)
    cn = (izz * rdot - ixz * (pdot - q * r) + (iyy - ixx) * p * q) / (qs * ref.span)
    alpha = record["alpha"]
    ca, sa = np.cos(alpha), np.sin(alpha)
    return {
        "CX": cx,
        "CY": cy,
        "CZ": cz,
        "Cl": cl,
        "Cm": cm,
        "Cn": cn,
        "CL": -cz * ca + cx * sa,
        "CD": -cx * ca - cz * sa,
    }


def with_coefficients(
    record: FlightRecord, overwrite: bool = False, include_thrust: bool = True
) -> FlightRecord:
    """The record with coefficient and nondimensional-rate channels added where missing.

    With overwrite=True the computed ones replace the record's own.
    """
    add: dict[str, np.ndarray] = {}
    missing = [c for c in COEFFICIENT_CHANNELS if overwrite or c not in record]
    if missing:
        computed = force_moment_coefficients(record, include_thrust=include_thrust)
        add.update({c: computed[c] for c in missing})
    missing_rates = [c for c in ("phat", "qhat", "rhat") if overwrite or c not in record]
    if missing_rates:
        rates = nondimensional_rates(record)
        add.update({c: rates[c] for c in missing_rates})
    return record.with_channels(**add) if add else record


def _reference(record: FlightRecord):
    if record.meta.reference is None:
        raise ValueError(
            "record has no reference geometry (meta.reference: area, span, chord); "
            "coefficients cannot be made dimensionless"
        )
    return record.meta.reference
