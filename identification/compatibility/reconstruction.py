"""Data compatibility by flight path reconstruction: sensor biases, scale factors, time
shifts and air-data (vane, pitot) calibration from the kinematics alone.

Morelli & Klein (2016) ch. 10 and Jategaonkar (2015) ch. 10; Cooper, Drobik & Martin,
ARL Flight Mechanics Report 187 (1990; flight path reconstruction, vane calibration
alpha_m = K_alpha (alpha - x_alpha q / V) + b). The measured specific forces and body
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

The parameters are estimated by output error (maximum likelihood with the noise
covariance R re-estimated every iteration, Gauss-Newton with Levenberg-Marquardt
damping; M&K ch. 6) together with the initial states ``x0_<state>``. The optimiser of
``output_error`` is built around the discretised linear model (exact matrix-exponential
sensitivities), so this nonlinear kinematic model has its own compact Gauss-Newton with
central finite-difference sensitivities (as SIDPAC's ``oe`` does for nonlinear models):
all perturbed parameter sets are integrated together in one vectorised RK4 loop, and
parameters that enter only the output equations reuse the nominal states. Cramer-Rao
bounds come from the information matrix, corrected for colored residuals (M&K eq. 6.54;
``output_error.colored_residual_covariance``) by default: the integrated input noise makes
the residuals of a reconstruction strongly colored. Parameters the maneuver cannot
separate (zero sensitivity, or a near-singular normalised information matrix;
``identifiability``) are fixed at their a priori values and reported in
``Estimate.unidentifiable``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flightid.channels import CHANNELS
from flightid.identification.engine import convergence
from flightid.identification.engine import identifiability as ident
from flightid.identification.engine.bounds import colored_residual_covariance
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit, maximum_likelihood
from flightid.identification.estimate import Estimate
from flightid.identification.models.rigid_body import local_gravity
from flightid.record import FlightRecord

METHOD = "compatibility"
INPUTS: tuple[str, ...] = ("ax", "ay", "az", "p", "q", "r")
STATES: tuple[str, ...] = ("u", "v", "w", "phi", "theta", "psi", "h", "north", "east")
OUTPUTS: tuple[str, ...] = ("V", "alpha", "beta", "phi", "theta", "psi", "h", "north", "east")
DEFAULT_OUTPUTS: tuple[str, ...] = ("V", "alpha", "beta", "phi", "theta", "psi", "h")
REQUIRED: tuple[str, ...] = (*INPUTS, "V", "alpha", "beta", "phi", "theta")
VANE_POSITIONS: tuple[str, ...] = tuple(
    f"vane_{angle}_{axis}" for angle in ("alpha", "beta") for axis in "xyz")
WIND: tuple[str, ...] = ("wind_north", "wind_east", "wind_down")

# WGS84 ellipsoid (NIMA TR8350.2, 3rd ed.): semi-major axis, first eccentricity squared
_A, _E2 = 6378137.0, 0.00669437999013
DEFAULT_LATITUDE = math.radians(45.0)
EARTH_RATE = 7.292115e-5  # rad/s, WGS84
MIN_SAMPLES = 50
# an output that repeats its previous sample this often is a slow source held between
# updates (the Twin Otter heading: 98 %); it is left out of the default outputs
MAX_HELD = 0.95
# sensor parameters whose estimates correlate more than this cannot be told apart by the
# maneuver (e.g. bias_ay and bias_r, b_ay = u b_r, without a heading output)
MAX_CORRELATION = 0.99
START_WINDOW_S = 0.5  # initial states from a line fit over this much of the record


# ------------------------------------------------------------------ parameters


@dataclass(frozen=True)
class Parameter:
    """One parameter of the reconstruction: its unit, a priori value and what it means."""

    name: str
    unit: str
    default: float
    step: float  # finite-difference half step for the sensitivities
    in_states: bool  # changes the integrated states (else only the output equations)
    description: str


def _catalogue() -> dict[str, Parameter]:
    out: dict[str, Parameter] = {}

    def add(name, unit, step, in_states, text, default=0.0):
        out[name] = Parameter(name, unit, default, step, in_states, text)

    for c in INPUTS:
        unit = CHANNELS[c].unit
        step = 1e-3 if c.startswith("a") else 1e-5
        add(f"bias_{c}", unit, step, True, f"bias of the {c} sensor ({unit})")
        add(f"scale_{c}", "-", 1e-4, True, f"scale-factor error of the {c} sensor: m = (1+s) x")
    for c in OUTPUTS:
        unit = CHANNELS[c].unit
        step = {"m/s": 1e-3, "rad": 1e-5, "m": 1e-2}[unit]
        add(f"bias_{c}", unit, step, False, f"bias of the measured {c} ({unit})")
        add(f"delay_{c}", "s", 1e-3, False, f"time delay of {c} behind the inertial inputs (s)")
    add("scale_V", "-", 1e-4, False, "airspeed scale-factor error: m = (1+s) V + b")
    add("upwash_alpha", "-", 1e-4, False, "alpha vane flow amplification: K_alpha = 1 + k")
    add("sidewash_beta", "-", 1e-4, False, "beta vane flow amplification: K_beta = 1 + k")
    for name in VANE_POSITIONS:
        axis = name[-1]
        add(name, "m", 1e-2, False, f"{name.split('_')[1]} vane position, body {axis} from the CG")
    for name in WIND:
        add(name, "m/s", 1e-3, True, f"constant wind, {name[5:]} component (m/s)")
    for s in STATES:
        unit = CHANNELS[s].unit
        step = {"m/s": 1e-3, "rad": 1e-5, "m": 1e-2}[unit]
        add(f"x0_{s}", unit, step, True, f"initial {s} ({unit})")
    return out


PARAMETERS: dict[str, Parameter] = _catalogue()


def _catalogue_effects() -> dict[str, tuple[str, str]]:
    """Parameter -> (entry, parameter) of the effect catalogue (``flightid effects``)."""
    out: dict[str, tuple[str, str]] = {}
    for name in PARAMETERS:
        kind, _, rest = name.partition("_")
        if kind == "bias":
            out[name] = ("bias", "value")  # bias_<c>: the bias on channel c
        elif kind == "scale":
            out[name] = ("scale", "factor")  # scale_<c> = factor - 1
        elif kind == "delay":
            out[name] = ("delay", "tau")
        elif kind == "vane":
            out[name] = ("vanes", rest)  # vane_alpha_x -> vanes.alpha_x
        elif kind == "wind":
            out[name] = ("wind", rest)
    out["upwash_alpha"] = ("vanes", "upwash")
    out["sidewash_beta"] = ("vanes", "sidewash")
    return out


# which injectable effect each sensor parameter estimates: name -> (catalogue entry, its
# parameter); the initial states x0_<state> are not effects
CATALOGUE_EFFECTS: dict[str, tuple[str, str]] = _catalogue_effects()


def default_free(record: FlightRecord, outputs: Sequence[str] | None = None) -> list[str]:
    """The parameters estimated unless told otherwise: the six inertial biases, the alpha
    and beta vane bias and flow amplification, and the airspeed bias (initial states are
    always added)."""
    outputs = list(outputs or _default_outputs(record))
    free = [f"bias_{c}" for c in INPUTS]
    if "alpha" in outputs:
        free += ["bias_alpha", "upwash_alpha"]
    if "beta" in outputs:
        free += ["bias_beta", "sidewash_beta"]
    if "V" in outputs:
        free += ["bias_V"]
    return free


def _default_outputs(record: FlightRecord) -> list[str]:
    return [c for c in DEFAULT_OUTPUTS if c in record and held_fraction(record[c]) < MAX_HELD]


def held_fraction(x: np.ndarray) -> float:
    """Fraction of samples that repeat the previous one exactly (a slow or held source)."""
    return float(np.mean(np.diff(np.asarray(x)) == 0)) if len(x) > 1 else 0.0


# ------------------------------------------------------------------ the model


@dataclass
class Problem:
    """A record arranged for the reconstruction: measured inputs and outputs, gravity."""

    time: np.ndarray
    dt: float
    inputs: np.ndarray  # (N, 6) measured ax ay az p q r
    outputs: tuple[str, ...]
    z: np.ndarray  # (N, ny) measured outputs (psi unwrapped)
    gravity: float
    latitude: float | None  # rad; None: flat, non-rotating Earth
    gyros: str  # 'inertial' (they sense Earth rate) or 'earth' (rates relative to the Earth)


def _corrected_inputs(problem: Problem, P: Mapping[str, np.ndarray]) -> np.ndarray:
    """True inputs (N, 6, K) from the measured ones: x = (m - bias) / (1 + scale)."""
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


def _integrate(problem: Problem, P: Mapping[str, np.ndarray], a: np.ndarray) -> np.ndarray:
    """States (N, 9, K): u v w phi theta psi h north east from the true inputs a (N, 6, K).

    Flat Earth: ``_navigate`` once. With a latitude, the rotating round Earth enters
    through the transport rate, the Earth rate (for inertial gyros) and the Coriolis
    acceleration (Savage 2007 ch. 4; Titterton & Weston 2004 eq. 3.40). These are 1e-5
    rad/s and 1e-2 m/s^2 at most, so they are evaluated on the flat solution and the
    navigation is run again with them: the neglected part is of their square.
    """
    states, rot, v_ned = _navigate(problem, P, a)
    if problem.latitude is None:
        return states
    lat = problem.latitude
    s2 = math.sin(lat) ** 2
    height = states[:, 6]  # (N, K)
    r_east = _A / math.sqrt(1 - _E2 * s2) + height  # prime-vertical radius + h
    r_north = _A * (1 - _E2) / (1 - _E2 * s2) ** 1.5 + height  # meridian radius + h
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
    """Flow angles (rad) at the alpha and beta vane positions (m, body axes from the CG)
    for CG air velocity u, v, w (m/s) and body rates p, q, r (rad/s): local velocity
    V + omega x r_vane (M&K 2016 eq. 10.12 before linearisation)."""
    xa, ya, za = alpha_pos
    xb, yb, zb = beta_pos
    alpha = np.arctan2(w + p * ya - q * xa, u + q * za - r * ya)
    ub, vb, wb = u + q * zb - r * yb, v + r * xb - p * zb, w + p * yb - q * xb
    beta = np.arcsin(np.clip(vb / np.sqrt(ub * ub + vb * vb + wb * wb), -1.0, 1.0))
    return alpha, beta


def _model_outputs(problem: Problem, P: Mapping[str, np.ndarray], x: np.ndarray,
                   a: np.ndarray) -> np.ndarray:
    """Modelled measurements (N, ny, K) from states x (N, 9, K) and true inputs a."""
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


def _batch(values: Mapping[str, float], k: int) -> dict[str, np.ndarray]:
    return {name: np.full(k, float(values.get(name, p.default)))
            for name, p in PARAMETERS.items()}


def simulate(problem: Problem, values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Modelled outputs (N, ny) and states (N, 9) at parameter ``values`` (SI units)."""
    P = _batch(values, 1)
    a = _corrected_inputs(problem, P)
    x = _integrate(problem, P, a)
    return _model_outputs(problem, P, x, a)[:, :, 0], x[:, :, 0]


