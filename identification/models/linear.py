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
)

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
    parameters, start_values = parameter_starts(
        "lateral", derivatives, LATERAL_DERIVATIVES, biases, LATERAL_BIASES, LATERAL_TYPICAL,
        start)
    c = condition
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


# plausible a priori values (light aircraft, per rad), used only as start values
LATERAL_TYPICAL: dict[str, float] = {
    "CY_beta": -0.5, "Cl_beta": -0.05, "Cl_p": -0.4, "Cl_r": 0.1, "Cl_da": -0.1,
    "Cn_beta": 0.05, "Cn_r": -0.1, "Cn_dr": -0.05,
}


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


def parameter_starts(model: str, derivatives: Sequence[str], allowed: Sequence[str],
                     biases: Sequence[str], allowed_biases: Sequence[str],
                     typical: Mapping[str, float], start: Mapping[str, float] | None = None,
                     trim: Mapping[str, float] | None = None,
                     ) -> tuple[tuple[str, ...], dict[str, float]]:
    """A linear model's parameters and their start values, the names checked.

    Each parameter starts at 0, then at its typical value, then at its trim value, then at
    the caller's start value (each later one overriding the earlier).

    Parameters
    ----------
    model : str
        The model's name, for the error messages.
    derivatives : sequence of str
        The nondimensional derivatives estimated (per rad).
    allowed : sequence of str
        The derivatives the model has.
    biases : sequence of str
        The bias parameters estimated (SI units).
    allowed_biases : sequence of str
        The biases the model has.
    typical : mapping of str to float
        Typical start values of derivatives (per rad).
    start : mapping of str to float or None, optional
        The caller's start values; every name must be a parameter.
    trim : mapping of str to float or None, optional
        Start values from the trim (only those naming a parameter are used).

    Returns
    -------
    parameters : tuple of str
        The derivatives, then the biases.
    start_values : dict of str to float
        Start value per parameter, in the order of ``parameters``.

    Raises
    ------
    ValueError
        An unknown or duplicate derivative or bias, or a start value for a non-parameter.
    """
    _check_names(derivatives, allowed, model)
    _check_names(biases, allowed_biases, model)
    parameters = tuple(derivatives) + tuple(biases)
    start_values = {p: 0.0 for p in parameters}
    start_values.update(_typical_start(derivatives, typical))
    start_values.update({k: v for k, v in (trim or {}).items() if k in parameters})
    if start:
        start_values.update(_checked(start, parameters, model))
    return parameters, start_values


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
