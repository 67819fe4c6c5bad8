"""Longitudinal linear perturbation models: short period (alpha, q) and full (V, alpha, q, theta).

The longitudinal counterparts of ``models.linear.lateral`` (Morelli & Klein 2016 ch. 6,
SIDPAC's ``lon`` model file): their derivative names, defaults, biases and start values,
and the builders of the ``LinearModel`` at a reference condition.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from flightid.identification.models.linear import (
    LinearModel,
    Matrices,
    parameter_starts,
)
from flightid.identification.models.reference_condition import ReferenceCondition

SHORT_PERIOD_DERIVATIVES: tuple[str, ...] = (
    "CL_alpha", "CL_q", "CL_de", "Cm_alpha", "Cm_q", "Cm_de", "Cm_alphadot",
)
SHORT_PERIOD_DEFAULT: tuple[str, ...] = (
    "CL_alpha", "CL_de", "Cm_alpha", "Cm_q", "Cm_de",
)
SHORT_PERIOD_BIASES: tuple[str, ...] = ("bias_alphadot", "bias_qdot", "bias_az")

LONGITUDINAL_DERIVATIVES: tuple[str, ...] = (
    "CD_0", "CD_alpha", "CD_de", "CL_0", "CL_alpha", "CL_q", "CL_de",
    "Cm_alpha", "Cm_q", "Cm_de", "Cm_alphadot",
)
LONGITUDINAL_DEFAULT: tuple[str, ...] = (
    "CD_0", "CD_alpha", "CL_0", "CL_alpha", "CL_de", "Cm_alpha", "Cm_q", "Cm_de",
)
LONGITUDINAL_BIASES: tuple[str, ...] = (
    "bias_Vdot", "bias_alphadot", "bias_qdot", "bias_thetadot", "bias_az",
)

# plausible a priori values (light aircraft, per rad), used only as start values
LONGITUDINAL_TYPICAL: dict[str, float] = {
    "CL_alpha": 5.0, "CL_0": 0.4, "CD_0": 0.04, "CD_alpha": 0.2, "CL_de": 0.3,
    "Cm_alpha": -0.5, "Cm_q": -10.0, "Cm_de": -1.0,
}


def short_period(
    condition: ReferenceCondition,
    derivatives: Sequence[str] = SHORT_PERIOD_DEFAULT,
    start: Mapping[str, float] | None = None,
    biases: Sequence[str] = SHORT_PERIOD_BIASES,
) -> LinearModel:
    """Short-period model: states alpha (rad), q (rad/s); input de; outputs alpha, q, az.

    Morelli & Klein (2016) ch. 3 (short-period approximation) / SIDPAC ``lon``; lift in
    stability axes:
      alphadot = -qbar S/(m V) CL + q + bias_alphadot
      qdot     = qbar S cbar/Iyy Cm + bias_qdot
      az       = -qbar S/m CL + bias_az          (m/s^2, specific force, z down)
    CL = CL_alpha alpha + CL_q qhat + CL_de de, Cm = Cm_alpha alpha + Cm_q qhat + Cm_de de
    + Cm_alphadot alphadot cbar/2V (qhat = q cbar/2V). The gravity and trim terms are
    constant over a short maneuver and are absorbed by the biases.

    Parameters
    ----------
    condition : ReferenceCondition
        Reference condition, mass properties and geometry (SI).
    derivatives : sequence of str, optional
        Nondimensional derivatives to include (per rad), from ``SHORT_PERIOD_DERIVATIVES``;
        those not listed are absent (zero). Default ``SHORT_PERIOD_DEFAULT``.
    start : mapping of str to float or None, optional
        Start values overriding the typical ones (``LONGITUDINAL_TYPICAL``, 0 otherwise).
    biases : sequence of str, optional
        Bias parameters to include, from ``SHORT_PERIOD_BIASES`` (default all), SI units.

    Returns
    -------
    LinearModel
        The model 'short_period'.

    Raises
    ------
    ValueError
        An unknown or duplicate derivative or bias, or a start value for a non-parameter.
    """
    parameters, start_values = parameter_starts(
        "short_period", derivatives, SHORT_PERIOD_DERIVATIVES, biases, SHORT_PERIOD_BIASES,
        LONGITUDINAL_TYPICAL, start)
    c = condition
    k_z = c.qbar * c.area / (c.mass * c.V)
    k_az = c.qbar * c.area / c.mass
    k_m = c.qbar * c.area * c.chord / c.Iyy
    rate = c.chord / (2 * c.V)
    present = set(parameters)

    def build(v: Mapping[str, complex]) -> Matrices:
        def d(n: str) -> complex:
            return v[n] if n in present else 0.0

        dtype = complex if any(isinstance(x, complex) for x in v.values()) else float
        lift_x = np.array([d("CL_alpha"), d("CL_q") * rate], dtype=dtype)
        lift_u = np.array([d("CL_de")], dtype=dtype)
        A = np.zeros((2, 2), dtype=dtype)
        B = np.zeros((2, 2), dtype=dtype)
        A[0] = -k_z * lift_x + np.array([0.0, 1.0])
        B[0, 0] = -k_z * lift_u[0]
        B[0, 1] = d("bias_alphadot")
        # Cm_alphadot: alphadot is the first state equation, substituted (bilinear terms)
        mad = d("Cm_alphadot") * rate
        A[1] = k_m * (np.array([d("Cm_alpha"), d("Cm_q") * rate]) + mad * A[0])
        B[1, 0] = k_m * (d("Cm_de") + mad * B[0, 0])
        B[1, 1] = d("bias_qdot") + k_m * mad * B[0, 1]
        C = np.zeros((3, 2), dtype=dtype)
        D = np.zeros((3, 2), dtype=dtype)
        C[:2] = np.eye(2)
        C[2] = -k_az * lift_x
        D[2, 0] = -k_az * lift_u[0]
        D[2, 1] = d("bias_az")
        return A, B, C, D

    return LinearModel(
        name="short_period",
        states=("alpha", "q"),
        inputs=("de",),
        outputs=("alpha", "q", "az"),
        parameters=parameters,
        start=start_values,
        build=build,
        condition=condition,
        description="short-period perturbation model (alpha, q), Morelli & Klein ch. 6",
    )


def longitudinal(
    condition: ReferenceCondition,
    derivatives: Sequence[str] = LONGITUDINAL_DEFAULT,
    start: Mapping[str, float] | None = None,
    biases: Sequence[str] = LONGITUDINAL_BIASES,
    thrust_input: bool = False,
) -> LinearModel:
    """Full longitudinal model: states V (m/s), alpha (rad), q (rad/s), theta (rad); input de.

    Outputs V, alpha, q, theta, az (m/s^2). Stability-axis forces with the dynamic-pressure
    dependence of the trim coefficients CD_0, CL_0, the trim thrust T0 (N, along body x,
    ``condition.thrust``) turning with alpha, and the accelerometer's body-axis z force
    (Etkin & Reid 1996 ch. 4; Morelli & Klein 2016 ch. 3), linearised about alpha0:
      Vdot     = -qbar S/m (2 CD_0 dV/V + CD_alpha alpha + CD_de de) - T0 sin(alpha0)/m alpha
                 - g cos(gamma0)(theta - alpha)
      alphadot = -qbar S/(m V)(2 CL_0 dV/V + CL_alpha alpha + CL_q qhat + CL_de de)
                 - T0 cos(alpha0)/(m V) alpha + q - g sin(gamma0)/V (theta - alpha)
      qdot     = qbar S cbar/Iyy (Cm_alpha alpha + Cm_q qhat + Cm_de de
                                  + Cm_alphadot alphadot cbar/2V)
      thetadot = q
      az       = -qbar S/m (CL cos(alpha) + CD sin(alpha)) perturbed: the lift terms times
                 cos(alpha0), the drag terms times sin(alpha0), and the rotation of the
                 trim force (CD_0 cos(alpha0) - CL_0 sin(alpha0)) alpha
    plus biases, gamma0 = theta0 - alpha0. The thrust change with speed is absorbed in
    CD_0 as an effective speed damping, unless ``thrust_input``. CL_0 and CD_0 start at
    the trim force balance, (m g cos(gamma0) - T0 sin(alpha0)) / (qbar S) and
    (T0 cos(alpha0) - m g sin(gamma0)) / (qbar S). Without the thrust and az terms a slow,
    high-lift aircraft is misread: the Telemaster at 15 m/s (CL_0 0.93, T0/(qbar S) 0.13,
    noise-free JSBSim card at 100 Hz, V alpha q az fitted) gave CL_alpha +3.45 %, with them
    +0.49 %.

    Parameters
    ----------
    condition : ReferenceCondition
        Reference condition, mass properties, geometry and trim thrust (SI).
    derivatives : sequence of str, optional
        Nondimensional derivatives to include (per rad, CD_0 and CL_0 dimensionless), from
        ``LONGITUDINAL_DERIVATIVES``; those not listed are absent (zero). Default
        ``LONGITUDINAL_DEFAULT``.
    start : mapping of str to float or None, optional
        Start values overriding the typical ones (``LONGITUDINAL_TYPICAL``, the trim force
        balance for CL_0 and CD_0, 0 otherwise).
    biases : sequence of str, optional
        Bias parameters to include, from ``LONGITUDINAL_BIASES`` (default all), SI units.
    thrust_input : bool, optional
        If True, the record's ``thrust`` channel (N, along body x) is a second input:
        dT cos(alpha0)/m in Vdot and -dT sin(alpha0)/(m V) in alphadot (its constant part
        goes into the biases). Default False.

    Returns
    -------
    LinearModel
        The model 'longitudinal'.

    Raises
    ------
    ValueError
        An unknown or duplicate derivative or bias, or a start value for a non-parameter.
    """
    c = condition
    gamma0 = c.theta - c.alpha
    # trim force balance in stability axes, thrust along body x
    weight, qs = c.mass * c.g, c.qbar * c.area
    named = (*derivatives, *biases)
    trim = {}
    if "CL_0" in named:
        trim["CL_0"] = (weight * np.cos(gamma0) - c.thrust * np.sin(c.alpha)) / qs
    if "CD_0" in named:
        trim["CD_0"] = (c.thrust * np.cos(c.alpha) - weight * np.sin(gamma0)) / qs
    parameters, start_values = parameter_starts(
        "longitudinal", derivatives, LONGITUDINAL_DERIVATIVES, biases, LONGITUDINAL_BIASES,
        LONGITUDINAL_TYPICAL, start, trim)
    k_f = c.qbar * c.area / c.mass
    k_m = c.qbar * c.area * c.chord / c.Iyy
    rate = c.chord / (2 * c.V)
    present = set(parameters)
    gc, gs = c.g * np.cos(gamma0), c.g * np.sin(gamma0)
    ca, sa = np.cos(c.alpha), np.sin(c.alpha)
    thrust = c.thrust / c.mass  # m/s^2
    inputs = ("de", "thrust") if thrust_input else ("de",)

    def build(v: Mapping[str, complex]) -> Matrices:
        def d(n: str) -> complex:
            return v[n] if n in present else 0.0

        dtype = complex if any(isinstance(x, complex) for x in v.values()) else float
        # state order V, alpha, q, theta
        drag_x = np.array([2 * d("CD_0") / c.V, d("CD_alpha"), 0.0, 0.0], dtype=dtype)
        lift_x = np.array(
            [2 * d("CL_0") / c.V, d("CL_alpha"), d("CL_q") * rate, 0.0], dtype=dtype
        )
        A = np.zeros((4, 4), dtype=dtype)
        B = np.zeros((4, len(inputs) + 1), dtype=dtype)
        A[0] = -k_f * drag_x + np.array([0.0, gc - thrust * sa, 0.0, -gc])
        B[0, [0, -1]] = [-k_f * d("CD_de"), d("bias_Vdot")]
        A[1] = -k_f / c.V * lift_x + np.array(
            [0.0, (gs - thrust * ca) / c.V, 1.0, -gs / c.V])
        B[1, [0, -1]] = [-k_f / c.V * d("CL_de"), d("bias_alphadot")]
        if thrust_input:
            B[:2, 1] = [ca / c.mass, -sa / (c.mass * c.V)]
        mad = d("Cm_alphadot") * rate
        A[2] = k_m * (np.array([0.0, d("Cm_alpha"), d("Cm_q") * rate, 0.0]) + mad * A[1])
        B[2] = k_m * mad * B[1]
        B[2, [0, -1]] += [k_m * d("Cm_de"), d("bias_qdot")]
        A[3] = [0.0, 0.0, 1.0, 0.0]
        B[3, -1] = d("bias_thetadot")
        C = np.zeros((5, 4), dtype=dtype)
        D = np.zeros((5, len(inputs) + 1), dtype=dtype)
        C[:4] = np.eye(4)
        rotation = np.array([0.0, d("CD_0") * ca - d("CL_0") * sa, 0.0, 0.0], dtype=dtype)
        C[4] = -k_f * (lift_x * ca + drag_x * sa + rotation)
        D[4, [0, -1]] = [-k_f * (d("CL_de") * ca + d("CD_de") * sa), d("bias_az")]
        return A, B, C, D

    return LinearModel(
        name="longitudinal",
        states=("V", "alpha", "q", "theta"),
        inputs=inputs,
        outputs=("V", "alpha", "q", "theta", "az"),
        parameters=parameters,
        start=start_values,
        build=build,
        condition=condition,
        description="full longitudinal perturbation model (V, alpha, q, theta)",
    )
