"""Linear perturbation model structures parameterised by nondimensional derivatives.

The models of Morelli & Klein (2016) ch. 6 (example 6.1 and SIDPAC's ``lat``/``lon``
model files): continuous-time state space

    xdot = A(theta) x + B(theta) [u; 1],    y = C(theta) x + D(theta) [u; 1]

whose entries are built from nondimensional derivatives (``flightid.derivatives``), the
mass properties, geometry and reference condition (``models.reference_condition``). The
last input column is the constant 1, multiplied by the biases ``bias_<x>dot`` (state
equations) and ``bias_<y>`` (outputs), in SI units. States, inputs and outputs are the
*measured* channels (absolute, SI): the biases absorb the trim terms, so no trim value is
subtracted first, as in SIDPAC. A model is a plain description (names, start values, one
``build`` function of the parameter values using only arithmetic, so complex-step
differentiation of the matrices, ``matrix_sensitivities``, is exact to rounding).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from flightid.channels import LATERAL_INPUTS
from flightid.identification.models.reference_condition import (
    ReferenceCondition,
    condition_from_record,
    level_pitch_attitude,
)
from flightid.record import FlightRecord

Matrices = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass
class LinearModel:
    """A linear model structure: names, a priori values, and the matrix builder.

    ``build(values)`` returns continuous-time (A, B, C, D) with B and D having one column
    per input plus a last column for the constant 1 (bias parameters).
    ``start`` holds the a priori value of every parameter (start of the iteration, and
    the value a parameter is fixed at when it is not estimated or not identifiable).
    """

    name: str
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    parameters: tuple[str, ...]
    start: dict[str, float]
    build: Callable[[Mapping[str, complex]], Matrices]
    condition: ReferenceCondition | None = None
    description: str = ""
    state_channels: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        missing = [p for p in self.parameters if p not in self.start]
        if missing:
            raise ValueError(f"model {self.name}: no start value for {', '.join(missing)}")
        unknown = [p for p in self.start if p not in self.parameters]
        if unknown:
            raise ValueError(f"model {self.name}: start values for unknown {', '.join(unknown)}")
        if not self.state_channels:
            self.state_channels = {s: s for s in self.states}

    def values(self, **changes: float) -> dict[str, float]:
        """All parameter values: the start values with ``changes`` applied (names checked)."""
        unknown = [k for k in changes if k not in self.parameters]
        if unknown:
            raise KeyError(
                f"model {self.name} has no parameter {', '.join(unknown)}; it has "
                f"{', '.join(self.parameters)}"
            )
        return {**self.start, **changes}

    def matrices(self, values: Mapping[str, float] | None = None) -> Matrices:
        """Continuous-time (A, B, C, D) at ``values`` (default: the start values)."""
        return self.build(self.values() if values is None else {**self.start, **values})

    def with_start(self, **changes: float) -> LinearModel:
        """A copy whose start (a priori) values have ``changes`` applied."""
        return LinearModel(
            self.name, self.states, self.inputs, self.outputs, self.parameters,
            self.values(**changes), self.build, self.condition, self.description,
            dict(self.state_channels),
        )


def matrix_sensitivities(
    model: LinearModel, values: Mapping[str, float], names: Sequence[str]
) -> tuple[Matrices, tuple[np.ndarray, ...]]:
    """(A, B, C, D) and their derivatives with respect to ``names`` (stacked on axis 0).

    Complex step (Martins et al. 2003): d M / d p = Im M(p + i h) / h, exact to rounding
    for the arithmetic builders here.

    Parameters
    ----------
    model : LinearModel
        The linear model.
    values : mapping of str to float
        Parameter values (missing ones take the model's start values).
    names : sequence of str
        Parameters to differentiate with respect to (npar of them).

    Returns
    -------
    matrices : tuple of numpy.ndarray
        Continuous-time (A, B, C, D) at ``values``, real.
    sensitivities : tuple of numpy.ndarray
        (dA, dB, dC, dD), each of shape (npar, *matrix shape).
    """
    base = {k: complex(v) for k, v in {**model.start, **values}.items()}
    mats = [np.real(m).astype(float) for m in model.build(base)]
    h = 1e-30
    grads: list[list[np.ndarray]] = [[], [], [], []]
    for name in names:
        shifted = dict(base)
        shifted[name] = base[name] + 1j * h
        for slot, m in enumerate(model.build(shifted)):
            grads[slot].append(np.imag(np.asarray(m, dtype=complex)) / h)
    stacked = tuple(
        np.stack(g) if g else np.zeros((0, *mats[i].shape)) for i, g in enumerate(grads)
    )
    return tuple(mats), stacked  # type: ignore[return-value]


# --------------------------------------------------------------------------- lateral

LATERAL_DERIVATIVES: tuple[str, ...] = (
    "CY_beta", "CY_p", "CY_r", "CY_da", "CY_dr",
    "Cl_beta", "Cl_p", "Cl_r", "Cl_da", "Cl_dr",
    "Cn_beta", "Cn_p", "Cn_r", "Cn_da", "Cn_dr",
)
# the 13 derivatives of Morelli & Klein example 6.1 (Twin Otter, SIDPAC ``lat``)
LATERAL_EXAMPLE_6_1: tuple[str, ...] = (
    "CY_beta", "CY_r", "CY_dr",
    "Cl_beta", "Cl_p", "Cl_r", "Cl_da", "Cl_dr",
    "Cn_beta", "Cn_p", "Cn_r", "Cn_da", "Cn_dr",
)
LATERAL_BIASES: tuple[str, ...] = (
    "bias_betadot", "bias_pdot", "bias_rdot", "bias_phidot", "bias_ay",
)


def lateral(
    condition: ReferenceCondition,
    derivatives: Sequence[str] = LATERAL_EXAMPLE_6_1,
    start: Mapping[str, float] | None = None,
    biases: Sequence[str] = LATERAL_BIASES,
) -> LinearModel:
    """Lateral-directional perturbation model (Morelli & Klein 2016, example 6.1).

    States beta (rad), p, r (rad/s), phi (rad); inputs da, dr (rad); outputs beta, p, r,
    phi, ay (m/s^2). Body-axis rates, inertia coupling through Ixz:
      betadot = qbar S/(m V) CY + p sin(alpha0) - r cos(alpha0) + g cos(theta0)/V phi
      [pdot; rdot] = [[Ixx, -Ixz], [-Ixz, Izz]]^-1 qbar S b [Cl; Cn]
      phidot  = p + tan(theta0) r
      ay      = qbar S CY / m
    with CY, Cl, Cn linear in beta, phat = p b/2V, rhat = r b/2V, da, dr, plus biases.

    Parameters
    ----------
    condition : ReferenceCondition
        Reference condition, mass properties and geometry (SI).
    derivatives : sequence of str, optional
        Nondimensional derivatives to include (per rad), from ``LATERAL_DERIVATIVES``;
        those not listed are absent (zero). Default ``LATERAL_EXAMPLE_6_1``.
    start : mapping of str to float or None, optional
        Start values overriding the typical ones (``LATERAL_TYPICAL``, 0 otherwise).
    biases : sequence of str, optional
        Bias parameters to include, from ``LATERAL_BIASES`` (default all), SI units.

    Returns
    -------
    LinearModel
        The model 'lateral'.

    Raises
    ------
    ValueError
        An unknown or duplicate derivative or bias, or a start value for a non-parameter.
    """
    _check_names(derivatives, LATERAL_DERIVATIVES, "lateral")
    _check_names(biases, LATERAL_BIASES, "lateral")
    c = condition
    parameters = tuple(derivatives) + tuple(biases)
    start_values = {p: 0.0 for p in parameters}
    start_values.update(_typical_start(derivatives, LATERAL_TYPICAL))
    if start:
        start_values.update(_checked(start, parameters, "lateral"))
    gamma = c.Ixx * c.Izz - c.Ixz**2
    k_y = c.qbar * c.area / (c.mass * c.V)  # betadot per unit CY
    k_ay = c.qbar * c.area / c.mass  # ay per unit CY
    k_m = c.qbar * c.area * c.span  # moment per unit Cl or Cn
    rate = c.span / (2 * c.V)  # phat per p
    # inverse inertia rows (Etkin; Morelli & Klein eq. 3.37)
    c3, c4, c9 = c.Izz / gamma, c.Ixz / gamma, c.Ixx / gamma
    sa, ca = np.sin(c.alpha), np.cos(c.alpha)
    g_v = c.g * np.cos(c.theta) / c.V
    tt = np.tan(c.theta)
    present = set(parameters)

    def build(v: Mapping[str, complex]) -> Matrices:
        def d(n: str) -> complex:
            return v[n] if n in present else 0.0

        def row(coef: str) -> tuple[list[complex], list[complex]]:
            # d C<coef> / d [beta, p, r, phi] and / d [da, dr]
            xs = [d(f"C{coef}_beta"), d(f"C{coef}_p") * rate, d(f"C{coef}_r") * rate, 0.0]
            us = [d(f"C{coef}_da"), d(f"C{coef}_dr")]
            return xs, us

        yx, yu = row("Y")
        lx, lu = row("l")
        nx, nu = row("n")
        dtype = complex if any(isinstance(x, complex) for x in v.values()) else float
        A = np.zeros((4, 4), dtype=dtype)
        B = np.zeros((4, 3), dtype=dtype)
        C = np.zeros((5, 4), dtype=dtype)
        D = np.zeros((5, 3), dtype=dtype)
        A[0] = np.array(yx) * k_y + np.array([0.0, sa, -ca, g_v])
        B[0, :2] = np.array(yu) * k_y
        for j in range(4):
            A[1, j] = k_m * (c3 * lx[j] + c4 * nx[j])
            A[2, j] = k_m * (c4 * lx[j] + c9 * nx[j])
        for j in range(2):
            B[1, j] = k_m * (c3 * lu[j] + c4 * nu[j])
            B[2, j] = k_m * (c4 * lu[j] + c9 * nu[j])
        A[3] = [0.0, 1.0, tt, 0.0]
        B[:, 2] = [d("bias_betadot"), d("bias_pdot"), d("bias_rdot"), d("bias_phidot")]
        C[:4, :4] = np.eye(4)
        C[4] = np.array(yx) * k_ay
        D[4, :2] = np.array(yu) * k_ay
        D[4, 2] = d("bias_ay")
        return A, B, C, D

    return LinearModel(
        name="lateral",
        states=("beta", "p", "r", "phi"),
        inputs=LATERAL_INPUTS,
        outputs=("beta", "p", "r", "phi", "ay"),
        parameters=parameters,
        start=start_values,
        build=build,
        condition=condition,
        description="lateral-directional perturbation model, Morelli & Klein example 6.1",
    )


# --------------------------------------------------------------------------- longitudinal

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
# the rate derivatives a preset leaves out, which the identification methods estimate
# unless the record holds them a priori (``a_priori``): left at zero they are not absent
# from the aircraft but folded into the others. On the Navion (Cm_alphadot -4.36, Teper
# 1969) output error without it put Cm_q at -14.5 for a truth of -9.96 (52 sigma) on
# navion-doublets; on the Twin Otter (CZ_q -20, NASA TM-4099) without CL_q it put CL_de
# 74 % low (6 sigma) on twinotter-21-elevator. Estimated, they come with bounds that
# carry their correlation with Cm_q and CL_alpha (Morelli & Klein 2016 sec. 6.3). Not in
# the short-period model: its alphadot is a combination of its states and input, so
# Cm_alphadot cannot be told from Cm_alpha and Cm_q (twinotter-21-elevator seed 2:
# Cm_alpha withheld as unidentifiable when Cm_alphadot was free).
RATE_DERIVATIVES: dict[str, tuple[str, ...]] = {
    "longitudinal": ("CL_q", "Cm_alphadot"),
}

# plausible a priori values (light aircraft, per rad), used only as start values
LATERAL_TYPICAL: dict[str, float] = {
    "CY_beta": -0.5, "Cl_beta": -0.05, "Cl_p": -0.4, "Cl_r": 0.1, "Cl_da": -0.1,
    "Cn_beta": 0.05, "Cn_r": -0.1, "Cn_dr": -0.05,
}
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
    _check_names(derivatives, SHORT_PERIOD_DERIVATIVES, "short_period")
    _check_names(biases, SHORT_PERIOD_BIASES, "short_period")
    c = condition
    parameters = tuple(derivatives) + tuple(biases)
    start_values = {p: 0.0 for p in parameters}
    start_values.update(_typical_start(derivatives, LONGITUDINAL_TYPICAL))
    if start:
        start_values.update(_checked(start, parameters, "short_period"))
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
    _check_names(derivatives, LONGITUDINAL_DERIVATIVES, "longitudinal")
    _check_names(biases, LONGITUDINAL_BIASES, "longitudinal")
    c = condition
    parameters = tuple(derivatives) + tuple(biases)
    start_values = {p: 0.0 for p in parameters}
    start_values.update(_typical_start(derivatives, LONGITUDINAL_TYPICAL))
    gamma0 = c.theta - c.alpha
    # trim force balance in stability axes, thrust along body x
    weight, qs = c.mass * c.g, c.qbar * c.area
    if "CL_0" in parameters:
        start_values["CL_0"] = (weight * np.cos(gamma0) - c.thrust * np.sin(c.alpha)) / qs
    if "CD_0" in parameters:
        start_values["CD_0"] = (c.thrust * np.cos(c.alpha) - weight * np.sin(gamma0)) / qs
    if start:
        start_values.update(_checked(start, parameters, "longitudinal"))
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


MODELS: dict[str, Callable[..., LinearModel]] = {
    "lateral": lateral,
    "short_period": short_period,
    "longitudinal": longitudinal,
}


def preset_for_record(preset: str, record: FlightRecord, derivatives: Sequence[str] | None,
                      method: str) -> LinearModel:
    """The named preset at the record's condition, with ``derivatives`` if given.

    Parameters
    ----------
    preset : str
        'lateral', 'short_period' or 'longitudinal'.
    record : FlightRecord
        The flight, SI channels; gives the reference condition.
    derivatives : sequence of str or None
        Derivatives to include; None or empty takes the preset's default.
    method : str
        Name of the method asking, named in the error.

    Returns
    -------
    LinearModel
        The preset at the record's condition.

    Raises
    ------
    ValueError
        ``preset`` is not a preset.
    """
    if preset not in MODELS:
        raise ValueError(f"{method} needs a model preset ({', '.join(MODELS)}), got {preset!r}")
    structure = {"derivatives": tuple(derivatives)} if derivatives else {}
    return model_for_record(preset, record, **structure)


def model_for_record(kind: str, record: FlightRecord, **kwargs) -> LinearModel:
    """Model ``kind`` ('lateral', 'short_period', 'longitudinal') at the record's condition.

    A record without a pitch attitude channel (a hobby recorder) takes the reference pitch
    attitude from the mean specific force, theta0 = atan2(ax, -az) (unaccelerated flight;
    ``level_pitch_attitude``).

    Parameters
    ----------
    kind : str
        Model name, a key of ``MODELS``.
    record : FlightRecord
        The flight, SI channels.
    **kwargs
        Passed to the model builder (``derivatives``, ``start``, ``biases``, ...).

    Returns
    -------
    LinearModel
        The model at the record's reference condition.

    Raises
    ------
    ValueError
        ``kind`` is not a known model.
    """
    if kind not in MODELS:
        raise ValueError(f"unknown model {kind!r}; known: {', '.join(MODELS)}")
    override = {}
    if "theta" not in record:
        override["theta"] = level_pitch_attitude(record)
    return MODELS[kind](condition_from_record(record, **override), **kwargs)


def without_outputs(model: LinearModel, drop: Sequence[str]) -> LinearModel:
    """``model`` with the outputs in ``drop`` removed (rows of C and D).

    The states stay, so an unmeasured attitude is still integrated from the rates.

    Parameters
    ----------
    model : LinearModel
        The linear model.
    drop : sequence of str
        Output names to remove; names not among the outputs are ignored.

    Returns
    -------
    LinearModel
        A copy with the remaining outputs, same states, inputs and parameters.
    """
    keep = [i for i, o in enumerate(model.outputs) if o not in drop]

    def build(values: Mapping[str, complex]) -> Matrices:
        A, B, C, D = model.build(values)
        return A, B, C[keep], D[keep]

    return LinearModel(model.name, model.states, model.inputs,
                       tuple(model.outputs[i] for i in keep), model.parameters,
                       dict(model.start), build, model.condition, model.description,
                       dict(model.state_channels))


def _check_names(names: Sequence[str], allowed: Sequence[str], model: str) -> None:
    bad = [n for n in names if n not in allowed]
    if bad:
        raise ValueError(
            f"{model} model has no parameter {', '.join(bad)}; allowed: {', '.join(allowed)}"
        )
    if len(set(names)) != len(names):
        raise ValueError(f"{model} model: duplicate parameter names in {list(names)}")


def _checked(values: Mapping[str, float], parameters: Sequence[str], model: str) -> dict:
    bad = [n for n in values if n not in parameters]
    if bad:
        raise ValueError(
            f"{model} model: start value for {', '.join(bad)}, which is not a parameter "
            f"({', '.join(parameters)})"
        )
    return {k: float(v) for k, v in values.items()}


def _typical_start(derivatives: Sequence[str], typical: Mapping[str, float]) -> dict:
    return {n: typical[n] for n in derivatives if n in typical}
