"""Rigid-body equations of motion: body axes, flat earth, Euler angles, fixed-step RK4.

States x = (u, v, w, p, q, r, phi, theta, psi) on the FIRST axis, x[9, ...]: body
velocities relative to the air (m/s), body rates (rad/s) and 3-2-1 Euler angles (rad);
any trailing shape is a batch (samples, parameter perturbations). Forces are the
non-gravitational ones (aerodynamic plus thrust, N, body axes), moments are about the CG
(N m, body axes). Flat, non-rotating earth, constant gravity, still air (Stevens, Lewis
& Johnson 2016, eqs. 1.7-18 to 1.7-21; Morelli & Klein 2016, eqs. 3.32-3.38):

    udot = r v - q w - g sin(theta)               + X/m
    vdot = p w - r u + g cos(theta) sin(phi)      + Y/m
    wdot = q u - p v + g cos(theta) cos(phi)      + Z/m
    Ixx pdot - Ixz rdot = L + (Iyy - Izz) q r + Ixz p q
    Iyy qdot            = M + (Izz - Ixx) p r - Ixz (p^2 - r^2) - h r
    Izz rdot - Ixz pdot = N + (Ixx - Iyy) p q - Ixz q r          + h q
    phidot   = p + tan(theta) (q sin(phi) + r cos(phi))
    thetadot = q cos(phi) - r sin(phi)
    psidot   = (q sin(phi) + r cos(phi)) / cos(theta)

with Ixz positive as in Etkin (flightid.channels) and h the angular momentum of the
spinning engine rotor along body x (N m s): the gyroscopic moment -omega x h (Stevens,
Lewis & Johnson 2016, sec. 1.7, "engine angular momentum"). Everything is plain
arithmetic and numpy functions that accept complex numbers, so complex-step
differentiation through an integration is exact to rounding.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from flightid.units import G0

STATES: tuple[str, ...] = ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi")

# The functions below take ``xp``, the namespace of sin, cos, sqrt, arctan, arcsin: numpy
# for arrays (batches, complex steps), SCALAR for a state held as Python floats, which is
# ten times faster than numpy on one trajectory (no per-call array overhead).
SCALAR = SimpleNamespace(sin=math.sin, cos=math.cos, sqrt=math.sqrt, arctan=math.atan,
                         arcsin=math.asin)

# WGS-84 normal gravity on the ellipsoid (Somigliana; NIMA TR8350.2, 3rd ed., eqs. 4-1 and
# 4-3), which includes the centrifugal part of the earth's rotation, and its height change
_G_EQUATOR = 9.7803253359  # m/s^2
_SOMIGLIANA_K = 0.00193185265241
_E2 = 0.00669437999013
_A, _F, _M = 6378137.0, 1.0 / 298.257223563, 0.00344978650684


def local_gravity(latitude: float, altitude: float = 0.0) -> float:
    """Effective gravity at a geodetic latitude and altitude.

    The acceleration a plumb line feels (gravitation plus the centrifugal part of the
    earth's rotation), as in the flat-earth equations of a rotating-earth simulation:
    9.780 m/s^2 at the equator, 9.832 m/s^2 at the poles; Somigliana's formula with the
    second-order free-air term (TR8350.2 eq. 4-3).

    Parameters
    ----------
    latitude : float
        Geodetic latitude, rad.
    altitude : float, optional
        Altitude above sea level (the ellipsoid), m. Default 0.

    Returns
    -------
    float
        Gravity, m/s^2.
    """
    s2 = math.sin(latitude) ** 2
    g0 = _G_EQUATOR * (1 + _SOMIGLIANA_K * s2) / math.sqrt(1 - _E2 * s2)
    return g0 * (1 - 2 * altitude / _A * (1 + _F + _M - 2 * _F * s2) + 3 * altitude**2 / _A**2)


@dataclass(frozen=True)
class MassProperties:
    """Mass (kg), inertias about the CG (kg m^2, Ixz positive as in Etkin), gravity (m/s^2)."""

    mass: float
    Ixx: float
    Iyy: float
    Izz: float
    Ixz: float = 0.0
    g: float = G0

    def __post_init__(self) -> None:
        for name in ("mass", "Ixx", "Iyy", "Izz", "g"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"mass property {name} must be positive and finite, got {value}")
        if self.Ixx * self.Izz - self.Ixz**2 <= 0:
            raise ValueError(
                f"inertia matrix is not positive definite: Ixx Izz - Ixz^2 = "
                f"{self.Ixx * self.Izz - self.Ixz**2:.6g} kg^2 m^4"
            )


def air_data(x, xp=np) -> tuple:
    """True airspeed, angle of attack and sideslip of states x[9, ...].

    alpha = arctan(w/u), beta = arcsin(v/V) (complex-step safe; u > 0 in normal flight).

    Parameters
    ----------
    x : numpy.ndarray
        States (``STATES`` on the first axis), shape (9, ...), SI units.
    xp : module or namespace, optional
        Namespace of sqrt, arctan, arcsin: numpy (default) or ``SCALAR``.

    Returns
    -------
    tuple
        (V m/s, alpha rad, beta rad), each of the trailing shape of ``x``.
    """
    u, v, w = x[0], x[1], x[2]
    speed = xp.sqrt(u * u + v * v + w * w)
    return speed, xp.arctan(w / u), xp.arcsin(v / speed)


def state_from_air_data(speed: float, alpha: float, beta: float) -> tuple[float, float, float]:
    """Body velocities u, v, w from airspeed, alpha and beta.

    Parameters
    ----------
    speed : float
        True airspeed, m/s.
    alpha : float
        Angle of attack, rad.
    beta : float
        Sideslip angle, rad.

    Returns
    -------
    tuple of float
        (u, v, w), m/s, body axes.
    """
    cb = np.cos(beta)
    return speed * np.cos(alpha) * cb, speed * np.sin(beta), speed * np.sin(alpha) * cb


def euler_trig(x, xp=np) -> tuple:
    """(sin phi, cos phi, sin theta, cos theta) of states x[9, ...].

    Parameters
    ----------
    x : numpy.ndarray
        States, shape (9, ...); phi and theta in rad.
    xp : module or namespace, optional
        Namespace of sin, cos: numpy (default) or ``SCALAR``.

    Returns
    -------
    tuple
        (sin phi, cos phi, sin theta, cos theta), each of the trailing shape of ``x`` (1).
    """
    return xp.sin(x[6]), xp.cos(x[6]), xp.sin(x[7]), xp.cos(x[7])


def translational(x, ax, ay, az, g: float, trig: tuple | None = None) -> tuple:
    """(udot, vdot, wdot) for body specific forces ax, ay, az.

    Specific forces rather than forces so that a mass that changes along the record (fuel
    burn) enters as a time history.

    Parameters
    ----------
    x : numpy.ndarray
        States, shape (9, ...), SI units.
    ax, ay, az : float or numpy.ndarray
        Non-gravitational specific forces along body x, y, z (force/mass), m/s^2.
    g : float
        Gravity, m/s^2.
    trig : tuple or None, optional
        ``euler_trig(x)`` if already computed.

    Returns
    -------
    tuple
        (udot, vdot, wdot), m/s^2.
    """
    u, v, w, p, q, r = x[0], x[1], x[2], x[3], x[4], x[5]
    sf, cf, st, ct = euler_trig(x) if trig is None else trig
    return (r * v - q * w - g * st + ax,
            p * w - r * u + g * ct * sf + ay,
            q * u - p * v + g * ct * cf + az)


def rotational(x, roll, pitch, yaw, mp: MassProperties, rotor_momentum=0.0) -> tuple:
    """(pdot, qdot, rdot) for moments about the CG and the rotor's angular momentum.

    Parameters
    ----------
    x : numpy.ndarray
        States, shape (9, ...), SI units.
    roll, pitch, yaw : float or numpy.ndarray
        Moments L, M, N about the CG, body axes, N m.
    mp : MassProperties
        Inertias (kg m^2).
    rotor_momentum : float or numpy.ndarray, optional
        Angular momentum h of the engine rotor along body x, N m s. Default 0.

    Returns
    -------
    tuple
        (pdot, qdot, rdot), rad/s^2.
    """
    p, q, r = x[3], x[4], x[5]
    ixx, iyy, izz, ixz = mp.Ixx, mp.Iyy, mp.Izz, mp.Ixz
    h = rotor_momentum
    lhs_roll = roll + (iyy - izz) * q * r + ixz * p * q
    lhs_yaw = yaw + (ixx - iyy) * p * q - ixz * q * r + h * q
    det = ixx * izz - ixz * ixz
    return ((izz * lhs_roll + ixz * lhs_yaw) / det,
            (pitch + (izz - ixx) * p * r - ixz * (p * p - r * r) - h * r) / iyy,
            (ixz * lhs_roll + ixx * lhs_yaw) / det)


def kinematic(x, trig: tuple | None = None) -> tuple:
    """(phidot, thetadot, psidot) from the body rates and Euler angles.

    Parameters
    ----------
    x : numpy.ndarray
        States, shape (9, ...), SI units.
    trig : tuple or None, optional
        ``euler_trig(x)`` if already computed.

    Returns
    -------
    tuple
        (phidot, thetadot, psidot), rad/s.
    """
    q, r = x[4], x[5]
    sf, cf, st, ct = euler_trig(x) if trig is None else trig
    qr = q * sf + r * cf
    return x[3] + st / ct * qr, q * cf - r * sf, qr / ct


def derivative(x: np.ndarray, force: tuple, moment: tuple, mp: MassProperties,
               rotor_momentum=0.0) -> np.ndarray:
    """dx/dt of the rigid-body equations for body forces and moments.

    Parameters
    ----------
    x : numpy.ndarray
        States, shape (9, ...), SI units.
    force : tuple
        (X, Y, Z) non-gravitational forces, body axes, N.
    moment : tuple
        (L, M, N) moments about the CG, body axes, N m.
    mp : MassProperties
        Mass (kg), inertias (kg m^2) and gravity (m/s^2).
    rotor_momentum : float or numpy.ndarray, optional
        Angular momentum of the engine rotor along body x, N m s. Default 0.

    Returns
    -------
    numpy.ndarray
        dx/dt, shape of ``x``: m/s^2, rad/s^2, rad/s.
    """
    trig = euler_trig(x)
    specific = [f / mp.mass for f in force]
    return np.stack([*translational(x, *specific, mp.g, trig),
                     *rotational(x, *moment, mp, rotor_momentum), *kinematic(x, trig)])


def rk4(rhs: Callable[[np.ndarray, int, int], np.ndarray], x0: np.ndarray, steps: int,
        dt: float) -> np.ndarray:
    """Fixed-step classical Runge-Kutta integration.

    Parameters
    ----------
    rhs : callable
        ``rhs(x, i, stage)`` is dx/dt at sample i with stage 0 (t_i), 1 (t_i + dt/2) or
        2 (t_i + dt), so the caller supplies its inputs at those three instants.
    x0 : numpy.ndarray
        Initial state, any shape.
    steps : int
        Number of steps.
    dt : float
        Step, s.

    Returns
    -------
    numpy.ndarray
        States at samples 0..steps, shape (steps + 1, *x0.shape).
    """
    out = np.empty((steps + 1, *x0.shape), dtype=x0.dtype)
    out[0] = x = x0
    half = 0.5 * dt
    sixth = dt / 6.0
    for i in range(steps):
        k1 = rhs(x, i, 0)
        k2 = rhs(x + half * k1, i, 1)
        k3 = rhs(x + half * k2, i, 1)
        k4 = rhs(x + dt * k3, i, 2)
        x = x + sixth * (k1 + 2.0 * (k2 + k3) + k4)
        out[i + 1] = x
    return out
