"""The kinematic model of flight path reconstruction: the rigid-body kinematics driven by
the measured specific forces and body rates, and the instrument models of the outputs.

The measured specific forces and body
rates drive the rigid-body kinematic equations (flat, non-rotating Earth, M&K eqs.
10.4-10.6, with the apparent gravity of the WGS84 normal field):

    udot = r v - q w - g sin(theta) + ax
    vdot = p w - r u + g cos(theta) sin(phi) + ay
    wdot = q u - p v + g cos(theta) cos(phi) + az
    phidot = p + tan(theta) (q sin(phi) + r cos(phi))
    thetadot = q cos(phi) - r sin(phi)
    psidot = (q sin(phi) + r cos(phi)) / cos(theta)
    [north, east, -h]dot = L_EB [u, v, w] + wind

with u, v, w the CG velocity relative to the air mass in body axes. A constant wind (NED)
leaves these velocity equations unchanged (the wind vector obeys the same transport term
as the ground velocity), so it shows only in the position outputs (h, north, east).

Instrument models (each measured channel m of a true quantity x):
    inputs  (ax ay az p q r):  m = (1 + scale_<c>) x + bias_<c>
    V:                         m(t) = (1 + scale_V) V(t - delay_V) + bias_V
    alpha, beta vanes:         m(t) = (1 + upwash_alpha) alpha_v(t - delay_alpha) + bias_alpha
                               m(t) = (1 + sidewash_beta) beta_v(t - delay_beta) + bias_beta
    phi theta psi h north east: m(t) = x(t - delay_<c>) + bias_<c>
where alpha_v, beta_v are the exact flow angles at the vane positions (vane_alpha_x, ...,
m from the CG, body axes): local velocity = [u, v, w] + omega x r_vane (the ``Vanes``
effect of ``flightid.sim.sensors.suites`` in reverse). Time shifts are relative to the inertial
inputs, which are the time reference (only relative shifts are observable).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flightid.identification.compatibility.parameters import (
    EARTH_RATE,
    INPUTS,
    PARAMETERS,
    STATES,
    VANE_POSITIONS,
    WGS84_A,
    WGS84_E2,
    WIND,
)
from flightid.identification.engine import problem as problem_skeleton


@dataclass(kw_only=True)
class Problem(problem_skeleton.Problem):
    """A record arranged for the reconstruction (the skeleton's time, measured outputs with
    psi unwrapped, and noise floor, and:) measured inputs, output names, gravity."""

    inputs: np.ndarray  # (N, 6) measured ax ay az p q r
    outputs: tuple[str, ...]
    gravity: float
    latitude: float | None  # rad; None: flat, non-rotating Earth
    gyros: str  # 'inertial' (they sense Earth rate) or 'earth' (rates relative to the Earth)


def corrected_inputs(problem: Problem, P: Mapping[str, np.ndarray]) -> np.ndarray:
    """True inputs from the measured ones: x = (m - bias) / (1 + scale).

    Parameters
    ----------
    problem : Problem
        The reconstruction problem (measured inputs, SI).
    P : mapping of str to numpy.ndarray
        Parameter values per batch member; shape (K,) each.

    Returns
    -------
    numpy.ndarray
        The true inputs ax ay az (m/s^2) p q r (rad/s); shape (N, 6, K).
    """
    m = problem.inputs[:, :, None]
    bias = np.stack([P[f"bias_{c}"] for c in INPUTS])[None]
    scale = np.stack([P[f"scale_{c}"] for c in INPUTS])[None]
    return (m - bias) / (1.0 + scale)


def _quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a b of quaternions stored on the last axis as (w, x, y, z)."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def _quat_from_euler(phi, theta, psi) -> np.ndarray:
    """Body-to-NED quaternion (w, x, y, z) of 3-2-1 Euler angles (rad)."""
    cf, sf = np.cos(phi / 2), np.sin(phi / 2)
    ct, st = np.cos(theta / 2), np.sin(theta / 2)
    cp, sp = np.cos(psi / 2), np.sin(psi / 2)
    return np.stack([cp * ct * cf + sp * st * sf, cp * ct * sf - sp * st * cf,
                     cp * st * cf + sp * ct * sf, sp * ct * cf - cp * st * sf], axis=-1)


def _rotation(qn: np.ndarray) -> np.ndarray:
    """Body-to-NED direction cosine matrices (..., 3, 3) of unit quaternions (..., 4)."""
    w, x, y, z = np.moveaxis(qn, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def _prefix_products(dq: np.ndarray) -> np.ndarray:
    """Cumulative quaternion products dq_0 dq_1 ... dq_i along axis 0 (Hillis-Steele scan:
    log2(N) vectorised passes instead of an N-step loop)."""
    out = dq.copy()
    d = 1
    while d < len(out):
        out[d:] = _quat_multiply(out[:-d], out[d:])
        d *= 2
    return out


def integrate(problem: Problem, P: Mapping[str, np.ndarray], a: np.ndarray) -> np.ndarray:
    """States u v w phi theta psi h north east from the true inputs.

    Flat Earth: ``_navigate`` once. With a latitude, the rotating round Earth enters
    through the transport rate, the Earth rate (for inertial gyros) and the Coriolis
    acceleration (Savage 2007 ch. 4; Titterton & Weston 2004 eq. 3.40). These are 1e-5
    rad/s and 1e-2 m/s^2 at most, so they are evaluated on the flat solution and the
    navigation is run again with them: the neglected part is of their square.

    Parameters
    ----------
    problem : Problem
        The reconstruction problem.
    P : mapping of str to numpy.ndarray
        Parameter values per batch member; shape (K,) each.
    a : numpy.ndarray
        True inputs; shape (N, 6, K).

    Returns
    -------
    numpy.ndarray
        States (m/s, rad, m); shape (N, 9, K).
    """
    states, rot, v_ned = _navigate(problem, P, a)
    if problem.latitude is None:
        return states
    lat = problem.latitude
    s2 = math.sin(lat) ** 2
    height = states[:, 6]  # (N, K)
    r_east = WGS84_A / math.sqrt(1 - WGS84_E2 * s2) + height  # prime-vertical radius + h
    r_north = WGS84_A * (1 - WGS84_E2) / (1 - WGS84_E2 * s2) ** 1.5 + height  # meridian radius + h
    ground = v_ned + np.stack([P[w] for w in WIND], axis=-1)[None]  # (N, K, 3)
    vn, ve = ground[..., 0], ground[..., 1]
    transport = np.stack([ve / r_east, -vn / r_north, -ve * math.tan(lat) / r_east], axis=-1)
    earth = EARTH_RATE * np.array([math.cos(lat), 0.0, -math.sin(lat)])
    frame_rate = transport + (earth if problem.gyros == "inertial" else 0.0)
    rate_correction = np.einsum("nkji,nkj->nki", rot, frame_rate)  # L^T omega, body axes
    coriolis = -np.cross(2.0 * earth + transport, ground)
    states, _, _ = _navigate(problem, P, a, rate_correction, coriolis)
    return states


def _navigate(problem: Problem, P: Mapping[str, np.ndarray], a: np.ndarray,
              rate_correction: np.ndarray | None = None,
              acceleration: np.ndarray | None = None,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """States (N, 9, K), body-to-NED matrices (N, K, 3, 3) and NED air velocity (N, K, 3).

    The kinematics of M&K eqs. 10.4-10.6 integrated as a strapdown navigator (Savage 2007,
    ch. 7): the attitude quaternion obeys qdot = q [0, omega] / 2 and is advanced over each
    sample interval by the exact rotation of the rotation vector omega_mid dt + dt^2/12
    omega_i x omega_i+1 (rates linear over the interval; the second term is the coning
    correction); the velocity in NED obeys Vdot = L_EB a + [0, 0, g] (trapezoidal rule),
    which is the body-axis equation udot = r v - q w - g sin(theta) + ax, ... rotated;
    positions integrate V + wind (trapezoidal). Every step is vectorised over time.
    ``rate_correction`` (N, K, 3) is subtracted from the body rates, ``acceleration``
    (N, K, 3) added in NED (round-Earth terms).
    """
    n, _, k = a.shape
    dt, g = problem.dt, problem.gravity
    rates = a[:, 3:6].transpose(0, 2, 1)  # (N, K, 3)
    if rate_correction is not None:
        rates = rates - rate_correction
    mid = 0.5 * (rates[1:] + rates[:-1])
    rot = dt * mid + dt * dt / 12.0 * np.cross(rates[:-1], rates[1:])
    angle = np.linalg.norm(rot, axis=-1)
    small = angle < 1e-6
    # sin(angle/2)/angle without 0/0: its series below 1e-6 rad
    factor = np.where(small, 0.5 - angle**2 / 48.0,
                      np.sin(0.5 * angle) / np.where(small, 1.0, angle))
    dq = np.concatenate([np.cos(0.5 * angle)[..., None], factor[..., None] * rot], axis=-1)
    q0 = _quat_from_euler(P["x0_phi"], P["x0_theta"], P["x0_psi"])  # (K, 4)
    quat = np.empty((n, k, 4))
    quat[0] = q0
    quat[1:] = _quat_multiply(q0[None], _prefix_products(dq))
    quat /= np.linalg.norm(quat, axis=-1, keepdims=True)
    L = _rotation(quat)  # (N, K, 3, 3) body -> NED
    qw, qx, qy, qz = np.moveaxis(quat, -1, 0)
    phi = np.arctan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy))
    theta = np.arcsin(np.clip(2 * (qw * qy - qz * qx), -1.0, 1.0))
    psi = np.unwrap(np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)), axis=0)
    psi += P["x0_psi"] - psi[0]
    f_ned = np.einsum("nkij,nkj->nki", L, a[:, 0:3].transpose(0, 2, 1))
    f_ned[..., 2] += g
    if acceleration is not None:
        f_ned += acceleration
    v_ned = np.empty((n, k, 3))
    v_ned[0] = np.einsum("kij,kj->ki", L[0], np.stack([P["x0_u"], P["x0_v"], P["x0_w"]], -1))
    v_ned[1:] = v_ned[0] + np.cumsum(0.5 * dt * (f_ned[1:] + f_ned[:-1]), axis=0)
    v_body = np.einsum("nkji,nkj->nki", L, v_ned)  # L^T v
    ground = v_ned + np.stack([P[w] for w in WIND], axis=-1)[None]
    pos = np.empty((n, k, 3))
    pos[0] = np.stack([P["x0_north"], P["x0_east"], -P["x0_h"]], axis=-1)
    pos[1:] = pos[0] + np.cumsum(0.5 * dt * (ground[1:] + ground[:-1]), axis=0)
    out = np.empty((n, len(STATES), k))
    out[:, 0:3] = v_body.transpose(0, 2, 1)
    out[:, 3], out[:, 4], out[:, 5] = phi, theta, psi
    out[:, 6] = -pos[..., 2]
    out[:, 7], out[:, 8] = pos[..., 0], pos[..., 1]
    return out, L, v_ned


def vane_angles(u, v, w, p, q, r, alpha_pos=(0.0, 0.0, 0.0), beta_pos=(0.0, 0.0, 0.0)):
    """Flow angles at the alpha and beta vane positions: local velocity V + omega x r_vane
    (M&K 2016 eq. 10.12 before linearisation).

    Parameters
    ----------
    u, v, w : numpy.ndarray
        CG air velocity, body axes, m/s.
    p, q, r : numpy.ndarray
        Body rates, rad/s.
    alpha_pos : tuple of float, optional
        Alpha vane position (x, y, z), m from the CG, body axes. Default the CG.
    beta_pos : tuple of float, optional
        Beta vane position (x, y, z), m from the CG, body axes. Default the CG.

    Returns
    -------
    tuple of numpy.ndarray
        (alpha, beta) at the vanes, rad.
    """
    xa, ya, za = alpha_pos
    xb, yb, zb = beta_pos
    alpha = np.arctan2(w + p * ya - q * xa, u + q * za - r * ya)
    ub, vb, wb = u + q * zb - r * yb, v + r * xb - p * zb, w + p * yb - q * xb
    beta = np.arcsin(np.clip(vb / np.sqrt(ub * ub + vb * vb + wb * wb), -1.0, 1.0))
    return alpha, beta


def model_outputs(problem: Problem, P: Mapping[str, np.ndarray], x: np.ndarray,
                   a: np.ndarray) -> np.ndarray:
    """Modelled measurements from states and true inputs.

    Parameters
    ----------
    problem : Problem
        The reconstruction problem (its outputs and time).
    P : mapping of str to numpy.ndarray
        Parameter values per batch member; shape (K,) each.
    x : numpy.ndarray
        States; shape (N, 9, K).
    a : numpy.ndarray
        True inputs; shape (N, 6, K).

    Returns
    -------
    numpy.ndarray
        The modelled outputs, SI; shape (N, ny, K).
    """
    u, v, w = x[:, 0], x[:, 1], x[:, 2]
    p, q, r = a[:, 3], a[:, 4], a[:, 5]
    pos = {name: P[name][None] for name in VANE_POSITIONS}
    out = []
    for name in problem.outputs:
        if name == "V":
            y = (1.0 + P["scale_V"]) * np.sqrt(u * u + v * v + w * w)
        elif name == "alpha":
            alpha, _ = vane_angles(u, v, w, p, q, r,
                                   (pos["vane_alpha_x"], pos["vane_alpha_y"], pos["vane_alpha_z"]))
            y = (1.0 + P["upwash_alpha"]) * alpha
        elif name == "beta":
            ub, vb, wb = (u + q * pos["vane_beta_z"] - r * pos["vane_beta_y"],
                          v + r * pos["vane_beta_x"] - p * pos["vane_beta_z"],
                          w + p * pos["vane_beta_y"] - q * pos["vane_beta_x"])
            beta = np.arcsin(np.clip(vb / np.sqrt(ub * ub + vb * vb + wb * wb), -1.0, 1.0))
            y = (1.0 + P["sidewash_beta"]) * beta
        else:
            y = x[:, STATES.index(name)]
        y = _delayed(problem.time, y, P[f"delay_{name}"]) + P[f"bias_{name}"]
        out.append(y)
    return np.stack(out, axis=1)


def _delayed(t: np.ndarray, y: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """y(t - tau) per batch member by linear interpolation (first value before the start)."""
    if not np.any(tau):
        return y
    out = np.empty_like(y)
    for j in range(y.shape[1]):
        out[:, j] = y[:, j] if tau[j] == 0 else np.interp(t - tau[j], t, y[:, j])
    return out


def batch(values: Mapping[str, float], k: int) -> dict[str, np.ndarray]:
    """Every kinematic parameter repeated for ``k`` simultaneous simulations.

    Parameters
    ----------
    values : Mapping of str to float
        Parameter values (SI units); a parameter not given takes its default.
    k : int
        The number of simulations.

    Returns
    -------
    dict of str to ndarray
        Each parameter of ``PARAMETERS`` as an array of ``k`` equal values.
    """
    return {name: np.full(k, float(values.get(name, p.default)))
            for name, p in PARAMETERS.items()}


def simulate(problem: Problem, values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Modelled outputs and states at parameter ``values``.

    Parameters
    ----------
    problem : Problem
        The reconstruction problem.
    values : mapping of str to float
        Parameter values, SI.

    Returns
    -------
    tuple of numpy.ndarray
        Outputs (N, ny) and states (N, 9), SI.
    """
    P = batch(values, 1)
    a = corrected_inputs(problem, P)
    x = integrate(problem, P, a)
    return model_outputs(problem, P, x, a)[:, :, 0], x[:, :, 0]


