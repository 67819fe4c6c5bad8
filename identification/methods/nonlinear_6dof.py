"""Output error on the nonlinear 6-DOF rigid-body equations with a linear aerodynamic model.

Morelli & Klein (2016) sec. 6.4 (nonlinear dynamic models) and Jategaonkar (2015)
ch. 4: the measured outputs V, alpha, beta, p, q, r, phi, theta, psi, ax, ay, az are
matched by the flat-earth body-axis equations of ``rigid_body``, driven by the measured
controls de, da, dr, the measured thrust (N, along body x) and air density, with the
aerodynamic coefficients linear in the perturbations from a reference:

    C = C_0 + C_alpha (alpha - alpha_ref) + C_beta (beta - beta_ref) + C_p (phat - phat_ref)
          + C_q (qhat - qhat_ref) + C_r (rhat - rhat_ref) + C_de (de - de_ref) + ...

for C in CX CY CZ Cl Cm Cn (body axes, ``force_axes="body"``) or CD CY CL Cl Cm Cn (lift and
drag in the local stability axes, ``force_axes="stability"``: CX = CL sin(alpha) - CD
cos(alpha), CZ = -CL cos(alpha) - CD sin(alpha)). Rates are nondimensional, phat = p b/2V,
qhat = q cbar/2V, rhat = r b/2V, computed from the model's own states; the references are
the record means, as in equation error, so the biases C_0 are the coefficients at the mean
condition and the equation-error start values carry over unchanged. With
``moment_axes="stability"`` the rolling and yawing moments are those of the stability axes
(Cl_s, Cn_s), with the stability-axis rates phat = (p cos(alpha) + r sin(alpha)) b/2V and
rhat = (r cos(alpha) - p sin(alpha)) b/2V in every coefficient, rotated to the body axes at
the instantaneous alpha: Cl = Cl_s cos(alpha) - Cn_s sin(alpha), Cn = Cl_s sin(alpha) + Cn_s
cos(alpha) (Morelli & Klein 2016 ch. 3; the stability-axis convention of most lateral data
sets); a body-axis model of such an aircraft misses the products of the alpha perturbation
with the lateral terms. Moment coefficients may carry an alphadot term (alphadot cbar/2V,
alphadot from the translational equations at the same instant). ``rotor_momentum`` adds the
angular momentum of the engine rotor ``h_engine`` (N m s), whose gyroscopic moment is
otherwise read as aerodynamics; ``engine_torque`` a constant engine rolling moment
``L_engine`` (N m), which a coefficient bias would wrongly scale with dynamic pressure;
``propulsive_moments`` takes the record's propulsive moments L_prop, M_prop, N_prop (N m
about the CG, from the engine model, as the thrust is) as known inputs, so that a twin's
differential thrust in yaw (each propeller sees u - r y) is not read as aerodynamic damping
(it replaces h_engine and L_engine). The mass is the record's time history (fuel burn),
gravity the local effective one (``rigid_body.local_gravity``).

Integration: classical RK4 at the record rate; the inputs at the half steps come from the
4-point cubic interpolant of the samples (``controls="linear"`` takes the mean of the two
neighbours, ``"zoh"`` holds the earlier one). Recorded signals are band-limited by the anti-
alias filters, and a linear midpoint of a smooth signal is off by its curvature: on a 50 Hz
Twin Otter record behind a 10 Hz 4-pole filter, linear midpoints bias Cl_p, Cl_da and
Cl_beta by -0.85 %, cubic ones by -0.03 % (noise-free). Output sensitivities: complex step
(Martins et al. 2003) in parallel columns, one integration carrying every parameter
perturbation as a batch: dy/dtheta_k = Im y(theta + i h e_k) / h, exact to rounding for
these analytic equations, so the Gauss-Newton steps are those of the exact information
matrix. The optimiser, bounds and refit loop are those of the shared engine
(``identification.engine``), as in output error: ``gauss_newton.maximum_likelihood``
(Newton-Raphson with R concentrated out, Levenberg-Marquardt safeguard, R re-estimated
every iteration); Cramer-Rao bounds sqrt(diag M^-1) (M&K eq. 6.50), optionally corrected
for colored residuals (M&K eq. 6.54, ``bounds``); identifiability as in output error
(unexcited controls, zero sensitivity, collinearity of the normalised information matrix)
with ``refit.refit_without_unidentifiable``; start values from equation error.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from flightid.identification.data.coefficients import mass_properties
from flightid.identification.engine import identifiability as ident
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit, maximum_likelihood
from flightid.identification.engine.refit import refit_iterated
from flightid.identification.engine.results import estimate_from_fit
from flightid.identification.estimate import Estimate
from flightid.identification.methods import equation_error
from flightid.identification.methods.equation_error import channel_values
from flightid.identification.methods.protocol import Method, OutputErrorOptions, option
from flightid.identification.models import rigid_body as rb
from flightid.record import FlightRecord, Reference
from flightid.units import G0

ID = "oe6dof"
FORCE_AXES = ("body", "stability")
# coefficient of each slot: x force, y force, z force, rolling, pitching, yawing moment
SLOTS = {"body": ("CX", "CY", "CZ", "Cl", "Cm", "Cn"),
         "stability": ("CD", "CY", "CL", "Cl", "Cm", "Cn")}
MOMENTS = ("Cl", "Cm", "Cn")
# regressor columns after the constant: derivative variable -> record channel (equation error)
VARIABLES = ("alpha", "beta", "p", "q", "r", "de", "da", "dr", "alphadot")
VARIABLE_CHANNEL = {"alpha": "alpha", "beta": "beta", "p": "phat", "q": "qhat", "r": "rhat",
                    "de": "de", "da": "da", "dr": "dr", "alphadot": "alphadot_hat"}
CONTROLS = ("de", "da", "dr")
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
_COLUMNS = {v: j + 1 for j, v in enumerate(VARIABLES)}  # column 0 is the constant


def default_structure(force_axes: str = "body", alphadot: bool = False
                      ) -> dict[str, tuple[str, ...]]:
    """{coefficient: variables}: longitudinal ones on alpha, q, de, lateral on beta, p, r, da, dr.

    ``alphadot`` adds Cm_alphadot.
    """
    if force_axes not in FORCE_AXES:
        raise ValueError(f"force_axes must be one of {', '.join(FORCE_AXES)}, got {force_axes!r}")
    x, y, z, roll, pitch, yaw = SLOTS[force_axes]
    return {x: LONGITUDINAL, y: LATERAL, z: LONGITUDINAL, roll: LATERAL,
            pitch: LONGITUDINAL + (("alphadot",) if alphadot else ()), yaw: LATERAL}


def parameter_name(coefficient: str, variable: str) -> str:
    """Canonical name of a term: parameter_name('Cm', 'q') == 'Cm_q', ('CL', '0') == 'CL_0'."""
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
        _check_structure(self.structure, self.force_axes)
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
                out[parameter_name(coef, v)] = (slots.index(coef), _COLUMNS[v])
        return out


def _check_structure(structure: Mapping[str, Sequence[str]], force_axes: str) -> None:
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


# ------------------------------------------------------------------ record -> problem


@dataclass
class Problem:
    """Data and model of one fit, arranged for fast integration."""

    model: SixDofModel
    time: np.ndarray
    dt: float
    # inputs (de - de_ref, da - da_ref, dr - dr_ref, thrust N, rho kg/m^3, mass kg,
    # L_prop, M_prop, N_prop N m (0 unless the model takes them)), (N, 9)
    inputs: np.ndarray
    # the same at the RK4 stage instants t_i, t_i + dt/2, t_i+1: (3, N - 1, 9)
    stage_inputs: np.ndarray
    z: np.ndarray  # (N, ny) measured outputs
    x0: np.ndarray  # (9,) measured initial state
    x0_names: tuple[str, ...]
    fixed: dict[str, float]
    noise_floor: np.ndarray
    controls: str

    @property
    def output_names(self) -> tuple[str, ...]:
        """The measured outputs, in the columns of ``z``."""
        return tuple(self.model.outputs)


def model_from_record(
    record: FlightRecord,
    structure: Mapping[str, Sequence[str]] | None = None,
    *,
    force_axes: str | None = None,
    alphadot: bool = False,
    outputs: Sequence[str] | None = None,
    rotor_momentum: bool = False,
    engine_torque: bool = False,
    start: Mapping[str, float] | None = None,
    gravity: float | None = None,
    moment_axes: str = "body",
    propulsive_moments: bool = False,
) -> SixDofModel:
    """The 6-DOF model at a record's mass properties, geometry and mean references.

    ``structure`` {coefficient: variables} defaults to ``default_structure(force_axes,
    alphadot)``; ``force_axes`` is inferred from the structure when not given. Outputs
    default to those of OUTPUTS the record has. ``rotor_momentum`` adds h_engine (N m s),
    ``engine_torque`` L_engine (N m, constant rolling moment of the engine). Gravity
    (m/s^2) defaults to the local effective gravity at the record's mean latitude and
    altitude (``rigid_body.local_gravity``), else G0. ``moment_axes`` "stability" makes Cl
    and Cn stability-axis coefficients on stability-axis rates (see the module docstring).
    ``propulsive_moments`` drives the model with the record's L_prop, M_prop, N_prop (N m).
    """
    if structure is None:
        structure = default_structure(force_axes or "body", alphadot)
    structure = {c: tuple(t) for c, t in structure.items()}
    if force_axes is None:
        force_axes = "stability" if {"CL", "CD"} & set(structure) else "body"
    _check_structure(structure, force_axes)
    if record.meta.reference is None:
        raise ValueError("record has no meta.reference (area, span, chord): the 6-DOF model "
                         "needs the reference geometry")
    mp = {k: float(np.mean(v)) for k, v in mass_properties(record).items()}
    if gravity is None:
        gravity = (rb.local_gravity(float(np.mean(record["latitude"])),
                                    float(np.mean(record["h"])) if "h" in record else 0.0)
                   if "latitude" in record else G0)
    mass = rb.MassProperties(mp["mass"], mp["Ixx"], mp["Iyy"], mp["Izz"], mp["Ixz"], gravity)
    used = {v for t in structure.values() for v in t}
    references = {v: float(np.mean(channel_values(record, VARIABLE_CHANNEL[v])))
                  for v in VARIABLES if v in used}
    if outputs is None:
        outputs = tuple(o for o in OUTPUTS if o in record)
    return SixDofModel(structure, force_axes, mass, record.meta.reference, references,
                       tuple(outputs), rotor_momentum, engine_torque, dict(start or {}),
                       moment_axes=moment_axes, propulsive_moments=propulsive_moments)


def _density(record: FlightRecord) -> np.ndarray:
    if "rho" in record:
        return record["rho"]
    if "qbar" in record and "V" in record:
        return 2.0 * record["qbar"] / record["V"] ** 2
    raise ValueError("record has neither 'rho' nor 'qbar' and 'V': the 6-DOF model needs the "
                     "air density (kg/m^3)")


def measured_state(record: FlightRecord, index: int = 0) -> np.ndarray:
    """The state (u, v, w, p, q, r, phi, theta, psi) of sample ``index`` in SI units.

    u, v, w from their channels, else from V, alpha and beta; psi 0 when absent.
    """
    if all(c in record for c in ("u", "v", "w")):
        uvw = [record[c][index] for c in ("u", "v", "w")]
    else:
        missing = [c for c in ("V", "alpha", "beta") if c not in record]
        if missing:
            raise ValueError(f"record lacks {', '.join(missing)} (and u, v, w) for the initial "
                             "state of the 6-DOF model")
        uvw = rb.state_from_air_data(record["V"][index], record["alpha"][index],
                                     record["beta"][index])
    rest = []
    for c in ("p", "q", "r", "phi", "theta", "psi"):
        if c in record:
            rest.append(record[c][index])
        elif c == "psi":
            rest.append(0.0)
        else:
            raise ValueError(f"record lacks channel {c!r} for the initial state of the 6-DOF model")
    return np.array([*uvw, *rest], dtype=float)


def problem_from_record(record: FlightRecord, model: SixDofModel,
                        initial_state: str = "measured", controls: str = "cubic") -> Problem:
    """Arrange a record's inputs and outputs for ``model`` (checks channels and sampling)."""
    if initial_state not in INITIAL_STATES:
        raise ValueError(f"initial_state must be one of {', '.join(INITIAL_STATES)}, got "
                         f"{initial_state!r}")
    if controls not in CONTROL_HOLDS:
        raise ValueError(f"controls must be one of {', '.join(CONTROL_HOLDS)}, got {controls!r}")
    time = record.time
    if time.size < 10:
        raise ValueError(f"record has {time.size} samples; output error needs at least 10")
    steps = np.diff(time)
    dt = float(np.mean(steps))
    if np.max(np.abs(steps - dt)) > 1e-6 * dt + 1e-9:
        i = int(np.argmax(np.abs(steps - dt)))
        raise ValueError(f"record is not uniformly sampled (step {steps[i]:.6g} s at sample {i}, "
                         f"mean {dt:.6g} s); resample it before output error")
    missing = [o for o in model.outputs if o not in record]
    if "thrust" not in record:
        missing.append("thrust")
    if model.propulsive_moments:
        missing += [c for c in PROPULSIVE_MOMENTS if c not in record]
    missing += [c for c in CONTROLS if c in model.variables and c not in record]
    if missing:
        raise ValueError(f"record lacks channel(s) {', '.join(missing)} needed by the 6-DOF model")
    n = time.size
    ctrl = [record[c] - model.references[c] if c in model.variables else np.zeros(n)
            for c in CONTROLS]
    moments = [record[c] if model.propulsive_moments else np.zeros(n)
               for c in PROPULSIVE_MOMENTS]
    inputs = np.column_stack([*ctrl, record["thrust"], _density(record),
                              mass_properties(record)["mass"], *moments])
    z = np.column_stack([np.unwrap(record[o]) if o == "psi" else record[o]
                         for o in model.outputs])
    bad = [c for c, col in zip((*CONTROLS, "thrust", "rho", "mass", *PROPULSIVE_MOMENTS,
                                *model.outputs),
                               np.hstack([inputs, z]).T, strict=True)
           if not np.all(np.isfinite(col))]
    if bad:
        raise ValueError(f"channel(s) {', '.join(bad)} contain NaN or inf values")
    if np.any(inputs[:, 4] <= 0):
        i = int(np.argmax(inputs[:, 4] <= 0))
        raise ValueError(f"air density is not positive at sample {i} (t = {time[i]} s)")
    mid = _cubic_midpoints(inputs) if controls == "cubic" else 0.5 * (inputs[:-1] + inputs[1:])
    start, end = inputs[:-1], inputs[1:].copy()
    if controls == "zoh":
        mid[:, :3] = start[:, :3]
        end[:, :3] = start[:, :3]
    x0 = measured_state(record)
    names = [s for s in rb.STATES if s != "psi" or "psi" in model.outputs]
    x0_names = tuple(f"x0_{s}" for s in names) if initial_state == "estimate" else ()
    floor = (1e-10 * np.maximum(np.ptp(z, axis=0), np.abs(z).max(axis=0)) + 1e-300) ** 2
    return Problem(model, time, dt, inputs, np.stack([start, mid, end]), z, x0, x0_names, {},
                   floor, controls)


