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

import re

import numpy as np
from scipy.ndimage import convolve1d
from scipy.signal import savgol_filter

from flightid.record import FlightRecord

MASS_PROPERTIES = ("mass", "Ixx", "Iyy", "Izz", "Ixz")
COEFFICIENT_CHANNELS = ("CX", "CY", "CZ", "Cl", "Cm", "Cn", "CL", "CD")
PROPULSIVE_MOMENTS = ("L_prop", "M_prop", "N_prop")
SMOOTHING_WINDOW_S = 0.2  # s, span of the local fits that differentiate the rates
# a spline factor of an angle: "(alpha-8deg)+" is (alpha - 8 deg)_+ = max(alpha - 8 deg, 0)
# in rad, "(alpha+4deg)+" has its knot at -4 deg (Morelli 1995; Morelli & Klein 2016 ch. 5)
HINGE = re.compile(r"^\((?P<channel>[A-Za-z_]\w*)(?P<knot>[-+]\d+(?:\.\d+)?)deg\)\+$")


def _window_samples(size: int, dt: float, window_s: float, order: int) -> int:
    """Odd number of samples of a local polynomial fit spanning ``window_s`` s."""
    if dt <= 0:
        raise ValueError(f"sample interval must be positive, got {dt} s")
    n = max(int(round(window_s / dt)) | 1, order + 2 | 1)
    if size < n:
        raise ValueError(
            f"{size} samples are too few for a {n}-sample differentiation window "
            f"({window_s} s at {dt} s)"
        )
    return n


def smoothed_derivative(
    x: np.ndarray, dt: float, window_s: float = SMOOTHING_WINDOW_S, order: int = 2
) -> np.ndarray:
    """Time derivative of x by a local polynomial (Savitzky-Golay) fit.

    The fit smooths noise above roughly 1 / window_s Hz.

    Parameters
    ----------
    x : numpy.ndarray
        The signal, any unit; shape (n,).
    dt : float
        Sample interval, s.
    window_s : float, optional
        The span of the local fit, s (rounded to an odd number of samples, at least
        order + 2). Default ``SMOOTHING_WINDOW_S``.
    order : int, optional
        The local polynomial's order. Default 2.

    Returns
    -------
    numpy.ndarray
        dx/dt, units of x per s; shape (n,).
    """
    x = np.asarray(x, dtype=float)
    n = _window_samples(x.size, dt, window_s, order)
    return savgol_filter(x, n, order, deriv=1, delta=dt, mode="interp")


def smoothed(x: np.ndarray, dt: float, window_s: float = SMOOTHING_WINDOW_S, order: int = 2
             ) -> np.ndarray:
    """x through the filter that ``smoothed_derivative`` applies to what it differentiates:
    the regressors of a differentiated signal need it too.

    The local-polynomial slope over 2M + 1 samples is the least-squares slope
    sum(k x_k) / (dt sum k^2), i.e. d/dt of x smoothed by a parabolic window
    s_k = a - b k^2; a and b match its first two moments (sum s_k = 1,
    sum s_k k^2 = sum k^4 / (3 sum k^2)), so jw S(w) equals the slope filter's response
    to within 0.2 % below its cutoff (a plain polynomial smoothing of the same span is
    off by 90 % at 4 Hz on a 0.2 s window).

    Parameters
    ----------
    x : numpy.ndarray
        The signal, any unit; shape (n,).
    dt : float
        Sample interval, s.
    window_s : float, optional
        The span of the local fit, s. Default ``SMOOTHING_WINDOW_S``.
    order : int, optional
        The local polynomial's order (sets the smallest window). Default 2.

    Returns
    -------
    numpy.ndarray
        The smoothed signal, unit of x; shape (n,).
    """
    x = np.asarray(x, dtype=float)
    n = _window_samples(x.size, dt, window_s, order)
    k = np.arange(n) - n // 2
    s2, s4 = float(np.sum(k**2)), float(np.sum(k**4))
    a, b = np.linalg.solve([[n, -s2], [s2, -s4]], [1.0, s4 / (3.0 * s2)])
    return convolve1d(x, a - b * k**2, mode="nearest")


def differentiated(record: FlightRecord, coefficient: str) -> bool:
    """True when ``coefficient`` is computed from smoothed derivatives of the rates.

    That is a moment coefficient the record does not hold, without measured angular
    accelerations.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    coefficient : str
        A coefficient name (CX, ..., Cn).

    Returns
    -------
    bool
        Whether it is computed from differentiated rates.
    """
    return (coefficient in ("Cl", "Cm", "Cn") and coefficient not in record
            and any(f"{r}dot" not in record for r in ("p", "q", "r")))


def nondimensional_rates(record: FlightRecord) -> dict[str, np.ndarray]:
    """phat = p b/2V, qhat = q cbar/2V, rhat = r b/2V from p, q, r and V.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, with reference geometry in its metadata.

    Returns
    -------
    dict of str to numpy.ndarray
        ``phat``, ``qhat``, ``rhat``, dimensionless; shape (n,) each.
    """
    ref = _reference(record)
    two_v = 2.0 * record["V"]
    return {
        "phat": record["p"] * ref.span / two_v,
        "qhat": record["q"] * ref.chord / two_v,
        "rhat": record["r"] * ref.span / two_v,
    }


