"""The nonlinear six-degree-of-freedom model structure of ``methods.nonlinear_6dof``: which
force and moment coefficients depend on which variables (polynomial in the states and
controls, body or stability force axes), parameter names and typical magnitudes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from flightid.channels import CONTROL_SURFACES
from flightid.identification.models import rigid_body as rb
from flightid.record import Reference

FORCE_AXES = ("body", "stability")
# coefficient of each slot: x force, y force, z force, rolling, pitching, yawing moment
SLOTS = {"body": ("CX", "CY", "CZ", "Cl", "Cm", "Cn"),
         "stability": ("CD", "CY", "CL", "Cl", "Cm", "Cn")}
MOMENTS = ("Cl", "Cm", "Cn")
# regressor columns after the constant: derivative variable -> record channel (equation error)
VARIABLES = ("alpha", "beta", "p", "q", "r", "de", "da", "dr", "alphadot")
VARIABLE_CHANNEL = {"alpha": "alpha", "beta": "beta", "p": "phat", "q": "qhat", "r": "rhat",
                    "de": "de", "da": "da", "dr": "dr", "alphadot": "alphadot_hat"}
CONTROLS = CONTROL_SURFACES
LONGITUDINAL = ("alpha", "q", "de")
LATERAL = ("beta", "p", "r", "da", "dr")
PROPULSIVE_MOMENTS = ("L_prop", "M_prop", "N_prop")
OUTPUTS = ("V", "alpha", "beta", "p", "q", "r", "phi", "theta", "psi", "ax", "ay", "az")
ROTOR = "h_engine"
TORQUE = "L_engine"
INITIAL_STATES = ("measured", "estimate")
CONTROL_HOLDS = ("linear", "cubic", "zoh")
MODELS = {"6dof": "body", "6dof_stability": "stability"}
MOMENT_AXES = ("body", "stability")
# plausible light-aircraft values (per rad), used only when no equation-error start is asked
TYPICAL = {
    "CX_alpha": 0.2, "CZ_alpha": -4.5, "CZ_q": -4.0, "CZ_de": -0.4, "CZ_0": -0.4,
    "CD_alpha": 0.2, "CD_0": 0.04, "CL_alpha": 4.5, "CL_q": 4.0, "CL_de": 0.4, "CL_0": 0.4,
    "Cm_alpha": -0.7, "Cm_q": -10.0, "Cm_de": -1.0,
    "CY_beta": -0.5, "CY_dr": 0.15, "Cl_beta": -0.07, "Cl_p": -0.4, "Cl_r": 0.1,
    "Cl_da": -0.13, "Cn_beta": 0.07, "Cn_r": -0.12, "Cn_dr": -0.07,
}
COLUMNS = {v: j + 1 for j, v in enumerate(VARIABLES)}  # column 0 is the constant


def default_structure(force_axes: str = "body", alphadot: bool = False
                      ) -> dict[str, tuple[str, ...]]:
    """{coefficient: variables}: longitudinal ones on alpha, q, de, lateral on beta, p, r, da, dr.

    Parameters
    ----------
    force_axes : str, optional
        'body' (CX, CY, CZ; default) or 'stability' (CD, CY, CL) force coefficients.
    alphadot : bool, optional
        If True, the pitching moment also depends on alphadot (Cm_alphadot). Default False.

    Returns
    -------
    dict of str to tuple of str
        {coefficient: its variables} for the six force and moment coefficients.

    Raises
    ------
    ValueError
        ``force_axes`` is not in ``FORCE_AXES``.
    """
    if force_axes not in FORCE_AXES:
        raise ValueError(f"force_axes must be one of {', '.join(FORCE_AXES)}, got {force_axes!r}")
    x, y, z, roll, pitch, yaw = SLOTS[force_axes]
    return {x: LONGITUDINAL, y: LATERAL, z: LONGITUDINAL, roll: LATERAL,
            pitch: LONGITUDINAL + (("alphadot",) if alphadot else ()), yaw: LATERAL}


def parameter_name(coefficient: str, variable: str) -> str:
    """Canonical name of a term: parameter_name('Cm', 'q') == 'Cm_q', ('CL', '0') == 'CL_0'.

    Parameters
    ----------
    coefficient : str
        Coefficient name, e.g. 'Cm'.
    variable : str
        Variable name, or '0' for the constant term.

    Returns
    -------
    str
        '<coefficient>_<variable>'.
    """
    return f"{coefficient}_{variable}"


@dataclass
class SixDofModel:
    """The model structure: aerodynamic terms, mass properties, references, outputs.

    ``references`` maps each regressor variable to its reference value (rad for alpha, beta
    and controls, nondimensional for the rates). ``start`` holds the a priori value of every
    parameter (start of the iteration, and the value of a parameter not estimated).
    """

    structure: dict[str, tuple[str, ...]]
    force_axes: str
    mass: rb.MassProperties
    reference: Reference
    references: dict[str, float]
    outputs: tuple[str, ...] = OUTPUTS
    rotor_momentum: bool = False
    engine_torque: bool = False
    start: dict[str, float] = field(default_factory=dict)
    name: str = "6dof"
    moment_axes: str = "body"
    propulsive_moments: bool = False

    def __post_init__(self) -> None:
        check_structure(self.structure, self.force_axes)
        if self.moment_axes not in MOMENT_AXES:
            raise ValueError(f"moment_axes must be one of {', '.join(MOMENT_AXES)}, got "
                             f"{self.moment_axes!r}")
        bad = [o for o in self.outputs if o not in OUTPUTS]
        if bad:
            raise ValueError(f"unknown 6-DOF output(s) {', '.join(bad)}; known: "
                             f"{', '.join(OUTPUTS)}")
        missing = [v for v in self.variables if v not in self.references]
        if missing:
            raise ValueError(f"no reference value for {', '.join(missing)}")
        unknown = [k for k in self.start if k not in self.parameters]
        if unknown:
            raise ValueError(f"start values for unknown parameter(s) {', '.join(unknown)}; "
                             f"the model has {', '.join(self.parameters)}")
        self.start = {**{p: TYPICAL.get(p, 0.0) for p in self.parameters}, **self.start}

    @property
    def variables(self) -> tuple[str, ...]:
        """Regressor variables used by any coefficient, in VARIABLES order."""
        used = {v for terms in self.structure.values() for v in terms}
        return tuple(v for v in VARIABLES if v in used)

    @property
    def parameters(self) -> tuple[str, ...]:
        """Derivatives, then the biases C_0, then h_engine and L_engine (when modelled)."""
        derivs = [parameter_name(c, v) for c, terms in self.structure.items() for v in terms]
        biases = [parameter_name(c, "0") for c in self.structure]
        engine = [ROTOR] if self.rotor_momentum else []
        engine += [TORQUE] if self.engine_torque else []
        return tuple(derivs + biases + engine)

    def index(self) -> dict[str, tuple[int, int]]:
        """(slot, column) in the coefficient tensor of each aerodynamic parameter."""
        slots = SLOTS[self.force_axes]
        out = {}
        for coef, terms in self.structure.items():
            out[parameter_name(coef, "0")] = (slots.index(coef), 0)
            for v in terms:
                out[parameter_name(coef, v)] = (slots.index(coef), COLUMNS[v])
        return out


def check_structure(structure: Mapping[str, Sequence[str]], force_axes: str) -> None:
    """Check a coefficient structure against the force axes.

    Parameters
    ----------
    structure : Mapping of str to sequence of str
        {coefficient: the variables of its terms}.
    force_axes : str
        ``body`` or ``stability``.

    Raises
    ------
    ValueError
        Naming the force axes, coefficient or variable that is not allowed.
    """
    if force_axes not in FORCE_AXES:
        raise ValueError(f"force_axes must be one of {', '.join(FORCE_AXES)}, got {force_axes!r}")
    allowed = SLOTS[force_axes]
    for coef, terms in structure.items():
        if coef not in allowed:
            other = "stability" if force_axes == "body" else "body"
            hint = (f" ({coef} belongs to force_axes='{other}')" if coef in SLOTS[other] else "")
            raise ValueError(f"coefficient {coef!r} is not one of {', '.join(allowed)} for "
                             f"force_axes='{force_axes}'{hint}")
        bad = [t for t in terms if t not in VARIABLES]
        if bad:
            raise ValueError(f"{coef}: unknown variable(s) {', '.join(bad)}; use "
                             f"{', '.join(VARIABLES)}")
        if len(set(terms)) != len(terms):
            raise ValueError(f"{coef}: repeated variables in {list(terms)}")
        if "alphadot" in terms and coef not in MOMENTS:
            raise ValueError(f"{coef}: alphadot is allowed in moment coefficients only (in a "
                             "force it would make the equations of motion implicit)")