def _cubic_midpoints(x: np.ndarray) -> np.ndarray:
    """Values halfway between samples (rows) by the 4-point cubic (Lagrange) interpolant.

    (-x[i-1] + 9 x[i] + 9 x[i+1] - x[i+2]) / 16; the end intervals use the linear mean.
    """
    mid = 0.5 * (x[:-1] + x[1:])
    if x.shape[0] >= 4:
        mid[1:-1] = (9.0 * (x[1:-2] + x[2:-1]) - x[:-3] - x[3:]) / 16.0
    return mid


# ------------------------------------------------------------------ simulation


def _aero(model: SixDofModel, x, controls: tuple, thrust, rho, combine, xp=np) -> tuple:
    """Aerodynamic state of states x[9, ...] (an array, or Python floats with xp=SCALAR).

    ``controls`` are (de, da, dr) minus their references (rad), thrust (N) and rho
    (kg/m^3), broadcast against x[0]; ``combine(rows)`` maps the regressor rows (alpha,
    beta, phat, qhat, rhat, de, da, dr as perturbations) to the six coefficients, without
    the alphadot terms. Returns body forces fx, fy, fz (N, thrust included), the
    coefficients, qbar S (N), V (m/s), alpha and beta (rad), and 1/(2V) (s/m).
    """
    ref, refs = model.reference, model.references
    u, v, w = x[0], x[1], x[2]
    uw2 = u * u + w * w
    speed2 = uw2 + v * v
    speed = xp.sqrt(speed2)
    alpha = xp.arctan(w / u)
    beta = xp.arcsin(v / speed)
    inv2v = 0.5 / speed
    uw = xp.sqrt(uw2)
    ca, sa = u / uw, w / uw  # cos(alpha), sin(alpha)
    p, r = x[3], x[5]
    stability_moments = model.moment_axes == "stability"
    if stability_moments:
        p, r = p * ca + r * sa, r * ca - p * sa
    coef = combine((alpha - refs.get("alpha", 0.0), beta - refs.get("beta", 0.0),
                    p * (ref.span * inv2v) - refs.get("p", 0.0),
                    x[4] * (ref.chord * inv2v) - refs.get("q", 0.0),
                    r * (ref.span * inv2v) - refs.get("r", 0.0), *controls))
    if stability_moments:
        cl, cn = coef[3], coef[5]
        coef = (coef[0], coef[1], coef[2], cl * ca - cn * sa, coef[4], cl * sa + cn * ca)
    qs = (0.5 * ref.area) * rho * speed2
    if model.force_axes == "body":
        cx, cz = coef[0], coef[2]
    else:
        # lift and drag in the local stability axes (rotation by alpha)
        cx = coef[2] * sa - coef[0] * ca
        cz = -coef[2] * ca - coef[0] * sa
    return qs * cx + thrust, qs * coef[1], qs * cz, coef, qs, speed, alpha, beta, inv2v


