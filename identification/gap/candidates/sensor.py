"""Sensor and mounting entries of the catalogue as candidates of the linear model.

- ``scale`` (sensor): one output scaled, y_measured = factor y;
- ``delay`` (sensor, tau s): a first-order Pade delay on one output; ``lag`` (sensor, tau
  s): a first-order lag 1/(tau s + 1) on one output; each one state appended
  (``model.lagged_output``). In the rigid-body band (omega tau << 1) both are
  1 - tau s to first order and differ only in tau^2 terms: a delay and a lag of the same
  channel form one equivalence class (docs/gap.md);
- ``misalignment`` (mounting, angle rad, axis ``y``): the IMU triad rotated about body y
  mixes the roll and yaw rates, p_s = cos(a) p - sin(a) r, r_s = sin(a) p + cos(a) r
  (``sim.effects.mounting.Misalignment``): a lateral candidate. About x or z the rotation
  mixes in q, ax or az, which one axis's model does not carry (``identifiable``);
- ``lever_arm`` (mounting, x z m): accelerometers off the CG read the tangential
  acceleration of the rotation, ay += x rdot - z pdot and az -= x qdot to first order
  (Morelli & Klein 2016, eq. 10.9), with rdot, pdot, qdot the model's own state rows;
- ``vanes`` (mounting, m): a vane ahead of the CG reads the rotation's flow,
  beta += x_b r/V and alpha -= x_a q/V to first order (Cooper, Drobik & Martin, ARL Flight
  Mechanics Report 187, 1990; Morelli & Klein 2016 §10.2); its z and y positions are left
  out (small on a nose boom). Its upwash and sidewash are ``scale`` of alpha and beta
  (factor = 1 + upwash): one equivalence class. In a Dutch roll r is close to -betadot,
  so x_b r/V is nearly a delay of beta by x_b/V: a beta vane 4.5 m ahead at 55 m/s and a
  beta delay of 0.08 s are nearly one class too.

Sensor ``bias`` is not a candidate: the output and state biases of the model (nuisance
parameters of every window) absorb it (``identifiable``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from flightid.identification.gap.model.edits import Candidate, extended, lagged_output
from flightid.identification.models.linear import LinearModel

TAU_START = 0.02  # s: start of a delay or lag fit (the catalogue's default is 0.05)


def _output_scale(channel: str) -> Callable[[LinearModel], LinearModel]:
    name = f"scale_{channel}"

    def wrap(model: LinearModel) -> LinearModel:
        row = model.outputs.index(channel)

        def build(v: Mapping[str, complex]) -> tuple:
            A, B, C, D = model.build(v)
            k = v[name]
            dtype = np.result_type(C.dtype, type(k))
            C, D = C.astype(dtype), D.astype(dtype)
            C[row] *= k
            D[row, :-1] *= k
            return A, B, C, D

        return extended(model, {name: 1.0}, build)

    return wrap


def scale(channel: str) -> Candidate:
    """The catalogue's sensor ``scale`` on output ``channel``.

    Parameters
    ----------
    channel : str
        An output of the model.

    Returns
    -------
    Candidate
        Its catalogue entry, options and the linear-model parameters it frees (the
        factor, 1: the model).
    """
    return Candidate("scale", {"channel": channel}, (f"scale_{channel}",),
                     _output_scale(channel))


def _time_constant(entry: str, channel: str) -> Candidate:
    name = f"{entry}_{channel}"
    pade = entry == "delay"

    def wrap(model: LinearModel) -> LinearModel:
        row = model.outputs.index(channel)

        def build(v: Mapping[str, complex]) -> tuple:
            return lagged_output(model.build(v), row, v[name], pade)

        return extended(model, {name: TAU_START}, build, (name,), channel)

    return Candidate(entry, {"channel": channel}, (name,), wrap, catalogue=("tau",))


def delay(channel: str) -> Candidate:
    """The catalogue's sensor ``delay`` (tau, s) on output ``channel``.

    Parameters
    ----------
    channel : str
        An output of the model.

    Returns
    -------
    Candidate
        Its catalogue entry, options and the linear-model parameters it frees (tau, s).
    """
    return _time_constant("delay", channel)


def lag(channel: str) -> Candidate:
    """The catalogue's sensor ``lag`` (tau, s) on output ``channel``.

    Parameters
    ----------
    channel : str
        An output of the model.

    Returns
    -------
    Candidate
        Its catalogue entry, options and the linear-model parameters it frees (tau, s).
    """
    return _time_constant("lag", channel)


def _rows(C: np.ndarray, D: np.ndarray, dtype) -> tuple[np.ndarray, np.ndarray]:
    return C.astype(dtype), D.astype(dtype)


def misalignment(model: LinearModel) -> Candidate | None:
    """The IMU triad rotated about body y (rad), when the model outputs p and r.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    Candidate or None
        None when the model lacks p or r.
    """
    if not {"p", "r"} <= set(model.outputs):
        return None
    name = "misalignment_y"

    def wrap(m: LinearModel) -> LinearModel:
        ip, ir = m.outputs.index("p"), m.outputs.index("r")

        def build(v: Mapping[str, complex]) -> tuple:
            A, B, C, D = m.build(v)
            a = v[name]
            c, s = np.cos(a), np.sin(a)
            C, D = _rows(C, D, np.result_type(C.dtype, type(a)))
            cp, cr, dp, dr = C[ip].copy(), C[ir].copy(), D[ip].copy(), D[ir].copy()
            C[ip], C[ir] = c * cp - s * cr, s * cp + c * cr
            D[ip], D[ir] = c * dp - s * dr, s * dp + c * dr
            return A, B, C, D

        return extended(m, {name: 0.0}, build)

    return Candidate("misalignment", {"axis": "y"}, (name,), wrap, catalogue=("angle",))


# per axis: the accelerometer output, and (lever-arm parameter, state, sign) of each term
_LEVER = {"ay": (("x", "r", 1.0), ("z", "p", -1.0)), "az": (("x", "q", -1.0),)}


def lever_arm(model: LinearModel) -> Candidate | None:
    """Accelerometers off the CG (m, body axes): ay or az with the tangential terms.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    Candidate or None
        None when the model outputs neither ay nor az (with the states they read).
    """
    channel = next((c for c in _LEVER if c in model.outputs), None)
    terms = tuple(t for t in _LEVER[channel] if t[1] in model.states) if channel else ()
    if not terms:
        return None
    names = tuple(f"lever_{axis}" for axis, _, _ in terms)

    def wrap(m: LinearModel) -> LinearModel:
        row = m.outputs.index(channel)
        rows = [m.states.index(state) for _, state, _ in terms]

        def build(v: Mapping[str, complex]) -> tuple:
            A, B, C, D = m.build(v)
            dtype = np.result_type(A.dtype, *(type(v[n]) for n in names))
            C, D = _rows(C, D, dtype)
            for n, i, (_, _, sign) in zip(names, rows, terms, strict=True):
                C[row] += sign * v[n] * A[i]
                D[row] += sign * v[n] * B[i]
            return A, B, C, D

        return extended(m, dict.fromkeys(names, 0.0), build)

    return Candidate("lever_arm", {}, names, wrap,
                     catalogue=tuple(axis for axis, _, _ in terms))


# per flow angle: (vane parameter, rate state, sign) of each term, all over V
# (a nose boom's z is small: beta_z is left out; with it the two-parameter vane lost to a
# one-parameter beta lag on the nested rule, the lateral blind card with beta_x 4.5 m)
_VANE = {"beta": (("beta_x", "r", 1.0),), "alpha": (("alpha_x", "q", -1.0),)}


def vanes(model: LinearModel) -> Candidate | None:
    """Flow vanes off the CG (m): beta or alpha with the rotation's flow.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    Candidate or None
        None without a reference condition, or when the model outputs neither beta nor
        alpha.
    """
    if model.condition is None:
        return None
    channel = next((c for c in _VANE if c in model.outputs), None)
    terms = tuple(t for t in _VANE[channel] if t[1] in model.states) if channel else ()
    if not terms:
        return None
    names = tuple(f"vane_{p}" for p, _, _ in terms)
    speed = model.condition.V

    def wrap(m: LinearModel) -> LinearModel:
        row = m.outputs.index(channel)
        cols = [m.states.index(state) for _, state, _ in terms]

        def build(v: Mapping[str, complex]) -> tuple:
            A, B, C, D = m.build(v)
            dtype = np.result_type(C.dtype, *(type(v[n]) for n in names))
            C, D = _rows(C, D, dtype)
            for n, j, (_, _, sign) in zip(names, cols, terms, strict=True):
                C[row, j] += sign * v[n] / speed
            return A, B, C, D

        return extended(m, dict.fromkeys(names, 0.0), build)

    return Candidate("vanes", {}, names, wrap, catalogue=tuple(p for p, _, _ in terms))


def sensor_candidates(model: LinearModel) -> list[Candidate]:
    """Every sensor and mounting candidate for ``model``: scale, delay and lag of each
    output, then misalignment, lever arm and vanes where the outputs carry them.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    list of Candidate
        In that order.
    """
    out = [scale(c) for c in model.outputs]
    out += [f(c) for f in (delay, lag) for c in model.outputs]
    out += [c for f in (misalignment, lever_arm, vanes) if (c := f(model)) is not None]
    return out