def angular_accelerations(record: FlightRecord, window_s: float = SMOOTHING_WINDOW_S
                          ) -> dict[str, np.ndarray]:
    """pdot, qdot, rdot: the record's channels, or smoothed derivatives of p, q, r.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    window_s : float, optional
        The smoothing span of ``smoothed_derivative``, s. Default ``SMOOTHING_WINDOW_S``.

    Returns
    -------
    dict of str to numpy.ndarray
        ``pdot``, ``qdot``, ``rdot``, rad/s^2; shape (n,) each.
    """
    out = {}
    for rate in ("p", "q", "r"):
        name = rate + "dot"
        if name in record:
            out[name] = record[name]
        else:
            out[name] = smoothed_derivative(record[rate], record.dt, window_s)
    return out


def mass_properties(record: FlightRecord) -> dict[str, np.ndarray]:
    """mass and Ixx Iyy Izz Ixz: record channels, else meta.extra values.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.

    Returns
    -------
    dict of str to numpy.ndarray
        ``mass`` (kg) and the inertias (kg m^2); shape (n,) each.

    Raises
    ------
    ValueError
        When one is neither a channel nor in meta.extra.
    """
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

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, with mass properties and reference geometry.
    include_thrust : bool, optional
        Subtract the record's ``thrust`` channel (N, along body x) from the x force, so CX and
        CD are aerodynamic only. Default True. The propulsive moments ``L_prop``, ``M_prop``,
        ``N_prop`` (N m, body axes: torque reaction, p-factor, gyroscopic) are subtracted from
        the moments where the record has them, so Cl, Cm, Cn are aerodynamic.
    window_s : float, optional
        Smoothing span for differentiated rates, s. Default 0.2.

    Returns
    -------
    dict of str to numpy.ndarray
        The coefficients, dimensionless; shape (n,) each.

    Raises
    ------
    ValueError
        When the dynamic pressure is not positive, or the thrust is asked for and missing.
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
    prop = {k: record[k] if k in record else 0.0 for k in PROPULSIVE_MOMENTS}
    cl = (ixx * pdot - ixz * (rdot + p * q) + (izz - iyy) * q * r - prop["L_prop"]) / (
        qs * ref.span)
    cm = (iyy * qdot + (ixx - izz) * p * r + ixz * (p * p - r * r) - prop["M_prop"]) / (
        qs * ref.chord)
    cn = (izz * rdot - ixz * (pdot - q * r) + (iyy - ixx) * p * q - prop["N_prop"]) / (
        qs * ref.span)
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

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    overwrite : bool, optional
        The computed channels replace the record's own. Default False.
    include_thrust : bool, optional
        As in ``force_moment_coefficients``. Default True.

    Returns
    -------
    FlightRecord
        The record with the added channels (the record itself when none are added).
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


THRUST_COEFFICIENTS = ("CX", "CL", "CD")
# the thrust coefficient: the propeller slipstream's dynamic pressure over the free
# stream's grows with it (momentum theory: qbar_slipstream / qbar = 1 + Tc S / A_disk),
# so surfaces in the slipstream have derivatives that change with Tc
THRUST_COEFFICIENT = "Tc"


def thrust_coefficient(record: FlightRecord) -> np.ndarray:
    """Tc = T / (qbar S), dimensionless, from the record's thrust (N, body x).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, with a ``thrust`` channel.

    Returns
    -------
    numpy.ndarray
        Tc, dimensionless; shape (n,).

    Raises
    ------
    ValueError
        When the record has no ``thrust`` channel.
    """
    if "thrust" not in record:
        raise ValueError("the thrust coefficient Tc needs the record's 'thrust' channel (N)")
    return record["thrust"] / (record["qbar"] * _reference(record).area)


def hinge_name(channel: str, knot_deg: float) -> str:
    """The spline factor (channel - knot)_+ of an angle channel (rad).

    For example hinge_name('alpha', 8.0) = '(alpha-8deg)+'.

    Parameters
    ----------
    channel : str
        The angle channel (rad).
    knot_deg : float
        The knot, deg.

    Returns
    -------
    str
        The factor's channel name.
    """
    return f"({channel}{'-' if knot_deg >= 0 else '+'}{abs(knot_deg):g}deg)+"


def channel_values(record: FlightRecord, channel: str) -> np.ndarray:
    """A channel of the record, or one derived from it.

    Derived channels: phat qhat rhat, alphadot_hat, the thrust coefficient Tc, the
    coefficients, a spline factor such as '(alpha-8deg)+' (see ``hinge_name``).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    channel : str
        The channel name.

    Returns
    -------
    numpy.ndarray
        The channel's values, SI (dimensionless for the derived ones); shape (n,).

    Raises
    ------
    KeyError
        When the record neither holds nor can derive ``channel``.
    """
    if channel in record:
        return record[channel]
    hinge = HINGE.match(channel)
    if hinge:  # the knot's sign in the name is that of -knot
        knot = -float(hinge["knot"])
        return np.maximum(channel_values(record, hinge["channel"]) - np.radians(knot), 0.0)
    if channel in ("phat", "qhat", "rhat"):
        return nondimensional_rates(record)[channel]
    if channel == THRUST_COEFFICIENT:
        return thrust_coefficient(record)
    if channel == "alphadot_hat":
        if record.meta.reference is None:
            raise ValueError("alphadot needs the reference chord (meta.reference)")
        alphadot = smoothed_derivative(record["alpha"], record.dt)
        return alphadot * record.meta.reference.chord / (2.0 * record["V"])
    if channel in COEFFICIENT_CHANNELS:
        # only the x force (CX, and CL, CD through it) needs the thrust to be subtracted
        needs_thrust = channel in THRUST_COEFFICIENTS
        return force_moment_coefficients(
            record, include_thrust=needs_thrust or "thrust" in record)[channel]
    raise KeyError(
        f"record has no channel {channel!r} (and it cannot be derived); it has "
        f"{', '.join(sorted(record.channels))}"
    )
