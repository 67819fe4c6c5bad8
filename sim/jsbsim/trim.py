"""Trim a JSBSim aircraft at a flight condition with JSBSim's own trim routine.

Straight flight uses JSBSim's full trim (``do_simple_trim`` mode 1: alpha, throttle,
pitch trim, beta, phi, aileron, rudder against udot wdot qdot vdot pdot rdot); a banked
condition uses its coordinated-turn trim (mode 5, turn rate g tan(phi) / V). The result
is checked (accelerations near zero, no saturated control) and stored with every JSBSim
setting needed to restore the exact state (``Trim.jsbsim``).

The ground is put at least ``CLEARANCE_M`` below the aircraft (terrain elevation
min(0, h - 300 m)), so that "sea level" conditions of the literature are out of ground
effect and clear of the gear.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import jsbsim

from flightid.sim.jsbsim.aero_coefficients import coefficients
from flightid.sim.jsbsim.condition import FlightCondition
from flightid.sim.jsbsim.model import COMMANDS, Model, as_model, quiet
from flightid.units import DEG, FT, LBF

CLEARANCE_M = 300.0
MAX_ALTITUDE_M = 25_000.0
MAX_SPEED_M_S = 1_500.0  # m/s: Mach 4.4 at sea level, beyond any aircraft JSBSim models here
MAX_MACH_PROPELLER = 0.9
# converged-trim check (JSBSim's own tolerances are 1e-3 ft/s^2 and 1e-4 rad/s^2)
MAX_LINEAR_ACCEL = 0.01  # m/s^2
MAX_ANGULAR_ACCEL = 1e-3  # rad/s^2


class TrimError(ValueError):
    """The aircraft cannot be trimmed at the requested condition; the message says why."""


class TrimInputError(TrimError):
    """The requested condition itself is invalid (negative altitude, no flaps, ...): bad
    input rather than a physical failure to trim."""


@dataclass(frozen=True)
class Trim:
    """A trimmed flight condition; angles and surfaces in rad (project signs), throttle 0..1."""

    aircraft: str
    altitude_m: float
    speed_m_s: float
    gamma_rad: float
    bank_rad: float
    flaps_rad: float
    alpha: float
    beta: float
    theta: float
    phi: float
    elevator: float
    aileron: float
    rudder: float
    throttle: float
    terrain_m: float
    residuals: dict[str, float] = field(default_factory=dict)  # udot.. (m/s^2), pdot.. (rad/s^2)
    jsbsim: dict[str, float] = field(default_factory=dict, repr=False)  # properties to restore

    @property
    def flight_condition(self) -> FlightCondition:
        """The condition this trim was made at."""
        return FlightCondition(self.altitude_m, self.speed_m_s, self.gamma_rad,
                               self.bank_rad, self.flaps_rad)

    @property
    def condition(self) -> dict[str, Any]:
        """The flight condition and trim values as a plain dict (for record metadata)."""
        d = asdict(self)
        d.pop("jsbsim")
        return d


# properties that define the trimmed state; restored by :func:`apply`
_IC_STATE = (
    "ic/h-sl-ft", "ic/terrain-elevation-ft", "ic/lat-geod-deg", "ic/long-gc-deg",
    "ic/phi-rad", "ic/theta-rad", "ic/psi-true-rad",
    "ic/u-fps", "ic/v-fps", "ic/w-fps", "ic/p-rad_sec", "ic/q-rad_sec", "ic/r-rad_sec",
)
_STATE_FROM = {
    "ic/phi-rad": "attitude/phi-rad", "ic/theta-rad": "attitude/theta-rad",
    "ic/psi-true-rad": "attitude/psi-rad",
    "ic/u-fps": "velocities/u-aero-fps", "ic/v-fps": "velocities/v-aero-fps",
    "ic/w-fps": "velocities/w-aero-fps",
    "ic/p-rad_sec": "velocities/p-rad_sec", "ic/q-rad_sec": "velocities/q-rad_sec",
    "ic/r-rad_sec": "velocities/r-rad_sec",
}


def _fcs_commands(model: Model) -> list[str]:
    props = [p for pair in COMMANDS.values() for p in pair]
    props += model.throttle_props()
    props += [f"fcs/mixture-cmd-norm[{i}]" for i in range(model.n_engines)]
    props += ["fcs/flap-cmd-norm"]
    # fuel, so that every flight from this trim starts with the same mass and CG
    i = 0
    while model.has(f"propulsion/tank[{i}]/contents-lbs"):
        props.append(f"propulsion/tank[{i}]/contents-lbs")
        i += 1
    return [p for p in props if model.has(p)]


def apply(model: Model, trim: Trim) -> None:
    """Put the model in the trimmed state (IC, commands, engines at steady state).

    Parameters
    ----------
    model : Model
        The loaded JSBSim model; changed in place.
    trim : Trim
        The trim.
    """
    fdm = model.fdm
    for prop, value in trim.jsbsim.items():
        if not prop.startswith("ic/"):
            fdm[prop] = value
    # attitude before body velocities: the IC converts u v w with the current attitude
    for prop in _IC_STATE:
        fdm[prop] = trim.jsbsim[prop]
    fdm["propulsion/set-running"] = -1
    _settle_surfaces(model)
    fdm.get_propulsion().get_steady_state()
    fdm.run_ic()
    steady_engines(model)


def steady_engines(model: Model) -> None:
    """Engines at steady state after the last ``run_ic`` of an initialisation.

    run_ic puts a turboprop's power back to idle (JSBSim's FGTurboProp); without this call
    the Twin Otter's thrust falls from 3581 N to 2024 N in the first second of a flight, a
    phugoid under every maneuver. At steady state unforced thrust and speed hold (3581 N,
    61.70 m/s over 3 s); piston engines are not affected.

    Parameters
    ----------
    model : Model
        The loaded JSBSim model.
    """
    model.fdm.get_propulsion().get_steady_state()


def _settle_surfaces(model: Model) -> None:
    """run_ic with trim status on, so that actuators and flap kinematics jump to their inputs."""
    fdm = model.fdm
    fdm.set_trim_status(True)
    try:
        fdm.run_ic()
    finally:
        fdm.set_trim_status(False)


def _check_inputs(model: Model, altitude_m: float, speed_m_s: float, gamma: float,
                  bank: float, flaps: float = 0.0) -> None:
    where = f"{model.name} at {speed_m_s:g} m/s, {altitude_m:g} m"
    if not all(map(math.isfinite, (altitude_m, speed_m_s, gamma, bank, flaps))):
        raise TrimInputError(f"{where}: altitude, speed, gamma, bank and flaps must be finite "
                             "numbers")
    if speed_m_s <= 0:
        raise TrimInputError(f"{model.name}: speed must be positive, got {speed_m_s:g} m/s")
    if speed_m_s > MAX_SPEED_M_S:
        raise TrimInputError(
            f"{model.name}: speed {speed_m_s:g} m/s is absurd (above {MAX_SPEED_M_S:g} m/s)")
    if altitude_m < 0:
        raise TrimInputError(f"{model.name}: altitude must be >= 0 m, got {altitude_m:g} m")
    if altitude_m > MAX_ALTITUDE_M:
        raise TrimInputError(
            f"{model.name}: altitude {altitude_m:g} m is absurd (above {MAX_ALTITUDE_M:g} m)"
        )
    if abs(gamma) >= math.radians(60):
        raise TrimInputError(f"{where}: flight-path angle (gamma) {math.degrees(gamma):g} deg is "
                             "absurd")
    if abs(bank) >= math.radians(80):
        raise TrimInputError(f"{where}: bank {math.degrees(bank):g} deg is absurd (>= 80 deg)")


def _set_condition(model: Model, altitude_m: float, speed_m_s: float, gamma: float,
                   bank: float, terrain_m: float, alpha: float = 0.0) -> None:
    fdm = model.fdm
    fdm["ic/terrain-elevation-ft"] = terrain_m / FT
    fdm["ic/h-sl-ft"] = altitude_m / FT
    fdm["ic/psi-true-rad"] = 0.0
    fdm["ic/beta-rad"] = 0.0
    fdm["ic/phi-rad"] = bank
    for rate in ("p", "q", "r"):
        fdm[f"ic/{rate}-rad_sec"] = 0.0
    fdm["ic/vt-fps"] = speed_m_s / FT
    fdm["ic/gamma-rad"] = gamma
    fdm["ic/alpha-rad"] = alpha


def _lift_coefficient(model: Model) -> float:
    """CL (stability axes) of the current evaluated state."""
    return coefficients(model)["CL"]


def _spin_up(model: Model, seconds: float = 1.0) -> None:
    """Fly a second at half throttle so that engines and propellers turn before trimming.

    Some engines (e.g. JSBSim's electric engine) do not reach a steady state from rest
    inside the trim loop. The state is re-initialised afterwards; the engine state stays.
    """
    fdm = model.fdm
    saved = {p: fdm[p] for p in model.throttle_props() if model.has(p)}
    for p in saved:
        fdm[p] = 0.5
    for _ in range(int(seconds / fdm.get_delta_t())):
        fdm.run()
    for p, v in saved.items():
        fdm[p] = v


def _stall_check(model: Model, altitude_m: float, speed_m_s: float, gamma: float,
                 bank: float, terrain_m: float) -> None:
    """TrimError when the lift needed exceeds the model's CLmax (alpha sweep 0..25 deg)."""
    fdm = model.fdm
    cl_max, alpha_at = -math.inf, 0.0
    hi = 25.0
    if model.alpha_limits is not None:
        hi = min(hi, max(model.alpha_limits[1] / DEG + 5.0, 10.0))
    steps = int(hi * 2) + 1
    qbar = None
    for i in range(steps):
        alpha = math.radians(hi * i / (steps - 1))
        _set_condition(model, altitude_m, speed_m_s, gamma, bank, terrain_m, alpha)
        fdm.run_ic()
        cl = _lift_coefficient(model)
        qbar = fdm["aero/qbar-psf"]
        if cl > cl_max:
            cl_max, alpha_at = cl, alpha
    weight = fdm["inertia/weight-lbs"]
    cl_needed = weight * math.cos(gamma) / (math.cos(bank) * qbar * fdm["metrics/Sw-sqft"])
    if cl_needed > cl_max:
        raise TrimError(
            f"{model.name} cannot trim at {speed_m_s:g} m/s, {altitude_m:g} m: below stall "
            f"(CL needed {cl_needed:.2f} > CLmax ~{cl_max:.2f} at alpha "
            f"{math.degrees(alpha_at):.0f} deg)"
        )


def _power_check(model: Model, altitude_m: float, speed_m_s: float, gamma: float,
                 bank: float, terrain_m: float) -> str | None:
    """'throttle saturates ...' when full throttle cannot balance drag + weight component.

    Evaluated at the alpha that gives the lift needed (elevator neutral), engines at
    steady state at full throttle: T cos(alpha) - D - W sin(gamma) < 0 means no trim.
    """
    fdm = model.fdm
    weight = fdm["inertia/weight-lbs"]
    for prop in model.throttle_props():
        fdm[prop] = 1.0
    for prop, _ in COMMANDS.values():
        if model.has(prop):
            fdm[prop] = 0.0
    alpha, last = 0.0, None
    for i in range(61):  # smallest alpha whose lift carries the weight
        alpha = math.radians(-6.0 + 0.5 * i)
        _set_condition(model, altitude_m, speed_m_s, gamma, bank, terrain_m, alpha)
        fdm.run_ic()
        qs = fdm["aero/qbar-psf"] * fdm["metrics/Sw-sqft"]
        last = _lift_coefficient(model) * qs
        if last * math.cos(bank) >= weight * math.cos(gamma):
            break
    fdm.get_propulsion().get_steady_state()
    fdm.run_ic()
    drag = coefficients(model)["CD"] * fdm["aero/qbar-psf"] * fdm["metrics/Sw-sqft"]
    thrust = fdm["forces/fbx-prop-lbs"]
    excess = thrust * math.cos(alpha) - drag - weight * math.sin(gamma)
    if excess < 0:
        return (f"throttle saturates at 1.0 (not enough power: drag {drag * LBF:.0f} N + "
                f"weight component {weight * math.sin(gamma) * LBF:.0f} N > thrust "
                f"{thrust * LBF:.0f} N)")
    return None


def _set_flaps(model: Model, flaps_rad: float) -> None:
    if not model.has("fcs/flap-cmd-norm") or not model.has("fcs/flap-pos-rad"):
        if flaps_rad:
            raise TrimInputError(f"{model.name} has no flaps (fcs/flap-cmd-norm)")
        return
    fdm = model.fdm
    lo, hi = 0.0, 1.0
    fdm["fcs/flap-cmd-norm"] = hi
    _settle_surfaces(model)
    full = fdm["fcs/flap-pos-rad"]
    if flaps_rad < 0 or flaps_rad > full + 1e-9:
        raise TrimInputError(
            f"{model.name}: flaps {math.degrees(flaps_rad):g} deg outside 0..{math.degrees(full):g}"
        )
    for _ in range(40):  # bisection on the (monotone) command -> position map
        mid = 0.5 * (lo + hi)
        fdm["fcs/flap-cmd-norm"] = mid
        _settle_surfaces(model)
        if fdm["fcs/flap-pos-rad"] < flaps_rad:
            lo = mid
        else:
            hi = mid
    fdm["fcs/flap-cmd-norm"] = 0.5 * (lo + hi) if flaps_rad > 0 else 0.0


def _saturation(model: Model) -> str | None:
    """Which control is at its stop after a trim, in words, or None."""
    fdm = model.fdm
    throttle = fdm[model.throttle_props()[0]]
    if throttle >= 0.999:
        return "throttle saturates at 1.0 (not enough power)"
    for control, (cmd, trim_cmd) in COMMANDS.items():
        if model.has(cmd) and model.has(trim_cmd):
            total = fdm[cmd] + fdm[trim_cmd]
            if abs(total) >= 0.999:
                surface = {"de": "elevator", "da": "aileron", "dr": "rudder"}[control]
                return f"{surface} saturates (command {total:+.2f})"
    return None


def trim(model: Model | str, altitude_m: float | FlightCondition,
         speed_m_s: float | None = None, gamma_rad: float = 0.0, bank_rad: float = 0.0,
         flaps_rad: float = 0.0) -> Trim:
    """Trim at an altitude, true airspeed, flight-path angle and bank, or at a FlightCondition.

    Parameters
    ----------
    model : Model or str
        The loaded JSBSim model, or an aircraft name.
    altitude_m : float or FlightCondition
        Altitude above sea level, m; or a card's condition, which gives all the others.
    speed_m_s : float, optional
        True airspeed, m/s; required unless ``altitude_m`` is a FlightCondition.
    gamma_rad : float, optional
        Flight-path angle, rad. Default 0.
    bank_rad : float, optional
        Bank angle, rad. Default 0.
    flaps_rad : float, optional
        Flap deflection, rad. Default 0.

    Returns
    -------
    Trim
        The trimmed state, with JSBSim's settings.

    Raises
    ------
    TrimError
        Naming the cause: bad input, below stall, not enough power, a saturated control, or
        JSBSim's trim failing to converge.
    """
    if isinstance(altitude_m, FlightCondition):
        c = altitude_m
        altitude_m, speed_m_s, gamma_rad, bank_rad, flaps_rad = (
            c.altitude_m, c.speed_m_s, c.gamma_rad, c.bank_rad, c.flaps_rad)
    if speed_m_s is None:
        raise TrimInputError("trim needs a speed (m/s) or a FlightCondition")
    model = as_model(model)
    _check_inputs(model, altitude_m, speed_m_s, gamma_rad, bank_rad, flaps_rad)
    fdm = model.fdm
    terrain_m = min(0.0, altitude_m - CLEARANCE_M)
    # Mach limit for propeller aircraft, from the speed of sound at that altitude
    _set_condition(model, altitude_m, speed_m_s, gamma_rad, bank_rad, terrain_m)
    fdm.run_ic()
    mach = fdm["velocities/mach"]
    if model.propeller and mach > MAX_MACH_PROPELLER:  # an absurd condition: bad input
        raise TrimInputError(
            f"{model.name} cannot trim at {speed_m_s:g} m/s, {altitude_m:g} m: Mach {mach:.2f} "
            f"is absurd for a propeller aircraft (limit {MAX_MACH_PROPELLER})"
        )
    for prop in _fcs_commands(model):
        if "mixture" in prop:
            fdm[prop] = 1.0
        elif prop.startswith("fcs/") and prop != "fcs/flap-cmd-norm":
            fdm[prop] = 0.0
    _set_flaps(model, flaps_rad)
    _stall_check(model, altitude_m, speed_m_s, gamma_rad, bank_rad, terrain_m)
    _set_condition(model, altitude_m, speed_m_s, gamma_rad, bank_rad, terrain_m)
    fdm.run_ic()
    fdm["propulsion/set-running"] = -1
    _spin_up(model)
    _set_condition(model, altitude_m, speed_m_s, gamma_rad, bank_rad, terrain_m)
    fdm.run_ic()
    where = f"{model.name} cannot trim at {speed_m_s:g} m/s, {altitude_m:g} m"
    try:
        with quiet():
            fdm.do_trim(5 if abs(bank_rad) > 1e-6 else 1)
    except jsbsim.TrimFailureError as exc:
        cause = (_saturation(model)
                 or _power_check(model, altitude_m, speed_m_s, gamma_rad, bank_rad, terrain_m)
                 or f"JSBSim trim did not converge ({exc})")
        raise TrimError(f"{where}: {cause}") from None
    cause = _saturation(model)
    if cause:
        raise TrimError(f"{where}: {cause}")
    residuals = {
        "udot": fdm["accelerations/udot-ft_sec2"] * FT,
        "vdot": fdm["accelerations/vdot-ft_sec2"] * FT,
        "wdot": fdm["accelerations/wdot-ft_sec2"] * FT,
        "pdot": fdm["accelerations/pdot-rad_sec2"],
        "qdot": fdm["accelerations/qdot-rad_sec2"],
        "rdot": fdm["accelerations/rdot-rad_sec2"],
    }
    worst_lin = max(abs(residuals[k]) for k in ("udot", "vdot", "wdot"))
    worst_ang = max(abs(residuals[k]) for k in ("pdot", "qdot", "rdot"))
    if worst_lin > MAX_LINEAR_ACCEL or worst_ang > MAX_ANGULAR_ACCEL:
        raise TrimError(
            f"{where}: JSBSim trim left accelerations {worst_lin:.3g} m/s^2, "
            f"{worst_ang:.3g} rad/s^2"
        )
    if fdm["position/h-agl-ft"] <= 0 or fdm["gear/wow"] > 0:
        raise TrimError(f"{where}: the aircraft is on the ground")
    saved = {p: fdm[p] for p in _fcs_commands(model)}
    saved["ic/h-sl-ft"] = fdm["position/h-sl-ft"]
    saved["ic/terrain-elevation-ft"] = terrain_m / FT
    saved["ic/lat-geod-deg"] = fdm["position/lat-geod-deg"]
    saved["ic/long-gc-deg"] = fdm["position/long-gc-deg"]
    for ic_prop, state_prop in _STATE_FROM.items():
        saved[ic_prop] = fdm[state_prop]
    result = Trim(
        aircraft=model.name,
        altitude_m=altitude_m,
        speed_m_s=speed_m_s,
        gamma_rad=gamma_rad,
        bank_rad=bank_rad,
        flaps_rad=flaps_rad,
        alpha=fdm["aero/alpha-rad"],
        beta=fdm["aero/beta-rad"],
        theta=fdm["attitude/theta-rad"],
        phi=fdm["attitude/phi-rad"],
        elevator=model.surface("de"),
        aileron=model.surface("da"),
        rudder=model.surface("dr"),
        throttle=fdm[model.throttle_props()[0]],
        terrain_m=terrain_m,
        residuals=residuals,
        jsbsim=saved,
    )
    return result
