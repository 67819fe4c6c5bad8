"""A record as a six-degree-of-freedom output-error problem: the model built from the
record's aircraft and flight, the measured initial state and air density, and the
controls and propulsive terms arranged for RK4 integration (with the cubic midpoints
between samples). The integration itself is ``simulation``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flightid.identification.data.coefficients import channel_values, mass_properties
from flightid.identification.engine import problem as problem_skeleton
from flightid.identification.models import rigid_body as rb
from flightid.identification.models.six_dof import (
    CONTROL_HOLDS,
    CONTROLS,
    INITIAL_STATES,
    OUTPUTS,
    PROPULSIVE_MOMENTS,
    VARIABLE_CHANNEL,
    VARIABLES,
    SixDofModel,
    check_structure,
    default_structure,
)
from flightid.record import FlightRecord
from flightid.units import G0


@dataclass(kw_only=True)
class Problem(problem_skeleton.Problem):
    """Data and model of one fit, arranged for fast integration (the skeleton's time,
    outputs, fixed parameters, initial states and noise floor, and:)."""

    model: SixDofModel
    # inputs (de - de_ref, da - da_ref, dr - dr_ref, thrust N, rho kg/m^3, mass kg,
    # L_prop, M_prop, N_prop N m (0 unless the model takes them)), (N, 9)
    inputs: np.ndarray
    # the same at the RK4 stage instants t_i, t_i + dt/2, t_i+1: (3, N - 1, 9)
    stage_inputs: np.ndarray
    x0: np.ndarray  # (9,) measured initial state
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

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, with ``meta.reference`` (area m^2, span and chord m) and
        mass properties.
    structure : mapping of str to sequence of str or None, optional
        {coefficient: variables}; default ``default_structure(force_axes, alphadot)``.
    force_axes : str or None, optional
        'body' or 'stability'; inferred from the structure when not given (stability when it
        has CL or CD).
    alphadot : bool, optional
        Add Cm_alphadot to the default structure. Default False.
    outputs : sequence of str or None, optional
        Outputs fitted; default those of ``OUTPUTS`` the record has.
    rotor_momentum : bool, optional
        Add h_engine, the engine rotor's angular momentum (N m s). Default False.
    engine_torque : bool, optional
        Add L_engine, a constant engine rolling moment (N m). Default False.
    start : mapping of str to float or None, optional
        Start values overriding the typical ones.
    gravity : float or None, optional
        Gravity, m/s^2; default the local effective gravity at the record's mean latitude
        and altitude (``rigid_body.local_gravity``), else G0.
    moment_axes : str, optional
        'body' (default) or 'stability': Cl and Cn are stability-axis coefficients on
        stability-axis rates (see ``estimation``'s module docstring).
    propulsive_moments : bool, optional
        Drive the model with the record's L_prop, M_prop, N_prop (N m). Default False.

    Returns
    -------
    SixDofModel
        The model; references are the record means of the variables (rad, nondimensional
        rates).

    Raises
    ------
    ValueError
        An invalid structure or force axes, or no reference geometry.
    """
    if structure is None:
        structure = default_structure(force_axes or "body", alphadot)
    structure = {c: tuple(t) for c, t in structure.items()}
    if force_axes is None:
        force_axes = "stability" if {"CL", "CD"} & set(structure) else "body"
    check_structure(structure, force_axes)
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


def density(record: FlightRecord) -> np.ndarray:
    """The air density along a record.

    Parameters
    ----------
    record : FlightRecord
        A record with ``rho`` (kg/m^3), or ``qbar`` (Pa) and ``V`` (m/s).

    Returns
    -------
    ndarray
        The density (kg/m^3): ``rho``, else 2 qbar / V^2.

    Raises
    ------
    ValueError
        When the record has neither.
    """
    if "rho" in record:
        return record["rho"]
    if "qbar" in record and "V" in record:
        return 2.0 * record["qbar"] / record["V"] ** 2
    raise ValueError("record has neither 'rho' nor 'qbar' and 'V': the 6-DOF model needs the "
                     "air density (kg/m^3)")


def measured_state(record: FlightRecord, index: int = 0) -> np.ndarray:
    """The state (u, v, w, p, q, r, phi, theta, psi) of sample ``index``.

    u, v, w from their channels, else from V, alpha and beta; psi 0 when absent.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    index : int, optional
        Sample index. Default 0.

    Returns
    -------
    numpy.ndarray
        The state, shape (9,): m/s, rad/s, rad.

    Raises
    ------
    ValueError
        A channel needed for the state is missing.
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
    """Arrange a record's inputs and outputs for ``model`` (checks channels and sampling).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval, at least 10 samples, with thrust
        (N), the air density (``rho`` or ``qbar`` and ``V``) and the model's controls.
    model : SixDofModel
        The 6-DOF model.
    initial_state : str, optional
        'measured' (default) or 'estimate' (x0_<state> parameters).
    controls : str, optional
        Inputs at the RK4 half steps: 'cubic' (default), 'linear' or 'zoh'.

    Returns
    -------
    Problem
        Time (s), inputs at the samples and RK4 stage instants, measured outputs, initial
        state, x0 parameter names and noise floor.

    Raises
    ------
    ValueError
        Invalid options, a non-uniform or short record, a missing or non-finite channel, or
        a non-positive air density.
    """
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
    inputs = np.column_stack([*ctrl, record["thrust"], density(record),
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
    mid = cubic_midpoints(inputs) if controls == "cubic" else 0.5 * (inputs[:-1] + inputs[1:])
    start, end = inputs[:-1], inputs[1:].copy()
    if controls == "zoh":
        mid[:, :3] = start[:, :3]
        end[:, :3] = start[:, :3]
    x0 = measured_state(record)
    names = [s for s in rb.STATES if s != "psi" or "psi" in model.outputs]
    x0_names = tuple(f"x0_{s}" for s in names) if initial_state == "estimate" else ()
    return Problem(model=model, time=time, dt=dt, inputs=inputs,
                   stage_inputs=np.stack([start, mid, end]), z=z, x0=x0, x0_names=x0_names,
                   fixed={}, noise_floor=problem_skeleton.noise_floor(z), controls=controls)


def cubic_midpoints(x: np.ndarray) -> np.ndarray:
    """Values halfway between samples (rows) by the 4-point cubic (Lagrange) interpolant.

    (-x[i-1] + 9 x[i] + 9 x[i+1] - x[i+2]) / 16; the end intervals use the linear mean.

    Parameters
    ----------
    x : numpy.ndarray
        Samples, shape (N, ...).

    Returns
    -------
    numpy.ndarray
        Midpoints, shape (N - 1, ...), in the units of ``x``.
    """
    mid = 0.5 * (x[:-1] + x[1:])
    if x.shape[0] >= 4:
        mid[1:-1] = (9.0 * (x[1:-2] + x[2:-1]) - x[:-3] - x[3:]) / 16.0
    return mid