def _batch_combination(model: SixDofModel, theta: np.ndarray, shape: tuple[int, ...]):
    """combine(rows) for arrays: one einsum of theta (6, 10, K) with the regressors."""
    reg = np.empty((1 + len(VARIABLES), *shape), dtype=theta.dtype)
    reg[0] = 1.0
    reg[9] = -model.references.get("alphadot", 0.0)

    def combine(rows: tuple) -> np.ndarray:
        for j, row in enumerate(rows, start=1):
            reg[j] = row
        return np.einsum("jrk,r...k->j...k", theta, reg)

    return combine


def _scalar_combination(model: SixDofModel, theta: np.ndarray):
    """combine(rows) for Python floats: sums over the nonzero terms of theta (6, 10, 1)."""
    t = theta[..., 0].tolist()
    adot_ref = model.references.get("alphadot", 0.0)
    const = [t[j][0] - t[j][9] * adot_ref for j in range(6)]
    terms = [[(c - 1, t[j][c]) for c in range(1, 9) if t[j][c] != 0.0] for j in range(6)]

    def combine(rows: tuple) -> list[float]:
        out = []
        for j in range(6):
            value = const[j]
            for c, k in terms[j]:
                value += k * rows[c]
            out.append(value)
        return out

    return combine


def _integrate(problem: Problem, theta: np.ndarray, engine: np.ndarray, x0: np.ndarray
               ) -> np.ndarray:
    """States (N, 9, K) for a batch of K coefficient tensors theta (6, 10, K).

    engine (2, K): rotor angular momentum (N m s) and engine rolling moment (N m); x0 (9, K).
    One real trajectory (K = 1) runs on Python floats, a batch on numpy arrays.
    """
    model = problem.model
    ref, mp = model.reference, model.mass
    stages = problem.stage_inputs.tolist()
    has_adot = "alphadot" in model.variables
    scalar = x0.shape[1] == 1 and not np.iscomplexobj(theta)
    if scalar:
        xp, combine = rb.SCALAR, _scalar_combination(model, theta)
        adot = theta[3:, _COLUMNS["alphadot"], 0].tolist()
        rotor, torque = engine[:, 0].tolist()
        x0 = x0[:, 0]
    else:
        xp, combine = np, _batch_combination(model, theta, x0.shape[1:])
        adot = theta[3:, _COLUMNS["alphadot"]]  # (3, K): Cl, Cm, Cn per alphadot_hat
        rotor, torque = engine
    span, chord = ref.span, ref.chord

    def rhs(state: np.ndarray, i: int, stage: int) -> np.ndarray:
        x = state.tolist() if scalar else state
        de, da, dr, thrust, rho, mass, l_prop, m_prop, n_prop = stages[stage][i]
        fx, fy, fz, coef, qs, _, _, _, inv2v = _aero(model, x, (de, da, dr), thrust, rho,
                                                    combine, xp)
        trig = rb.euler_trig(x, xp)
        udot, vdot, wdot = rb.translational(x, fx / mass, fy / mass, fz / mass, mp.g, trig)
        cl, cm, cn = coef[3], coef[4], coef[5]
        if has_adot:
            u, w = x[0], x[2]
            adot_hat = (u * wdot - w * udot) / (u * u + w * w) * (chord * inv2v)
            cl, cm, cn = cl + adot[0] * adot_hat, cm + adot[1] * adot_hat, cn + adot[2] * adot_hat
        pdot, qdot, rdot = rb.rotational(x, qs * span * cl + torque + l_prop,
                                         qs * chord * cm + m_prop, qs * span * cn + n_prop,
                                         mp, rotor)
        out = (udot, vdot, wdot, pdot, qdot, rdot, *rb.kinematic(x, trig))
        return np.array(out) if scalar else np.stack(out)

    states = rb.rk4(rhs, x0, problem.time.size - 1, problem.dt)
    return states[:, :, None] if scalar else states


