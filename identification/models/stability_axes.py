"""The lateral moments of a linear model in the stability axes of the measured alpha.

``with_stability_axes`` rotates the lateral model's roll and yaw aerodynamic moments with
the instantaneous angle of attack, fed in as known pseudo-inputs '<x>*dalpha' that
``with_stability_axes_channels`` computes from a record (Morelli & Klein 2016 ch. 6).
``_aerodynamic_sources`` names the states and inputs some derivative multiplies.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from flightid.derivatives import is_derivative
from flightid.identification.models.linear import LinearModel, Matrices
from flightid.record import FlightRecord

# the lateral moments and rates a preset rotates with the measured angle of attack when
# the aircraft's aerodynamics are linear in stability axes (``with_stability_axes``):
# (rows of the roll and yaw accelerations, columns of the roll and yaw rates)
STABILITY_AXES: dict[str, tuple[str, str]] = {"lateral": ("p", "r")}
ALPHA_SUFFIX = "*dalpha"
MOMENT_AXES = ("body", "stability")


def stability_axes_inputs(model: LinearModel) -> tuple[str, ...]:
    """The pseudo-input channels of ``with_stability_axes``.

    Parameters
    ----------
    model : LinearModel
        A lateral linear model.

    Returns
    -------
    tuple of str
        '<x>*dalpha' for each state and surface of ``model`` an aerodynamic derivative
        multiplies.
    """
    return tuple(f"{x}{ALPHA_SUFFIX}" for x in _aerodynamic_sources(model))


def with_stability_axes_channels(record: FlightRecord, model: LinearModel) -> FlightRecord:
    """``record`` with the pseudo-inputs of ``with_stability_axes(model)``.

    (alpha - alpha_ref) x for each measured state and surface x (alpha_ref the model's
    reference angle of attack).

    Parameters
    ----------
    record : FlightRecord
        The flight, with alpha (rad) and the model's states and inputs (SI).
    model : LinearModel
        A lateral linear model with a reference condition.

    Returns
    -------
    FlightRecord
        A copy with the channels '<x>*dalpha', each in the unit of its source x (per rad
        of alpha).
    """
    d_alpha = record["alpha"] - model.condition.alpha
    extra, units = {}, dict(record.meta.units)
    for x, name in zip(_aerodynamic_sources(model), stability_axes_inputs(model), strict=True):
        channel = model.state_channels.get(x, x)
        extra[name] = d_alpha * record[channel]
        units[name] = record.unit(channel)
    return FlightRecord(record.time, {**record.channels, **extra},
                        dataclasses.replace(record.meta, units=units))


def with_stability_axes(model: LinearModel) -> LinearModel:
    """``model`` for an aircraft whose lateral aerodynamics are linear in the stability
    axes of the instantaneous angle of attack (JSBSim's frame="STABILITY", rates
    p_s = p cos alpha + r sin alpha, r_s = r cos alpha - p sin alpha).

    The parameters stay the body-axis derivatives at the reference alpha_0. At
    alpha = alpha_0 + da the stability axes turn by da about y, so to first order in da
    (Etkin & Reid 1996 sec. 4.3, the axis transformation of the derivatives)
      [Cl; Cn] += da ([-Cn; Cl] + [C.._p rhat - C.._r phat]),  CY += da (CY_p rhat - CY_r phat),
    the moments' rotation and the rates' (the derivatives' axis transformation,
    Etkin & Reid eq. 4.3,5, taken along the flight). The second-order terms enter as
    known inputs '<x>*dalpha' = da x (``with_stability_axes_channels``) through the
    model's own aerodynamic columns, as ``with_dynamic_pressure`` does, so the
    sensitivities stay exact. On navion-demo's exact truth record (stability-axis
    aerodynamics, alpha within 0.25 deg of trim) a regression of the body-axis Cl on
    beta, phat, rhat, da, dr puts Cl_dr +1.7 %, Cn_da +4.5 %, Cn_p -0.9 % off; with the
    stability-axis rates and moments it fits to 1e-8.

    Parameters
    ----------
    model : LinearModel
        The linear model.

    Returns
    -------
    LinearModel
        A copy with the pseudo-inputs ``stability_axes_inputs(model)`` added before the bias
        column; ``model`` unchanged for a preset not in ``STABILITY_AXES`` or without a
        condition.
    """
    if model.name not in STABILITY_AXES or model.condition is None:
        return model
    roll, yaw = (model.states.index(s) for s in STABILITY_AXES[model.name])
    c = model.condition
    inertia = np.array([[c.Ixx, -c.Ixz], [-c.Ixz, c.Izz]])
    # [pdot; rdot] = I^-1 [L; N]: the moment rotation [L; N] -> [-N; L] in acceleration rows
    turn = np.linalg.solve(inertia, np.array([[0.0, -1.0], [1.0, 0.0]]) @ inertia)
    zero = {p: 0.0 for p in model.parameters if is_derivative(p)}
    sources = _aerodynamic_sources(model)
    n_in = len(model.inputs)
    names = (*model.states, *model.inputs)
    column = {x: names.index(x) for x in sources}

    def build(values: Mapping[str, complex]) -> Matrices:
        A, B, C, D = model.build(values)
        A0, B0, C0, D0 = model.build({**values, **zero})
        aero_x = np.concatenate([A - A0, B[:, :n_in] - B0[:, :n_in]], axis=1)
        aero_y = np.concatenate([C - C0, D[:, :n_in] - D0[:, :n_in]], axis=1)
        bx = np.zeros((A.shape[0], len(sources)), dtype=A.dtype)
        dy = np.zeros((C.shape[0], len(sources)), dtype=C.dtype)
        for k, x in enumerate(sources):
            bx[[roll, yaw], k] = turn @ aero_x[[roll, yaw], column[x]]
            # the rates' rotation: p_s picks up da r, r_s loses da p
            if x == model.states[yaw]:
                bx[:, k] += aero_x[:, roll]
                dy[:, k] += aero_y[:, roll]
            elif x == model.states[roll]:
                bx[:, k] -= aero_x[:, yaw]
                dy[:, k] -= aero_y[:, yaw]
        return (A, np.concatenate([B[:, :n_in], bx, B[:, n_in:]], axis=1), C,
                np.concatenate([D[:, :n_in], dy, D[:, n_in:]], axis=1))

    return LinearModel(model.name, model.states, (*model.inputs, *stability_axes_inputs(model)),
                       model.outputs, model.parameters, dict(model.start), build,
                       model.condition,
                       f"{model.description}, its moments in stability axes",
                       dict(model.state_channels))


def _aerodynamic_sources(model: LinearModel) -> list[str]:
    """The states and inputs of ``model`` that some derivative multiplies: a structural
    test (the matrices with every derivative at 1 against at 0), so an attitude
    (kinematic only) needs no channel."""
    names = [p for p in model.parameters if is_derivative(p)]
    on = model.build({**model.start, **dict.fromkeys(names, 1.0)})
    off = model.build({**model.start, **dict.fromkeys(names, 0.0)})
    m = len(model.inputs)
    moved = np.concatenate([np.abs(on[0] - off[0]), np.abs(on[1] - off[1])[:, :m]], axis=1)
    moved_y = np.concatenate([np.abs(on[2] - off[2]), np.abs(on[3] - off[3])[:, :m]], axis=1)
    used = (moved.sum(axis=0) + moved_y.sum(axis=0)) > 0
    return [x for x, u in zip((*model.states, *model.inputs), used, strict=True) if u]
