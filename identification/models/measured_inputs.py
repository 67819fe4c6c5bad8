"""Known inputs from measured channels for a linear model (``linear.LinearModel``): the
propulsive moments (``with_propulsive_moments``), the aerodynamic terms following the
measured dynamic pressure and airspeed (``with_dynamic_pressure``) and the kinematics and
inertial coupling beyond their linearisation (``with_kinematics``), each with the
pseudo-input channels it reads from a record (Morelli & Klein 2016 ch. 3 and 6)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from flightid.derivatives import is_derivative
from flightid.identification.models.linear import LinearModel, Matrices
from flightid.record import FlightRecord

# the measured propulsive moments (N m, body axes) a preset can take as known inputs
PROPULSIVE_MOMENTS: dict[str, tuple[str, ...]] = {"lateral": ("L_prop", "N_prop")}


def with_propulsive_moments(model: LinearModel) -> LinearModel:
    """``model`` driven also by the record's propulsive moments, known inputs with no parameter.

    The lateral model's pdot and rdot get [[Ixx, -Ixz], [-Ixz, Izz]]^-1 [L_prop; N_prop]
    (Morelli & Klein 2016 eq. 3.37), as equation error subtracts them from the moments it
    regresses (``data.coefficients``), so that both estimate the aerodynamic derivatives.
    Without them a twin's differential thrust (each propeller at y sees u - r y) is read as
    aerodynamic damping: on twinotter-lateral-0alpha's exact truth record output error puts
    Cn_r +2.1 %, Cn_p -1.9 %, Cn_beta -1.1 % off without them, +0.05 %, -0.9 %, -0.6 % with
    them.

    Parameters
    ----------
    model : LinearModel
        The linear model.

    Returns
    -------
    LinearModel
        A copy with the inputs L_prop, N_prop (N m, body axes) added before the bias column;
        ``model`` unchanged for another preset, without a condition, or when it already has
        them.
    """
    extra = PROPULSIVE_MOMENTS.get(model.name, ())
    if not extra or model.condition is None or set(extra) & set(model.inputs):
        return model
    c = model.condition
    gamma = c.Ixx * c.Izz - c.Ixz**2
    inverse = np.array([[c.Izz, c.Ixz], [c.Ixz, c.Ixx]]) / gamma
    rows = [model.states.index("p"), model.states.index("r")]
    m = len(model.inputs)

    def build(values: Mapping[str, complex]) -> Matrices:
        A, B, C, D = model.build(values)
        B2 = np.zeros((B.shape[0], m + len(extra) + 1), dtype=B.dtype)
        D2 = np.zeros((D.shape[0], m + len(extra) + 1), dtype=D.dtype)
        B2[:, :m], B2[:, -1] = B[:, :m], B[:, -1]
        D2[:, :m], D2[:, -1] = D[:, :m], D[:, -1]
        B2[np.ix_(rows, [m, m + 1])] = inverse
        return A, B2, C, D2

    return LinearModel(model.name, model.states, (*model.inputs, *extra), model.outputs,
                       model.parameters, dict(model.start), build, model.condition,
                       f"{model.description}, driven by the measured {', '.join(extra)}",
                       dict(model.state_channels))


# the presets whose aerodynamic terms ``with_dynamic_pressure`` makes follow the measured
# dynamic pressure and airspeed (the longitudinal ones carry the speed as a state and its
# 2 dV/V terms), with, per preset, the powers of 1/V beyond qbar of the state equations
# (betadot = qbar S/(m V) CY + ...) and of the variables (phat = p b/2V, rhat = r b/2V)
QBAR_SCHEDULED: dict[str, tuple[dict[str, int], dict[str, int]]] = {
    "lateral": ({"beta": 1}, {"p": 1, "r": 1}),
}
QBAR_SUFFIX = "*dqbar"


def _scheduled_sources(model: LinearModel) -> list[tuple[str, int]]:
    """(state or input, power of 1/V) of each pseudo-input of ``with_dynamic_pressure``:
    the states and inputs some derivative multiplies (a structural test: the matrices with
    every derivative at 1 against at 0), so an attitude (kinematic only) needs no channel."""
    rows, cols = QBAR_SCHEDULED[model.name]
    powers = sorted({0, *rows.values()})
    return [(x, cols.get(x, 0) + k) for x in _aerodynamic_sources(model) for k in powers]


def dynamic_pressure_inputs(model: LinearModel) -> tuple[str, ...]:
    """The pseudo-input channels of ``with_dynamic_pressure``.

    Parameters
    ----------
    model : LinearModel
        A lateral linear model.

    Returns
    -------
    tuple of str
        '<x>*dqbar<k>' for each state and input x of ``model`` that a derivative multiplies
        and each power k of 1/V.
    """
    return tuple(f"{x}{QBAR_SUFFIX}{k}" for x, k in _scheduled_sources(model))


def pseudo_input_source(name: str) -> str:
    """The state or input a pseudo-input of ``with_dynamic_pressure`` or ``with_stability_axes``
    is made of.

    Parameters
    ----------
    name : str
        Input name, e.g. 'dr*dqbar0' or 'dr*dalpha*dqbar0'.

    Returns
    -------
    str
        The source name ('dr' for both examples); any other input name unchanged.
    """
    return name.split(QBAR_SUFFIX, 1)[0].split(ALPHA_SUFFIX, 1)[0]


def with_dynamic_pressure_channels(record: FlightRecord, model: LinearModel) -> FlightRecord:
    """``record`` with the pseudo-inputs of ``with_dynamic_pressure(model)``.

    eps_k(t) x(t), eps_k = (qbar/qbar_ref) (V_ref/V)^k - 1, for each measured state and
    input x (reference qbar and V those of the model).

    Parameters
    ----------
    record : FlightRecord
        The flight, with channels qbar (Pa), V (m/s) and the model's states and inputs (SI).
    model : LinearModel
        A lateral linear model with a reference condition.

    Returns
    -------
    FlightRecord
        A copy with the channels '<x>*dqbar<k>', each in the unit of its source x.
    """
    c = model.condition
    ratio = record["qbar"] / c.qbar
    names = dynamic_pressure_inputs(model)
    extra, units = {}, dict(record.meta.units)
    for name, (x, k) in zip(names, _scheduled_sources(model), strict=True):
        channel = model.state_channels.get(x, x)
        extra[name] = (ratio * (c.V / record["V"]) ** k - 1.0) * record[channel]
        units[name] = record.unit(channel)
    return FlightRecord(record.time, {**record.channels, **extra},
                        dataclasses.replace(record.meta, units=units))


def with_dynamic_pressure(model: LinearModel) -> LinearModel:
    """``model`` whose aerodynamic terms follow the measured dynamic pressure and airspeed.

    The model holds qbar and V at their reference values, but in a large lateral maneuver
    the airspeed, and so qbar, drops while the forces and moments are largest: on
    twinotter-lateral-0alpha (NASA's 2.8 deg rudder 2-1-1 and 6 deg aileron doublet)
    qbar falls by 1 %, and output error without this reads the force and moment
    derivatives 0.5-1.7 % small in magnitude on the exact truth record (Cl_da -0.94 %,
    Cl_dr -1.6 %, CY_dr -1.0 %), an error that falls with the square of the input amplitude
    (Cl_da -0.24 % and -0.06 % at half and a quarter of it). Each aerodynamic term,
    qbar S (...) C with (...) carrying 1/V^k (k from the state equation's and the variable's
    1/V, ``QBAR_SCHEDULED``), is written as at the reference times (1 + eps_k),
    eps_k = (qbar/qbar_ref) (V_ref/V)^k - 1; the second-order part takes the measured
    states and inputs as pseudo-inputs '<x>*dqbar<k>' = eps_k x
    (``with_dynamic_pressure_channels``) through the same aerodynamic matrix columns
    (measured variables as pseudo-control inputs, Jategaonkar 2015 ch. 4; their noise
    enters multiplied by eps, about 0.01). The aerodynamic columns are the difference of
    the matrices at the parameter values and with every derivative at zero (the builders
    are linear in the derivatives), so the sensitivities stay exact.

    Parameters
    ----------
    model : LinearModel
        The linear model.

    Returns
    -------
    LinearModel
        A copy with the pseudo-inputs ``dynamic_pressure_inputs(model)`` added before the
        bias column; ``model`` unchanged for a preset not in ``QBAR_SCHEDULED`` or without
        a condition.
    """
    if model.name not in QBAR_SCHEDULED or model.condition is None:
        return model
    rows, _ = QBAR_SCHEDULED[model.name]
    zero = {p: 0.0 for p in model.parameters if is_derivative(p)}
    m = len(model.inputs)
    sources = _scheduled_sources(model)
    column = {x: j for j, x in enumerate((*model.states, *model.inputs))}
    state_power = np.array([rows.get(x, 0) for x in model.states])
    output_power = np.array([rows.get(y, 0) if y in rows and y not in model.states else 0
                             for y in model.outputs])

    def build(values: Mapping[str, complex]) -> Matrices:
        A, B, C, D = model.build(values)
        A0, B0, C0, D0 = model.build({**values, **zero})
        aero_x = np.concatenate([A - A0, B[:, :m] - B0[:, :m]], axis=1)
        aero_y = np.concatenate([C - C0, D[:, :m] - D0[:, :m]], axis=1)
        bx, dy = [], []
        for x, k in sources:
            j, own = column[x], k - _scheduled_power(model, x)
            bx.append(aero_x[:, j] * (state_power == own))
            dy.append(aero_y[:, j] * (output_power == own))
        return (A, np.concatenate([B[:, :m], np.stack(bx, axis=1), B[:, m:]], axis=1), C,
                np.concatenate([D[:, :m], np.stack(dy, axis=1), D[:, m:]], axis=1))

    return LinearModel(model.name, model.states,
                       (*model.inputs, *dynamic_pressure_inputs(model)), model.outputs,
                       model.parameters, dict(model.start), build, model.condition,
                       f"{model.description}, its aerodynamic terms following qbar(t), V(t)",
                       dict(model.state_channels))


# the lateral model's kinematic terms beyond their linearisation, computed from measured
# channels and fed in as known inputs of the state equations (``with_kinematics``)
KINEMATIC_INPUTS: dict[str, dict[str, str]] = {
    "lateral": {"beta": "betadot_kinematics", "phi": "phidot_kinematics",
                "p": "pdot_inertial", "r": "rdot_inertial"}}
KINEMATIC_CHANNELS = ("V", "alpha", "theta", "phi", "p", "q", "r")


def with_kinematics_channels(record: FlightRecord, model: LinearModel) -> FlightRecord:
    """``record`` with the known inputs of ``with_kinematics(model)``.

    The lateral kinematics and Euler's inertial coupling less their linearisation about
    the model's reference condition (level, wings-level, p0 = q0 = r0 = 0),
      betadot: p (sin alpha - sin alpha0) - r (cos alpha - cos alpha0)
               + g (cos theta sin phi / V - cos theta0 phi / V0)
               + sin beta [g (cos alpha sin theta - sin alpha cos theta cos phi)
                           - ax cos alpha - az sin alpha] / V
               + (cos beta - 1) (ay + g cos theta sin phi) / V
      phidot:  tan theta (q sin phi + r cos phi) - tan theta0 r
      [pdot; rdot]: [[Ixx, -Ixz], [-Ixz, Izz]]^-1 [(Iyy - Izz) q r + Ixz p q;
                                                  (Ixx - Iyy) p q - Ixz q r]
    (Stevens, Lewis & Johnson 2016 sec. 2.4, the wind-axis betadot with the specific forces;
    Morelli & Klein 2016 eqs. 3.36-3.37), from the measured channels. The sin beta term,
    zero in trim, carries the airspeed's change (-beta Vdot/V); a record without ax, az
    or beta goes without it. The cos beta term is the side force's and the bank's
    projection on the wind y axis beyond the linear model's qbar S CY/(m V) and g phi/V:
    the model's ay output reads the side force without it, so without the term the betadot
    and ay equations disagree by the factor cos beta (-0.06 % of CY at 2 deg), and output
    error's CY_beta follows the weight of the ay channel: on twinotter-lateral-0alpha
    (beta to 5 deg; 16 realizations) its mean error is +1.7 bounds without the term (+0.9
    with the ay noise set to zero), +0.5 and +0.4 with it. A record without ay or beta
    goes without it.

    Parameters
    ----------
    record : FlightRecord
        The flight, with channels V (m/s), alpha, theta, phi (rad), p, q, r (rad/s) and
        optionally beta (rad), ax, ay, az (m/s^2).
    model : LinearModel
        A lateral linear model with a reference condition.

    Returns
    -------
    FlightRecord
        A copy with the channels of ``KINEMATIC_INPUTS[model.name]``: betadot_kinematics,
        phidot_kinematics (rad/s), pdot_inertial, rdot_inertial (rad/s^2).
    """
    c = model.condition
    a, th, ph = record["alpha"], record["theta"], record["phi"]
    p, q, r = record["p"], record["q"], record["r"]
    names = KINEMATIC_INPUTS[model.name]
    extra = {
        names["beta"]: (p * (np.sin(a) - np.sin(c.alpha)) - r * (np.cos(a) - np.cos(c.alpha))
                        + c.g * (np.cos(th) * np.sin(ph) / record["V"]
                                 - np.cos(c.theta) * ph / c.V)),
        names["phi"]: np.tan(th) * (q * np.sin(ph) + r * np.cos(ph)) - np.tan(c.theta) * r,
    }
    if all(k in record for k in ("ax", "az", "beta")):
        sin_beta = np.sin(record["beta"])
        extra[names["beta"]] = extra[names["beta"]] + sin_beta * (
            c.g * (np.cos(a) * np.sin(th) - np.sin(a) * np.cos(th) * np.cos(ph))
            - record["ax"] * np.cos(a) - record["az"] * np.sin(a)) / record["V"]
    if all(k in record for k in ("ay", "beta")):
        extra[names["beta"]] = extra[names["beta"]] + (np.cos(record["beta"]) - 1.0) * (
            record["ay"] + c.g * np.cos(th) * np.sin(ph)) / record["V"]
    gamma = c.Ixx * c.Izz - c.Ixz**2
    roll = (c.Iyy - c.Izz) * q * r + c.Ixz * p * q
    yaw = (c.Ixx - c.Iyy) * p * q - c.Ixz * q * r
    extra[names["p"]] = (c.Izz * roll + c.Ixz * yaw) / gamma
    extra[names["r"]] = (c.Ixz * roll + c.Ixx * yaw) / gamma
    units = {**record.meta.units, **{n: "rad/s" for n in extra},
             names["p"]: "rad/s^2", names["r"]: "rad/s^2"}
    return FlightRecord(record.time, {**record.channels, **extra},
                        dataclasses.replace(record.meta, units=units))


def with_kinematics(model: LinearModel) -> LinearModel:
    """``model`` with the known inputs of ``with_kinematics_channels``.

    One input per state equation it completes (coefficient 1, no parameter). On
    twinotter-lateral-0alpha (bank to 10 deg, alpha moving 0.3 deg, theta 1.4 deg), with
    the dynamic pressure followed (``with_dynamic_pressure``), linearised kinematics put
    output error's yaw derivatives 0.4-2.5 % off on the exact truth record. On
    navion-sweep-roll (a 90 s aileron sweep, airspeed 45-49 m/s, bank to 19 deg), with the
    propulsive moments driven, the omitted inertial coupling and betadot's sin beta term
    put output error's Cn_r -0.97 %, Cn_p -0.91 %, Cn_beta -0.21 % off; with them -0.43 %,
    -0.57 %, -0.00 %.

    Parameters
    ----------
    model : LinearModel
        The linear model.

    Returns
    -------
    LinearModel
        A copy with the known inputs added before the bias column; ``model`` unchanged for a
        preset not in ``KINEMATIC_INPUTS`` or without a condition.
    """
    names = KINEMATIC_INPUTS.get(model.name)
    if not names or model.condition is None:
        return model
    rows = [model.states.index(s) for s in names]
    m = len(model.inputs)

    def build(values: Mapping[str, complex]) -> Matrices:
        A, B, C, D = model.build(values)
        known = np.zeros((B.shape[0], len(rows)), dtype=B.dtype)
        known[rows, range(len(rows))] = 1.0
        return (A, np.concatenate([B[:, :m], known, B[:, m:]], axis=1), C,
                np.concatenate([D[:, :m], np.zeros((D.shape[0], len(rows)), D.dtype),
                                D[:, m:]], axis=1))

    return LinearModel(model.name, model.states, (*model.inputs, *names.values()),
                       model.outputs, model.parameters, dict(model.start), build,
                       model.condition, f"{model.description}, with its full kinematics",
                       dict(model.state_channels))


def driven_by_measurements(record: FlightRecord, model: LinearModel, *,
                           dynamic_pressure: bool = True, propulsive_moments: bool = True,
                           moment_axes: str = "body") -> tuple[FlightRecord, LinearModel]:
    """(record, model) with the known inputs a linear lateral model takes from ``record``,
    as output error and filter error both use them.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels; the pseudo-input channels are added to a copy.
    model : LinearModel
        A linear model (``linear.LinearModel``); other presets than the lateral one come
        back unchanged.
    dynamic_pressure : bool, optional
        The aerodynamic terms follow the measured qbar (Pa) and V (m/s)
        (``with_dynamic_pressure``), and with them the full kinematics and inertial
        coupling (``with_kinematics``) where the record has their channels. Default True.
    propulsive_moments : bool, optional
        Drive the model with the record's L_prop, N_prop (N m)
        (``with_propulsive_moments``) where it has them. Default True.
    moment_axes : str, optional
        'body' (default), or 'stability' for an aircraft whose lateral aerodynamics are
        linear in the stability axes of the instantaneous alpha (``with_stability_axes``;
        the record needs ``alpha``, rad).

    Returns
    -------
    record : FlightRecord
        The flight with the pseudo-input channels the model reads.
    model : LinearModel
        The model with those known inputs.

    Raises
    ------
    ValueError
        ``moment_axes`` is not in ``MOMENT_AXES``, or 'stability' without an alpha channel.
    """
    if moment_axes not in MOMENT_AXES:
        raise ValueError(f"moment_axes must be one of {', '.join(MOMENT_AXES)}, got "
                         f"{moment_axes!r}")
    if moment_axes == "stability" and model.name in STABILITY_AXES and model.condition:
        if "alpha" not in record:
            raise ValueError("moment_axes=stability needs the record's alpha channel (rad)")
        record = with_stability_axes_channels(record, model)
        model = with_stability_axes(model)
    if (dynamic_pressure and model.name in QBAR_SCHEDULED and "qbar" in record
            and "V" in record):
        record = with_dynamic_pressure_channels(record, model)
        model = with_dynamic_pressure(model)
        if model.name in KINEMATIC_INPUTS and all(c in record for c in KINEMATIC_CHANNELS):
            record = with_kinematics_channels(record, model)
            model = with_kinematics(model)
    moments = PROPULSIVE_MOMENTS.get(model.name, ())
    if propulsive_moments and moments and all(c in record for c in moments):
        model = with_propulsive_moments(model)
    return record, model


def known_input_notes(model: LinearModel) -> dict[str, str]:
    """What ``driven_by_measurements`` gave ``model``, for an estimate's ``fit``.

    Parameters
    ----------
    model : LinearModel
        A model returned by ``driven_by_measurements``.

    Returns
    -------
    dict of str to str
        {'dynamic_pressure' | 'propulsive_moments' | 'moment_axes': description}, only the
        keys that apply.
    """
    notes = {}
    if is_scheduled(model):
        notes["dynamic_pressure"] = (f"aerodynamic terms times qbar(t)/"
                                     f"{model.condition.qbar:.1f} Pa")
    moments = [c for c in PROPULSIVE_MOMENTS.get(model.name, ()) if c in model.inputs]
    if moments:
        notes["propulsive_moments"] = f"{', '.join(moments)} (N m) as measured inputs"
    if any(ALPHA_SUFFIX in name for name in model.inputs):
        notes["moment_axes"] = "stability axes of the measured alpha"
    return notes


def is_scheduled(model: LinearModel) -> bool:
    """Whether ``model``'s aerodynamic terms follow the measured dynamic pressure.

    Parameters
    ----------
    model : LinearModel
        The linear model.

    Returns
    -------
    bool
        True when it has the pseudo-inputs of ``with_dynamic_pressure``.
    """
    return any(QBAR_SUFFIX in name for name in model.inputs)


def _scheduled_power(model: LinearModel, x: str) -> int:
    return QBAR_SCHEDULED[model.name][1].get(x, 0)


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