def _outputs_of_states(problem: Problem, states: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Outputs (N, K, ny) of states (N, 9, K)."""
    model = problem.model
    x = states.transpose(1, 0, 2)
    inp = problem.inputs.T[:, :, None]  # (9, N, 1)
    combine = _batch_combination(model, theta, x.shape[1:])
    fx, fy, fz, _, _, speed, alpha, beta, _ = _aero(model, x, tuple(inp[:3]), inp[3], inp[4],
                                                   combine)
    m = inp[5]
    columns = {"V": speed, "alpha": alpha, "beta": beta, "ax": fx / m, "ay": fy / m,
               "az": fz / m}
    for j, s in enumerate(rb.STATES[3:], start=3):
        columns[s] = x[j]
    return np.stack([columns[o] for o in model.outputs], axis=-1)


def _batch(problem: Problem, values: Mapping[str, float],
           columns: Mapping[str, np.ndarray], k: int, dtype: type
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coefficient tensors (6, 10, k), engine terms (2, k) and initial states (9, k).

    ``values`` are scalars common to the batch, ``columns`` arrays (k,) that override them.
    """
    model = problem.model
    index = model.index()
    theta = np.zeros((6, 1 + len(VARIABLES), k), dtype=dtype)
    engine = np.zeros((2, k), dtype=dtype)
    x0 = np.repeat(problem.x0.astype(dtype)[:, None], k, axis=1)
    for name, value in {**model.start, **values, **columns}.items():
        if name in index:
            theta[index[name][0], index[name][1]] = value
        elif name == ROTOR:
            engine[0] = value
        elif name == TORQUE:
            engine[1] = value
        elif name in problem.x0_names:
            x0[rb.STATES.index(name[3:])] = value
    return theta, engine, x0


def _outputs(problem: Problem, values: Mapping[str, float]) -> np.ndarray:
    """Model outputs (N, ny) at parameter values (the others at their fixed/start values).

    A trajectory that leaves the domain of the equations (a trial step of the optimiser
    that makes the model diverge) gives NaN outputs, which the optimiser rejects.
    """
    theta, engine, x0 = _batch(problem, {**problem.fixed, **values}, {}, 1, float)
    try:
        with np.errstate(all="ignore"):
            states = _integrate(problem, theta, engine, x0)
            return _outputs_of_states(problem, states, theta)[:, 0]
    except (ValueError, OverflowError, ZeroDivisionError):
        return np.full(problem.z.shape, np.nan)


def _outputs_and_sensitivities(problem: Problem, values: Mapping[str, float],
                               names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Outputs (N, ny) and complex-step sensitivities (N, ny, len(names)), one batched run."""
    if not names:
        return _outputs(problem, values), np.zeros((problem.z.shape[0], problem.z.shape[1], 0))
    base = {**problem.fixed, **values}
    k = len(names)
    steps = np.array([1e-20 * max(1.0, abs(base[n])) for n in names])
    columns = {}
    for j, name in enumerate(names):
        col = np.full(k, base[name], dtype=complex)
        col[j] += 1j * steps[j]
        columns[name] = col
    theta, engine, x0 = _batch(problem, base, columns, k, complex)
    states = _integrate(problem, theta, engine, x0)
    y = _outputs_of_states(problem, states, theta)  # (N, k, ny)
    sens = np.ascontiguousarray((y.imag / steps[None, :, None]).transpose(0, 2, 1))
    return y[:, 0].real.copy(), sens


def simulate(record: FlightRecord, model: SixDofModel, values: Mapping[str, float] | None = None,
             controls: str = "cubic", x0: Mapping[str, float] | None = None
             ) -> dict[str, np.ndarray]:
    """Model outputs {output: time history (SI)} for a record's inputs at parameter ``values``.

    Parameters not in ``values`` take the model's start values; the initial state is the
    record's first sample, with any ``x0`` {"x0_<state>": value} applied. Use it to predict
    a maneuver not used in the fit.
    """
    problem = problem_from_record(record, model, "estimate" if x0 else "measured", controls)
    problem.fixed = dict(x0 or {})
    y = _outputs(problem, dict(values or {}))
    return {o: y[:, j] for j, o in enumerate(model.outputs)}


# ------------------------------------------------------------------ estimation


def start_from_equation_error(record: FlightRecord, model: SixDofModel) -> dict[str, float]:
    """Start values of every derivative and bias from equation error on the same record.

    One least-squares fit per coefficient on the model's variables (record means as
    references, so the biases are the same parameters). Terms the regression cannot
    estimate keep the model's start values.
    """
    out: dict[str, float] = {}
    for coef, terms in model.structure.items():
        fit = equation_error.estimate(record, coef, list(terms), colored=False)
        for name in (*(parameter_name(coef, v) for v in terms), parameter_name(coef, "0")):
            if name in fit.names and name not in fit.unidentifiable:
                out[name] = fit[name]
    return out


def estimate(
    record: FlightRecord,
    model: SixDofModel | None = None,
    *,
    free: Sequence[str] | None = None,
    start: Mapping[str, float] | str | None = "equation_error",
    initial_state: str = "measured",
    controls: str = "cubic",
    full_noise_covariance: bool = False,
    colored: bool = False,
    max_iterations: int = 30,
    step_tolerance: float = 1e-3,
    cost_tolerance: float = 1e-7,
    check_identifiability: bool = True,
    min_input_range: float = ident.MIN_INPUT_RANGE,
    singular_eigenvalue: float = ident.SINGULAR_EIGENVALUE,
) -> Estimate:
    """Output-error maximum-likelihood estimate of the 6-DOF model's parameters from ``record``.

    model: default ``model_from_record(record)`` (body axes, no alphadot, no rotor).
    free: parameters to estimate (default all); the others stay at their start values.
    start: "equation_error" (default: the free parameters' start from equation error, the
    fixed ones keep the model's), a mapping of start values, or None (model's).
    initial_state: 'measured' (first sample) or 'estimate' (x0_<state> parameters, SI).
    controls: 'cubic' (default) or 'linear' interpolation between samples, or 'zoh' (held).
    Values are nondimensional derivatives, h_engine in N m s; standard errors are
    Cramer-Rao bounds (corrected for colored residuals when ``colored``).
    """
    if model is None:
        model = model_from_record(record)
    if isinstance(start, str):
        if start != "equation_error":
            raise ValueError(f"start must be a mapping, 'equation_error' or None, got {start!r}")
        start = start_from_equation_error(record, model)
        if free is not None:  # a parameter held fixed keeps its a priori value
            start = {n: v for n, v in start.items() if n in free}
    if start:
        unknown = [k for k in start if k not in model.parameters]
        if unknown:
            raise ValueError(f"start values for unknown parameter(s) {', '.join(unknown)}")
        model = replace(model, start={**model.start, **start})
    problem = problem_from_record(record, model, initial_state, controls)
    names = list(model.parameters if free is None else free)
    unknown = [n for n in names if n not in model.parameters]
    if unknown:
        raise ValueError(f"{', '.join(unknown)} not parameter(s) of the 6-DOF model "
                         f"({', '.join(model.parameters)})")
    x0_start = {n: float(problem.x0[rb.STATES.index(n[3:])]) for n in problem.x0_names}
    names += list(problem.x0_names)
    values = {**{n: model.start[n] for n in names if n in model.start}, **x0_start}

    unexcited = _unexcited(problem, names, min_input_range) if check_identifiability else {}

    def fit(active: list[str], current: dict[str, float],
            iterations: int = max_iterations) -> MaximumLikelihoodFit:
        problem.fixed = {n: v for n, v in {**model.start, **x0_start}.items() if n not in active}
        with np.errstate(over="ignore", invalid="ignore"):  # rejected diverging trial steps
            return maximum_likelihood(
                problem.z, problem.noise_floor,
                lambda v: _outputs_and_sensitivities(problem, v, active),
                lambda v: _outputs(problem, v),
                active, current, iterations, full_noise_covariance, step_tolerance,
                cost_tolerance)

    final, unidentifiable = refit_iterated(
        names, values, fit, lambda active, fitted: _singular(active, fitted, singular_eigenvalue),
        check_identifiability=check_identifiability, known=unexcited)
    # the estimate of output error ("oe"; ``run`` names the 6-DOF variant)
    est = estimate_from_fit(
        final, method="oe", model=problem.model.name, time=problem.time, measured=problem.z,
        output_names=problem.output_names, fixed=problem.fixed,
        unidentifiable=unidentifiable, colored=colored,
        full_noise_covariance=full_noise_covariance)
    est.fit.update({
        "force_axes": model.force_axes,
        "moment_axes": model.moment_axes,
        "structure": {c: list(t) for c, t in model.structure.items()},
        "references": dict(model.references),
        "integration": f"RK4 at the record rate ({1.0 / problem.dt:g} Hz), controls "
                       f"{controls}",
        "sensitivities": "complex step, batched",
        "initial_state": initial_state,
    })
    return est


def _unexcited(problem: Problem, names: Sequence[str], min_range: float) -> dict[str, str]:
    """Control derivatives whose control does not move (they multiply only that input)."""
    model = problem.model
    used = [c for c in CONTROLS if c in model.variables]
    flat = ident.unexcited_inputs(used, problem.inputs[:, [CONTROLS.index(c) for c in used]],
                                  min_range)
    out = {}
    for name in names:
        var = name.partition("_")[2]
        if var in flat:
            out[name] = (
                f"input {var} is not excited (peak-to-peak {flat[var]:.3g} rad < {min_range:g}): "
                f"{name} multiplies only {var}, so it cannot be separated from the bias terms"
            )
    return out


def _singular(names: list[str], fit: MaximumLikelihoodFit, tol: float) -> dict[str, str]:
    """Unidentifiable parameters of a fit; biases, initial states and h_engine kept in
    preference."""
    values = np.array([fit.values[n] for n in names])
    keep = [n for n in names if n.endswith("_0") or n.startswith("x0_") or n == ROTOR]
    return ident.unidentifiable(names, fit.information, values, prefer_keep=keep,
                                tolerance=tol)


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(OutputErrorOptions):
    """Options of ``--method oe6dof``."""

    structure: dict[str, list[str]] | None = option(
        None, "{coefficient: variables}, e.g. {\"Cm\": [\"alpha\", \"q\", \"de\"]} "
              "(default: every coefficient on its usual variables)")
    alphadot: bool = option(False, "add the alphadot terms (CL_alphadot, Cm_alphadot)")
    outputs: list[str] | None = option(None, "outputs fitted (default: those of V alpha beta "
                                             "p q r phi theta psi ax ay az the record has)")
    rotor_momentum: bool = option(False, "estimate the engine's angular momentum h_engine "
                                         "(N m s)")
    engine_torque: bool = option(False, "estimate a constant engine rolling moment (N m)")
    gravity: float | None = option(None, "gravity (m/s^2; default: at the record's latitude)")
    moment_axes: str = option("body", "axes of Cl and Cn: 'body' or 'stability'")
    propulsive_moments: bool = option(False, "take L_prop M_prop N_prop as measured inputs")
    free: list[str] | None = option(None, "parameters to estimate (default: all)")
    start: dict[str, float] | str | None = option(
        "equation_error", "start values, or 'equation_error'")
    initial_state: str = option("estimate", "'estimate' (x0 parameters) or 'measured'")
    controls: str = option("cubic", "controls between samples: 'cubic', 'linear' or 'zoh'")
    colored: bool = option(True, "Cramer-Rao bounds corrected for colored residuals")
    full_noise_covariance: bool = option(False, "estimate the full output-noise covariance")
    max_iterations: int = option(30, "Gauss-Newton iteration limit")


def run(record: FlightRecord, model: str = "6dof", options: Options | None = None
        ) -> Estimate:
    """6-DOF output error: model '6dof' (body-axis forces) or '6dof_stability' (lift and
    drag), the coefficients' structure and outputs from ``options``."""
    options = options or Options()
    if model not in MODELS:
        raise ValueError(f"6-DOF output error takes model {' or '.join(MODELS)}, got {model!r}")
    six = model_from_record(
        record, options.structure, force_axes=MODELS[model], alphadot=options.alphadot,
        outputs=options.outputs, rotor_momentum=options.rotor_momentum,
        engine_torque=options.engine_torque, gravity=options.gravity,
        moment_axes=options.moment_axes, propulsive_moments=options.propulsive_moments)
    est = estimate(
        record, six, free=options.free, start=options.start,
        initial_state=options.initial_state, controls=options.controls,
        full_noise_covariance=options.full_noise_covariance, colored=options.colored,
        max_iterations=options.max_iterations, **options.tuning())
    est.method = ID
    return est


def channels(model: str) -> tuple[str, ...]:
    """Channels the 6-DOF model needs: states, controls, specific forces, air data."""
    return ("V", "alpha", "beta", "p", "q", "r", "phi", "theta", "ax", "ay", "az", "de", "da",
            "dr", "qbar")


METHOD = Method(
    id=ID, name="6-DOF output error",
    summary="maximum likelihood on the nonlinear rigid-body equations (RK4, complex-step "
            "sensitivities) with linear aerodynamic coefficients",
    reference="Morelli & Klein, Aircraft System Identification: Theory and Practice, "
              "2nd ed., 2016, ch. 6; Jategaonkar 2015 ch. 4",
    options=Options, models=tuple(MODELS), default_model="6dof", channels=channels,
    run=run, contract_model="6dof",
)