def _outputs_and_sensitivities(problem: Problem, values: Mapping[str, float],
                               names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Outputs (N, ny) and central-difference sensitivities (N, ny, len(names)).

    One RK4 loop integrates the nominal and every +-step perturbation of the parameters
    that change the states; the output-only parameters reuse the nominal states.
    """
    in_states = [n for n in names if PARAMETERS[n].in_states]
    k_int = 1 + 2 * len(in_states)
    P = _batch(values, k_int)
    for j, name in enumerate(in_states):
        P[name][1 + 2 * j] += PARAMETERS[name].step
        P[name][2 + 2 * j] -= PARAMETERS[name].step
    a = _corrected_inputs(problem, P)
    x = _integrate(problem, P, a)
    # output batch: 1 + 2 len(names) members, each pointing at the integrated member it uses
    k_out = 1 + 2 * len(names)
    Q = _batch(values, k_out)
    source = np.zeros(k_out, dtype=int)
    for j, name in enumerate(names):
        step = PARAMETERS[name].step
        Q[name][1 + 2 * j] += step
        Q[name][2 + 2 * j] -= step
        if name in in_states:
            i = in_states.index(name)
            source[1 + 2 * j], source[2 + 2 * j] = 1 + 2 * i, 2 + 2 * i
    y = _model_outputs(problem, Q, x[:, :, source], a[:, :, source])
    steps = np.array([PARAMETERS[n].step for n in names])
    sens = (y[:, :, 1::2] - y[:, :, 2::2]) / (2.0 * steps)
    return y[:, :, 0], sens


# ------------------------------------------------------------------ set-up


def problem_from_record(record: FlightRecord, outputs: Sequence[str] | None = None,
                        gravity: float | None = None, latitude: float | None = None,
                        gyros: str | None = None) -> tuple[Problem, dict[str, str]]:
    """Arrange a record for the reconstruction; returns the problem and notes on choices.

    Checks channels, sampling and finite values. ``latitude`` (rad; default the mean of
    the record's latitude channel) switches on the rotating round Earth; without it the
    Earth is flat and still. Gravity (m/s^2): given, else the WGS84 normal gravity at the
    mean altitude and latitude (45 deg if unknown). ``gyros``: 'inertial' (real IMUs,
    they sense the Earth rate) or 'earth' (rates relative to the Earth, as JSBSim
    records them); default ``meta.extra['gyro_frame']``, else 'earth' for records whose
    provenance starts with "jsbsim", else 'inertial'.
    """
    notes: dict[str, str] = {}
    missing = [c for c in REQUIRED if c not in record]
    if missing:
        raise ValueError(
            f"record lacks channel(s) {', '.join(missing)}; flight path reconstruction needs "
            f"the inertial inputs {', '.join(INPUTS)} and the outputs V, alpha, beta, phi, theta"
        )
    outputs = tuple(outputs) if outputs is not None else tuple(_default_outputs(record))
    bad = [o for o in outputs if o not in OUTPUTS]
    if bad:
        raise ValueError(f"unknown output(s) {', '.join(bad)}; outputs are {', '.join(OUTPUTS)}")
    absent = [o for o in outputs if o not in record]
    if absent:
        raise ValueError(f"output(s) {', '.join(absent)} requested but not in the record")
    if not outputs:
        raise ValueError("no outputs to fit")
    time = record.time
    dt = record.uniform_step("the reconstruction", min_samples=MIN_SAMPLES)
    for c in (*INPUTS, *outputs):
        finite = np.isfinite(record[c])
        if not finite.all():
            i = int(np.argmin(finite))
            raise ValueError(f"channel {c!r} is not finite at sample {i} (t = {time[i]:.4g} s)")
    z = np.column_stack([np.unwrap(record[o]) if o == "psi" else record[o] for o in outputs])
    known = latitude
    if known is None and "latitude" in record:
        known = float(np.mean(record["latitude"]))
        notes["latitude"] = "mean of the record's latitude channel"
    if known is None:
        notes["earth"] = ("latitude unknown: flat, non-rotating Earth (Earth rate and "
                          "transport rate, < 0.005 deg/s, go into the gyro biases)")
    else:
        notes["earth"] = "rotating WGS84 Earth: transport rate, Earth rate, Coriolis"
    if gravity is None:
        lat_g = DEFAULT_LATITUDE if known is None else known
        altitude = float(np.mean(record["h"])) if "h" in record else 0.0
        gravity = local_gravity(lat_g, altitude)
        notes["gravity"] = (f"WGS84 normal gravity {gravity:.5f} m/s^2 at latitude "
                            f"{math.degrees(lat_g):.2f} deg, {altitude:.0f} m"
                            + (" (latitude assumed; +-0.026 m/s^2 goes into bias_az)"
                               if known is None else "")
                            + ("" if "h" in record else " (no h channel: sea level)"))
    else:
        notes["gravity"] = f"given: {gravity:.5f} m/s^2"
    if gyros is None:
        gyros = str(record.meta.extra.get("gyro_frame", ""))
        if not gyros:
            sim = record.meta.provenance.lower().startswith("jsbsim")
            gyros = "earth" if sim else "inertial"
            notes["gyros"] = ("JSBSim record: rates relative to the Earth (JSBSim "
                              "velocities/p-rad_sec)" if sim else "rates sensed by inertial gyros")
    if gyros not in ("inertial", "earth"):
        raise ValueError(f"gyros must be 'inertial' or 'earth', got {gyros!r}")
    inputs = np.column_stack([record[c] for c in INPUTS])
    return Problem(time.copy(), dt, inputs, outputs, z, float(gravity), known, gyros), notes


def _line_start(t: np.ndarray, x: np.ndarray) -> float:
    """Value at t[0] of a straight line fitted to the first START_WINDOW_S of x (noise-robust)."""
    n = max(3, min(len(t), int(round(START_WINDOW_S / (t[1] - t[0]))) + 1))
    c = np.polyfit(t[:n] - t[0], x[:n], 1)
    return float(c[1])


def initial_states(record: FlightRecord, values: Mapping[str, float]) -> dict[str, float]:
    """Start values x0_<state> from the record corrected with ``values`` (SI units)."""
    rec = correct(record, values, reconstruction=None)
    t = rec.time
    V, alpha, beta = (_line_start(t, rec[c]) for c in ("V", "alpha", "beta"))
    out = {
        "x0_u": V * math.cos(alpha) * math.cos(beta),
        "x0_v": V * math.sin(beta),
        "x0_w": V * math.sin(alpha) * math.cos(beta),
        "x0_phi": _line_start(t, rec["phi"]),
        "x0_theta": _line_start(t, rec["theta"]),
    }
    for s in ("psi", "h", "north", "east"):
        if s in rec:
            x = np.unwrap(rec[s]) if s == "psi" else rec[s]
            out[f"x0_{s}"] = _line_start(t, x)
    return out


# ------------------------------------------------------------------ estimation


def _iterate(problem: Problem, names: list[str], values: dict[str, float],
             max_iterations: int, step_tol: float, cost_tol: float) -> MaximumLikelihoodFit:
    """Maximum likelihood with a diagonal R: the output-error optimiser
    (``output_error.maximum_likelihood``: Newton-Raphson on N/2 ln det R with R concentrated
    out, Levenberg-Marquardt safeguard; M&K eqs. 6.22-6.33) on the kinematic model.

    Returns its fit with ``noise`` as the vector of output noise variances.
    """
    z = problem.z
    floor = (1e-10 * np.maximum(np.ptp(z, axis=0), np.abs(z).max(axis=0)) + 1e-300) ** 2
    fixed = {k: v for k, v in values.items() if k not in names}
    fit = maximum_likelihood(
        z, floor,
        lambda vals: _outputs_and_sensitivities(problem, {**fixed, **vals}, names),
        lambda vals: simulate(problem, {**fixed, **vals})[0],
        list(names), values, max_iterations, False, step_tol, cost_tol)
    fit.noise = np.diag(fit.noise).copy()
    return fit


# A scale factor k changes its channel by k * (peak-to-peak range): below these ranges that
# is under the calibration accuracy of flight-test sensors (Cooper, Drobik & Martin 1990,
# Table 1: vanes +-0.5 deg, rate gyros 0.5-3 deg/s, accelerometers 0.05 g, airspeed 10 kt) for any
# plausible k (< 25 %), so k cannot be told from the bias and the model error.
MIN_SCALE_RANGE = {"rad": math.radians(2.0), "rad/s": math.radians(10.0), "m/s^2": 0.2 * 9.80665,
                   "m/s": 20.0 * 0.514444}
_SCALED = {"upwash_alpha": "alpha", "sidewash_beta": "beta", "scale_V": "V",
           **{f"scale_{c}": c for c in INPUTS}}


def _unexcited(record: FlightRecord, names: Sequence[str]) -> dict[str, str]:
    """Scale factors whose channel barely moves in this flight, with the reason."""
    out = {}
    for name in names:
        channel = _SCALED.get(name)
        if channel is None:
            continue
        unit = CHANNELS[channel].unit
        span = float(np.ptp(record[channel]))
        need = MIN_SCALE_RANGE[unit]
        if span < need:
            out[name] = (f"{channel} moves only {span:.3g} {unit} peak to peak (< {need:.3g} "
                         f"{unit}): a scale factor cannot be told from the bias and the model "
                         "error; fly a larger excursion")
    return out


def _unidentifiable(names: list[str], fit: MaximumLikelihoodFit,
                    tolerance: float) -> dict[str, str]:
    values = np.array([fit.values[n] for n in names])
    found = ident.zero_sensitivity(names, fit.information, values)
    if found:
        return found
    # initial states must be estimated for the integration to start right: keep them
    keep = [n for n in names if n.startswith("x0_")]
    found = ident.collinear(names, fit.information, prefer_keep=keep, tolerance=tolerance)
    if found:
        return found
    corr = ident.correlation(np.linalg.inv(fit.information))
    sensors = [i for i, n in enumerate(names) if not n.startswith("x0_")]
    for i in sensors:
        for j in sensors:
            if j > i and abs(corr[i, j]) > MAX_CORRELATION:
                return {names[j]: (
                    f"correlation {corr[i, j]:+.4f} with {names[i]}: the maneuver cannot "
                    f"separate them; {names[j]} is fixed at its a priori value and "
                    f"{names[i]} absorbs both")}
    return {}


def _check_names(names: Sequence[str], outputs: Sequence[str], where: str) -> None:
    unknown = [n for n in names if n not in PARAMETERS]
    if unknown:
        raise ValueError(
            f"{where}: unknown parameter(s) {', '.join(unknown)}; known: {', '.join(PARAMETERS)}")
    for n in names:
        channel = n.split("_", 1)[1]
        if n.startswith(("bias_", "delay_")) and channel in OUTPUTS and channel not in INPUTS \
                and channel not in outputs:
            raise ValueError(f"{where}: {n} needs the output {channel!r}, which is not fitted "
                             f"(outputs: {', '.join(outputs)})")
    if any(n in names for n in WIND[:2]) and not any(o in outputs for o in ("north", "east")):
        raise ValueError(f"{where}: horizontal wind needs a north or east position output; the "
                         "air data and attitudes alone cannot see a constant wind")


def reconstruct(
    record: FlightRecord,
    *,
    free: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
    outputs: Sequence[str] | None = None,
    gravity: float | None = None,
    latitude: float | None = None,
    gyros: str | None = None,
    uncertainty: str = "noise",
    max_iterations: int = 60,
    step_tolerance: float = 1e-2,
    cost_tolerance: float = 1e-4,
    singular_eigenvalue: float = ident.SINGULAR_EIGENVALUE,
) -> tuple[FlightRecord, Estimate]:
    """Flight path reconstruction: estimate sensor calibration and return the corrected record.

    free: parameters to estimate (names of ``PARAMETERS``; default ``default_free``); the
    initial states x0_<state> are always added unless given in ``fixed``. fixed: known
    values (SI) of parameters not estimated, e.g. vane positions from drawings. outputs:
    measured channels to fit (default V alpha beta phi theta psi h, those present).
    gravity (m/s^2), latitude (rad) and gyros ('inertial' or 'earth') set the Earth model
    (see ``problem_from_record``). uncertainty: how the standard errors are formed (see
    ``UNCERTAINTY``). Returns the record with the estimates applied (``correct``) and the
    Estimate (values in SI units; ``PARAMETERS[name].unit``).
    A reconstruction that does not converge warns (``convergence.NotConvergedWarning``);
    ``max_iterations`` below 1 is refused.
    """
    convergence.check_limit("compatibility", "max_iterations", max_iterations)
    if uncertainty not in UNCERTAINTY:
        raise ValueError(f"uncertainty must be one of {', '.join(UNCERTAINTY)}, "
                         f"got {uncertainty!r}")
    fixed = dict(fixed or {})
    problem, notes = problem_from_record(record, outputs, gravity, latitude, gyros)
    names = list(default_free(record, problem.outputs) if free is None else free)
    _check_names(names, problem.outputs, "free")
    _check_names(list(fixed), problem.outputs, "fixed")
    both = [n for n in names if n in fixed]
    if both:
        raise ValueError(f"{', '.join(both)} given both as free and fixed")
    if len(set(names)) != len(names):
        raise ValueError("free lists a parameter twice")
    start = {**{n: p.default for n, p in PARAMETERS.items()}, **fixed}
    start.update({k: v for k, v in initial_states(record, start).items() if k not in fixed})
    used_states = [s for s in STATES if s in ("u", "v", "w", "phi", "theta")
                   or s in problem.outputs
                   or (s == "psi" and any(o in problem.outputs for o in ("north", "east")))]
    names += [f"x0_{s}" for s in used_states if f"x0_{s}" not in fixed and f"x0_{s}" not in names]

    unidentifiable: dict[str, str] = _unexcited(record, names)
    for _ in range(len(names) + 1):
        active = [n for n in names if n not in unidentifiable]
        values = {**start, **{n: start[n] for n in active}}
        # at the start values first, so that the iteration never meets a singular M
        probe = _iterate(problem, active, values, 0, step_tolerance, cost_tolerance)
        found = _unidentifiable(active, probe, singular_eigenvalue)
        if found:
            unidentifiable.update(found)
            continue
        fit = _iterate(problem, active, values, max_iterations, step_tolerance, cost_tolerance)
        found = _unidentifiable(active, fit, singular_eigenvalue)
        if not found:
            break
        unidentifiable.update(found)
    estimate = _result(problem, fit, {**start, **fit.values}, unidentifiable, uncertainty,
                       notes, fixed)
    applied = {**start, **fit.values}
    corrected = correct(record, applied, reconstruction=(problem, estimate))
    convergence.warn(estimate, "compatibility")
    return corrected, estimate


UNCERTAINTY = {
    "noise": "Cramer-Rao bound for the output noise plus the Monte Carlo scatter caused by "
             "the input noise (both noise levels from the data)",
    "colored": "Cramer-Rao bound corrected for colored residuals (M&K eq. 6.54)",
    "cramer-rao": "Cramer-Rao bound with the residual covariance (M&K eq. 6.50)",
}
MONTE_CARLO_RUNS = 200
OUTPUT_NOISE = "residual"


def white_noise_std(x: np.ndarray) -> float:
    """Standard deviation of the white noise on a sampled signal, in its unit.

    From third differences, which remove a smooth signal: var(d3 x) = 20 sigma^2 for white
    noise; robust (median absolute deviation) against the few samples where the signal
    jerks, falling back to the rms for a coarsely quantised signal whose median is 0.
    """
    d = np.diff(np.asarray(x, dtype=float), 3)
    robust = 1.4826 * float(np.median(np.abs(d - np.median(d))))
    return (robust if robust > 0 else float(np.std(d))) / math.sqrt(20.0)


def _noise_covariance(problem: Problem, fit: MaximumLikelihoodFit, values: Mapping[str, float],
                      runs: int = MONTE_CARLO_RUNS, seed: int = 0) -> tuple[np.ndarray, dict]:
    """Parameter covariance from the output noise and the input noise, with their levels.

    Output noise (white, level from ``white_noise_std``): the sandwich M^-1 S^T W R_out W
    S M^-1 of the weighted least-squares step. Input noise is integrated by the model,
    so its effect is a random walk that no stationary correction captures (the colored
    correction understates it several fold); it is propagated instead: ``runs`` input
    noise histories of the measured level go through the model at the estimate, and the
    Gauss-Newton step each one causes, -M^-1 S^T W dy, gives the covariance by Monte
    Carlo (fixed ``seed``). The two sources are independent, so the covariances add.
    """
    names = fit.names
    weight = 1.0 / fit.noise
    info_inv = np.linalg.inv(fit.information)
    out_sigma = np.array([white_noise_std(problem.z[:, j]) for j in range(problem.z.shape[1])])
    # an output held between slow updates (or coarsely quantised) is far from white: its
    # error is then at least the residual (conservative), which gives M^-1 for it
    out_var = np.maximum(out_sigma**2, fit.noise) if OUTPUT_NOISE == "residual" else out_sigma**2
    ws = fit.sens * weight[None, :, None]
    middle = np.einsum("iak,a,ial->kl", ws, out_var, ws)
    cov_out = info_inv @ middle @ info_inv
    in_sigma = np.array([white_noise_std(problem.inputs[:, j]) for j in range(len(INPUTS))])
    rng = np.random.default_rng(seed)
    steps = []
    for start in range(0, runs, 50):
        k = min(50, runs - start)
        P = _batch(values, k)
        a = _corrected_inputs(problem, P)
        a = a + rng.standard_normal(a.shape) * in_sigma[None, :, None]
        dy = _model_outputs(problem, P, _integrate(problem, P, a), a) - fit.y[:, :, None]
        steps.append(-info_inv @ np.einsum("iak,a,iar->kr", fit.sens, weight, dy))
    delta = np.concatenate(steps, axis=1)
    cov_in = delta @ delta.T / delta.shape[1]
    levels = {"input_noise_std": dict(zip(INPUTS, in_sigma.tolist(), strict=True)),
              "output_noise_std": dict(zip(problem.outputs, out_sigma.tolist(), strict=True)),
              "monte_carlo_runs": runs,
              "std_output_noise": dict(zip(names, np.sqrt(np.diag(cov_out)).tolist(),
                                           strict=True)),
              "std_input_noise": dict(zip(names, np.sqrt(np.diag(cov_in)).tolist(),
                                          strict=True))}
    return cov_out + cov_in, levels


def _result(problem: Problem, fit: MaximumLikelihoodFit, values: Mapping[str, float],
            unidentifiable: dict[str, str], uncertainty: str, notes: dict[str, str],
            fixed: Mapping[str, float]) -> Estimate:
    names = fit.names
    levels: dict = {}
    if uncertainty == "noise":
        cov, levels = _noise_covariance(problem, fit, values)
    elif uncertainty == "colored":
        weight = np.diag(1.0 / fit.noise)
        cov = colored_residual_covariance(fit.sens, fit.residuals, weight, fit.information)
    else:
        cov = np.linalg.inv(fit.information)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    spread = np.sum((problem.z - problem.z.mean(axis=0)) ** 2, axis=0)
    r2 = {o: float(1 - np.sum(fit.residuals[:, j] ** 2) / spread[j]) if spread[j] > 0
          else float("nan") for j, o in enumerate(problem.outputs)}
    outputs = {o: {"measured": problem.z[:, j], "model": fit.y[:, j],
                   "residual": fit.residuals[:, j]} for j, o in enumerate(problem.outputs)}
    stats = {
        "model": "kinematic flight path reconstruction (flat Earth, constant wind)",
        "converged": fit.converged,
        "reason": fit.reason,
        "iterations": fit.iterations,
        "cost": fit.cost_history[-1],
        "cost_history": list(fit.cost_history),
        "noise_std": {o: float(np.sqrt(fit.noise[j])) for j, o in enumerate(problem.outputs)},
        "R2_per_output": r2,
        "std_kind": UNCERTAINTY[uncertainty],
        "noise_levels": levels,
        "samples": int(problem.z.shape[0]),
        "outputs": list(problem.outputs),
        "inputs": list(INPUTS),
        "gravity_m_s2": problem.gravity,
        "notes": dict(notes),
        "fixed": {n: float(v) for n, v in fixed.items()},
        "units": {n: PARAMETERS[n].unit for n in names},
        "effects": {n: "{}.{}".format(*CATALOGUE_EFFECTS[n]) for n in names
                    if n in CATALOGUE_EFFECTS},
        "high_correlations": ident.high_correlations(names, cov, 0.9),
    }
    return Estimate(METHOD, list(names), np.array([fit.values[n] for n in names]), std, cov,
                    stats, dict(unidentifiable), outputs, problem.time.copy())


# ------------------------------------------------------------------ corrected record


def _shift(t: np.ndarray, x: np.ndarray, tau: float) -> np.ndarray:
    """x(t + tau): undo a delay tau (s); the end values are held."""
    return x if tau == 0 else np.interp(t + tau, t, x)


def correct(record: FlightRecord, values: Mapping[str, float],
            reconstruction: tuple[Problem, Estimate] | None = None) -> FlightRecord:
    """The record with calibration ``values`` (SI; missing ones at their defaults) applied.

    Inputs: x = (m - bias) / (1 + scale). V: (m(t + delay) - bias) / (1 + scale). Vanes:
    (m(t + delay) - bias) / (1 + k), then the vane-position effect removed exactly by a
    fixed-point iteration on ``vane_angles`` with the corrected rates. Attitudes, h,
    north, east: m(t + delay) - bias (psi keeps its wrapping). With ``reconstruction``
    (problem, estimate) the modelled outputs and u, v, w are added as
    ``<channel>_reconstructed`` and the estimates are documented in
    ``meta.extra['compatibility']``.
    """
    P = {n: float(values.get(n, p.default)) for n, p in PARAMETERS.items()}
    t = record.time
    ch: dict[str, np.ndarray] = {}
    how: dict[str, str] = {}
    for c in INPUTS:
        if c in record:
            ch[c] = (record[c] - P[f"bias_{c}"]) / (1.0 + P[f"scale_{c}"])
            how[c] = f"(m - {P[f'bias_{c}']:.6g}) / (1 + {P[f'scale_{c}']:.6g})"
    for c in ("phi", "theta", "h", "north", "east"):
        if c in record:
            ch[c] = _shift(t, record[c], P[f"delay_{c}"]) - P[f"bias_{c}"]
            how[c] = f"m(t + {P[f'delay_{c}']:.4g} s) - {P[f'bias_{c}']:.6g}"
    if "psi" in record:
        raw = record["psi"]
        shifted = _shift(t, np.unwrap(raw), P["delay_psi"]) - P["bias_psi"]
        ch["psi"] = shifted + (raw[0] - np.unwrap(raw)[0])
        if raw.min() >= 0 and raw.max() <= 2 * math.pi:
            ch["psi"] = np.mod(ch["psi"], 2 * math.pi)
        how["psi"] = f"m(t + {P['delay_psi']:.4g} s) - {P['bias_psi']:.6g}"
    if "V" in record:
        ch["V"] = (_shift(t, record["V"], P["delay_V"]) - P["bias_V"]) / (1.0 + P["scale_V"])
        how["V"] = f"(m(t + {P['delay_V']:.4g} s) - {P['bias_V']:.6g}) / (1 + {P['scale_V']:.6g})"
    if all(c in record for c in ("V", "alpha", "beta")):
        ch.update(_correct_vanes(record, P, ch))
        for c, k in (("alpha", "upwash_alpha"), ("beta", "sidewash_beta")):
            pos = ", ".join(f"{P[f'vane_{c}_{a}']:.4g}" for a in "xyz")
            how[c] = (f"(m(t + {P[f'delay_{c}']:.4g} s) - {P[f'bias_{c}']:.6g}) / "
                      f"(1 + {P[k]:.6g}), vane at ({pos}) m removed")
    units = dict(record.meta.units)
    extra = dict(record.meta.extra)
    if reconstruction is not None:
        problem, estimate = reconstruction
        for o in problem.outputs:
            ch[f"{o}_reconstructed"] = estimate.outputs[o]["model"].copy()
            units[f"{o}_reconstructed"] = CHANNELS[o].unit
        _, states = simulate(problem, values)
        for j, s in enumerate(("u", "v", "w")):
            ch[f"{s}_reconstructed"] = states[:, j]
            units[f"{s}_reconstructed"] = CHANNELS[s].unit
        extra["compatibility"] = {
            "method": "flight path reconstruction (identification/compatibility/reconstruction.py)",
            "estimates": {n: {"value": float(v), "std": float(s), "unit": PARAMETERS[n].unit}
                          for n, v, s in zip(estimate.names, estimate.values, estimate.std,
                                             strict=True)},
            "unidentifiable": dict(estimate.unidentifiable),
            "applied": {n: v for n, v in P.items() if v != PARAMETERS[n].default
                        and not n.startswith("x0_")},
            "corrections": how,
            "reconstructed": "channels <name>_reconstructed: the kinematic model outputs",
            "gravity_m_s2": problem.gravity,
        }
    meta = dataclasses.replace(record.meta, units=units, extra=extra)
    if reconstruction is not None:
        meta.provenance = (f"{record.meta.provenance}; corrected by flight path "
                           "reconstruction").lstrip("; ")
    return FlightRecord(t.copy(), {**record.channels, **ch}, meta)


def _correct_vanes(record: FlightRecord, P: Mapping[str, float],
                   ch: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Corrected alpha and beta: calibration undone, then the vane-position effect."""
    t = record.time
    av = (_shift(t, record["alpha"], P["delay_alpha"]) - P["bias_alpha"]) / (1 + P["upwash_alpha"])
    bv = (_shift(t, record["beta"], P["delay_beta"]) - P["bias_beta"]) / (1 + P["sidewash_beta"])
    apos = tuple(P[f"vane_alpha_{a}"] for a in "xyz")
    bpos = tuple(P[f"vane_beta_{a}"] for a in "xyz")
    if not any(apos) and not any(bpos):
        return {"alpha": av, "beta": bv}
    V = ch["V"]
    p, q, r = (ch.get(c, record[c]) if c in record else np.zeros_like(t) for c in ("p", "q", "r"))
    alpha, beta = av.copy(), bv.copy()
    for _ in range(6):  # contraction: the position effect is a small fraction of the angle
        u = V * np.cos(alpha) * np.cos(beta)
        v = V * np.sin(beta)
        w = V * np.sin(alpha) * np.cos(beta)
        a_model, b_model = vane_angles(u, v, w, p, q, r, apos, bpos)
        alpha = alpha + (av - a_model)
        beta = beta + (bv - b_model)
    return {"alpha": alpha, "beta": beta}