def outputs_and_sensitivities(problem: Problem, values: Mapping[str, float],
                               names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Outputs and central-difference sensitivities.

    One RK4 loop integrates the nominal and every +-step perturbation of the parameters
    that change the states; the output-only parameters reuse the nominal states.

    Parameters
    ----------
    problem : Problem
        The reconstruction problem.
    values : mapping of str to float
        Parameter values, SI.
    names : sequence of str
        The parameters differentiated.

    Returns
    -------
    tuple of numpy.ndarray
        Outputs (N, ny), SI, and sensitivities (N, ny, len(names)), output unit per
        parameter unit.
    """
    in_states = [n for n in names if PARAMETERS[n].in_states]
    k_int = 1 + 2 * len(in_states)
    P = batch(values, k_int)
    for j, name in enumerate(in_states):
        P[name][1 + 2 * j] += PARAMETERS[name].step
        P[name][2 + 2 * j] -= PARAMETERS[name].step
    a = corrected_inputs(problem, P)
    x = integrate(problem, P, a)
    # output batch: 1 + 2 len(names) members, each pointing at the integrated member it uses
    k_out = 1 + 2 * len(names)
    Q = batch(values, k_out)
    source = np.zeros(k_out, dtype=int)
    for j, name in enumerate(names):
        step = PARAMETERS[name].step
        Q[name][1 + 2 * j] += step
        Q[name][2 + 2 * j] -= step
        if name in in_states:
            i = in_states.index(name)
            source[1 + 2 * j], source[2 + 2 * j] = 1 + 2 * i, 2 + 2 * i
    y = model_outputs(problem, Q, x[:, :, source], a[:, :, source])
    steps = np.array([PARAMETERS[n].step for n in names])
    sens = (y[:, :, 1::2] - y[:, :, 2::2]) / (2.0 * steps)
    return y[:, :, 0], sens


