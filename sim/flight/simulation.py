"""Fly a trimmed JSBSim aircraft with scripted control inputs and record the truth channels.

``Simulation`` is the stepping core: ``reset(trim)``, then either ``step(controls)`` once
per record interval (a controller, the bridge, a gym environment) or ``fly(...)`` for a
whole scripted flight. ``Simulation.fly`` is the one flight loop of the project: the
module-level ``fly``, the disturbance runner (``sim.flight.disturbed.fly_disturbed``) and the
flight cards all go through it. Its hooks: control increments (arrays, callables or
constants), a gust schedule and a turbulence schedule (n x 3 NED, m/s, written into
JSBSim's ``atmosphere/gust-*-fps``), and a ``progress(k, n)`` callback.

Timing. JSBSim integrates at ``substeps`` times the record rate (at least
``MIN_INTERNAL_HZ`` = 400 Hz: 100 Hz record -> 400 Hz internal, 4 substeps). JSBSim runs
its models in the order propagate -> FCS -> ... -> aerodynamics -> accelerations, so
after each ``run()`` every property belongs to the new state. ``step(controls)`` sets
the controls before the last substep of the interval: the returned sample at t_k holds
the state at t_k, the surfaces at ``controls`` and the forces they produce, and those
controls act from t_k on (held for one interval). A record therefore pairs each state
with the surface positions acting at that instant, with no hidden delay; a controller
driving ``step`` sees a one-sample transport delay, like a digital flight computer.
Gust and turbulence samples k are written before the substeps that lead to t_k.

Controls are increments on the trim values: de, da, dr in rad (project signs,
flightid/channels.py), throttle as a fraction. Surface increments are mapped to JSBSim's
normalised pilot commands through the FCS's own command -> position map, measured at
reset (so gearing, asymmetric travel and trim summers are honoured); the recorded de,
da, dr are the actual surface positions JSBSim used. With ``surfaces="driven"`` (an
aircraft augmented with ``surface_drive=True``) the increments are surface *positions*
written past the FCS: the aircraft's actuator is bypassed after trim, as a model flown
from a record's measured surfaces needs (those have passed the real actuator already).
``fly`` takes a driven array as samples of a continuous position and writes each sample's
value interpolated at ``hold_center`` (a held value otherwise lags the surface by
(substeps - 1) / 2 internal steps: 2 % of the Twin Otter's pitch-rate peak in a 3211).

Speed. Per sample the loop steps JSBSim, writes the pilot commands and gusts that changed
(the commands of the whole flight are mapped before it, one vectorised ``np.interp`` per
control; JSBSim's models read these inputs and do not write them, so a value written
once holds), reads the raw properties through cached property nodes and packs them into
one buffer of doubles; the conversion to SI channels runs once, vectorised, after the
flight. With JSBSim's own turbulence off (``Atmosphere.turbulence == "none"``) JSBSim's
turbulence velocities and rates are zero, so the aero-relative rates equal the body
rates and the total wind is the steady wind plus the gusts written by the loop: those
nine properties are filled in after the flight instead of read (and checked against
JSBSim at the last sample). ``step`` converts its one sample with plain float
arithmetic, by the same formulas (``_channels``, table-driven: ``scaled_channels``).
``stepper(channels)`` is ``step`` for a loop that needs a few channels (a gym environment):
it reads only their properties and keeps nothing (0.9 of bare JSBSim stepping, against
0.6 for ``step``; benchmarks/gym_throughput.py). benchmarks/bench_runner.py measures
``fly``.

Property nodes belong to one FGFDMExec, and ``reset`` after the first gives the model a
fresh one (bit-identical restarts): nodes taken from ``sim.jsbsim.model`` before a reset are
stale afterwards. ``Simulation.get`` / ``Simulation.set`` resolve on the current one.
"""

from __future__ import annotations

import itertools
import math
import struct
from bisect import bisect_right
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flightid.record import FlightRecord, RecordMeta, Reference
from flightid.sim.jsbsim.model import (
    COMMANDS,
    DRIVE,
    DRIVE_ON,
    SURFACES,
    Model,
    as_model,
    quiet,
    set_integrators,
)
from flightid.sim.jsbsim.trim import _IC_STATE as _IC_ORDER
from flightid.sim.jsbsim.trim import Trim, apply
from flightid.units import EARTH_RADIUS_M, FT, LBF, PSF, SLUG, SLUG_FT2, SLUG_FT3

MIN_INTERNAL_HZ = 400.0
SURFACE_MODES = ("commanded", "driven")
_DRIVE_SPAN = 10.0  # rad: the driven surfaces' identity map spans any position
TURBULENCE_TYPES = {"none": 0, "standard": 1, "culp": 2, "milspec": 3, "tustin": 4}

Control = np.ndarray | Callable[[float], float] | float


class DepartureError(RuntimeError):
    """The flight left the valid envelope; ``reason``, ``time`` (s) and ``record`` say how."""

    def __init__(self, reason: str, time: float, record: FlightRecord | None = None) -> None:
        super().__init__(f"departure at t = {time:.3f} s: {reason}")
        self.reason = reason
        self.time = time
        self.record = record


@dataclass(frozen=True)
class Atmosphere:
    """Disturbances: steady wind (NED, m/s) and JSBSim turbulence with a random seed.

    turbulence: "none", "milspec" or "tustin" (Dryden spectra, MIL-F-8785C; JSBSim
    ``atmosphere/turb-type`` 3 and 4), "standard" or "culp" (JSBSim's older models).
    For milspec/tustin, ``windspeed_20ft_m_s`` sets the low-altitude intensity and
    ``severity`` the probability-of-exceedance curve of MIL-F-8785C Fig. 7 used above
    2000 ft: 0 off, 1 POE 2e-1, 2 1e-1, 3 1e-2 (light), 4 1e-3 (moderate), 5 1e-4,
    6 1e-5 (severe), 7 1e-6 (JSBSim FGWinds: "3=light, 4=moderate, 6=severe"; the
    matching windspeeds at 20 ft are 15, 30 and 45 kt).
    For standard/culp, ``turb_gain`` and ``turb_rate`` are JSBSim's turb-gain/turb-rate.
    """

    wind_ned_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    turbulence: str = "none"
    windspeed_20ft_m_s: float = 0.0
    severity: int = 0
    turb_gain: float = 0.0
    turb_rate: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        if self.turbulence not in TURBULENCE_TYPES:
            raise ValueError(
                f"unknown turbulence {self.turbulence!r}; use one of {', '.join(TURBULENCE_TYPES)}"
            )
        if not 0 <= self.severity <= 7:
            raise ValueError(f"turbulence severity must be 0..7, got {self.severity}")
        if self.windspeed_20ft_m_s < 0:
            raise ValueError(f"windspeed_20ft_m_s must be >= 0, got {self.windspeed_20ft_m_s}")


@dataclass(frozen=True)
class Limits:
    """Departure limits; None picks the default from the model and trim."""

    alpha_rad: tuple[float, float] | None = None  # default: <alphalimits> +-5 deg, else -20..30
    max_speed_m_s: float | None = None  # default: 2 x trim speed
    min_speed_m_s: float | None = None  # default: 0.3 x trim speed


# departure only (not channels): the flight loop reads them only within _NEAR_GROUND_FT
# of the trim's terrain (the height above sea level, read anyway, tells)
_AGL, _WOW = "position/h-agl-ft", "gear/wow"
_NEAR_GROUND_FT = 300.0

# raw JSBSim properties of every sample, in row order (JSBSim units)
_RAW = (
    "velocities/u-aero-fps", "velocities/v-aero-fps", "velocities/w-aero-fps",
    "velocities/p-rad_sec", "velocities/q-rad_sec", "velocities/r-rad_sec",
    "velocities/p-aero-rad_sec", "velocities/q-aero-rad_sec", "velocities/r-aero-rad_sec",
    "attitude/phi-rad", "attitude/theta-rad", "attitude/psi-rad",
    "aero/alpha-rad", "aero/beta-rad", "velocities/vt-fps", "aero/qbar-psf",
    "atmosphere/rho-slugs_ft3", "position/h-sl-ft", "velocities/mach",
    "forces/fbx-total-lbs", "forces/fby-total-lbs", "forces/fbz-total-lbs",
    "accelerations/pdot-rad_sec2", "accelerations/qdot-rad_sec2", "accelerations/rdot-rad_sec2",
    "fcs/elevator-pos-rad", "fcs/left-aileron-pos-rad", "fcs/rudder-pos-rad",
    "fcs/throttle-pos-norm", "forces/fbx-prop-lbs", "inertia/mass-slugs",
    "inertia/ixx-slugs_ft2", "inertia/iyy-slugs_ft2", "inertia/izz-slugs_ft2",
    "inertia/ixz-slugs_ft2",
    "forces/fbx-aero-lbs", "forces/fby-aero-lbs", "forces/fbz-aero-lbs",
    "moments/l-aero-lbsft", "moments/m-aero-lbsft", "moments/n-aero-lbsft",
    "moments/l-prop-lbsft", "moments/m-prop-lbsft", "moments/n-prop-lbsft",
    "atmosphere/total-wind-north-fps", "atmosphere/total-wind-east-fps",
    "atmosphere/total-wind-down-fps",
    "atmosphere/turb-north-fps", "atmosphere/turb-east-fps", "atmosphere/turb-down-fps",
    "position/lat-geod-rad", "position/long-gc-rad", _AGL, _WOW,
)
_FLAP = "fcs/flap-pos-rad"
# rotation speed, first one the aircraft has: a JSBSim propeller, a JSBSim engine, or an
# FCS function (the Telemaster computes its propeller rpm from the throttle)
_RPM = ("propulsion/engine[0]/propeller-rpm", "propulsion/engine[0]/engine-rpm",
        "fcs/propeller-rpm")
_AXES = ("north", "east", "down")
_GUST = tuple(f"atmosphere/gust-{a}-fps" for a in _AXES)
_STEADY_WIND = tuple(f"atmosphere/wind-{a}-fps" for a in _AXES)
_TOTAL_WIND = tuple(f"atmosphere/total-wind-{a}-fps" for a in _AXES)
_TURB = tuple(f"atmosphere/turb-{a}-fps" for a in _AXES)
_RATES = ("velocities/p-rad_sec", "velocities/q-rad_sec", "velocities/r-rad_sec")
_AERO_RATES = ("velocities/p-aero-rad_sec", "velocities/q-aero-rad_sec",
               "velocities/r-aero-rad_sec")
# not read per sample when JSBSim's turbulence is off (FGAuxiliary: aero rates = body
# rates - turbulence rates; FGWinds: total wind = wind + gust + cosine gust + turbulence)
_CALM_FILLED = _AERO_RATES + _TURB + _TOTAL_WIND


_MAPS: dict[tuple, dict[str, tuple[np.ndarray, np.ndarray]]] = {}


def _command_maps(model: Model, trim: Trim) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """FCS maps of de, da, dr at a trim, cached per aircraft file and trim setting."""
    key = (str(model.xml_path), tuple(sorted(trim.jsbsim.items())))
    if key not in _MAPS:
        if len(_MAPS) > 64:
            _MAPS.clear()
        _MAPS[key] = {c: m for c in ("de", "da", "dr")
                      if (m := _command_map(model, c)) is not None}
    return _MAPS[key]


def _command_map(model: Model, control: str) -> tuple[np.ndarray, np.ndarray] | None:
    """(positions, commands) of the FCS map pilot command -> surface (project sign), or None."""
    cmd, _ = COMMANDS[control]
    prop, sign = SURFACES[control]
    if not (model.has(cmd) and model.has(prop)):
        return None
    fdm = model.fdm
    saved = fdm[cmd]
    # the grid holds the usual kinks exactly: command + trim command = 0 and = +-1
    trim_cmd = fdm[COMMANDS[control][1]] if model.has(COMMANDS[control][1]) else 0.0
    grid = np.unique(np.concatenate([np.linspace(-2.0, 2.0, 81),
                                     [-trim_cmd, -1.0 - trim_cmd, 1.0 - trim_cmd]]))
    pos = np.empty_like(grid)
    fdm.set_trim_status(True)  # actuators and kinematics follow their input at once
    try:
        for i, c in enumerate(grid):
            fdm[cmd] = c
            fdm.run_ic()
            pos[i] = sign * fdm[prop]
    finally:
        fdm.set_trim_status(False)
        fdm[cmd] = saved
    order = np.argsort(pos, kind="stable")
    pos, cmds = pos[order], grid[order]
    keep = np.concatenate(([True], np.diff(pos) > 1e-12))  # drop saturated plateaus
    if keep.sum() < 2:
        return None
    return pos[keep], cmds[keep]


def _divide(a: float, b: float) -> float:
    """a / b with numpy's answer for b = 0 (+-inf, or nan for 0 / 0), as records have."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.float64(a) / b)


def hold_center(rate_hz: float) -> float:
    """Where a control given for sample k acts, relative to t_k (s).

    JSBSim computes the forces of a run after its FCS, so the control set before the run
    that ends at t_k makes the forces at t_k and at every substep up to the next setting,
    t_k + (substeps - 1) h: their middle is (substeps - 1) h / 2, h the internal step. An
    input sampled from a continuous signal is best taken there.
    """
    n = substeps(rate_hz)
    return (n - 1) / (2.0 * n * rate_hz)


def substeps(rate_hz: float) -> int:
    """JSBSim runs per record interval at ``rate_hz``: at least ``MIN_INTERNAL_HZ``."""
    return max(1, math.ceil(MIN_INTERNAL_HZ / rate_hz - 1e-9))


def _interp(x: float, xp: Sequence[float], fp: Sequence[float]) -> float:
    """``np.interp`` of one point with numpy's arithmetic (same result, no array overhead)."""
    if x <= xp[0]:
        return fp[0]
    if x >= xp[-1]:
        return fp[-1]
    j = bisect_right(xp, x) - 1  # xp[j] <= x < xp[j + 1]
    if xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    y = slope * (x - xp[j]) + fp[j]
    if y != y:  # nan from an infinite slope: numpy retries from the right end
        y = slope * (x - xp[j + 1]) + fp[j + 1]
        if y != y and fp[j] == fp[j + 1]:
            y = fp[j]
    return y


class Simulation:
    """Stepping core: ``reset(trim)``, then ``step(controls)`` per interval, or ``fly``."""

    def __init__(self, model: Model | str, rate_hz: float = 100.0,
                 atmosphere: Atmosphere | None = None, limits: Limits | None = None,
                 surfaces: str = "commanded") -> None:
        if not rate_hz > 0:
            raise ValueError(f"rate_hz must be positive, got {rate_hz}")
        if surfaces not in SURFACE_MODES:
            raise ValueError(f"surfaces must be one of {', '.join(SURFACE_MODES)}, "
                             f"got {surfaces!r}")
        self.driven = surfaces == "driven"
        # a private copy: reset() reloads it, which must not touch the caller's model
        self.model = model.copy() if isinstance(model, Model) else as_model(model)
        self.rate_hz = float(rate_hz)
        self.substeps = substeps(rate_hz)
        self.internal_hz = self.rate_hz * self.substeps
        self.atmosphere = atmosphere or Atmosphere()
        self.limits = limits or Limits()
        self.trim: Trim | None = None
        self._used = False  # the private model is fresh until the first reset
        self._resets = 0  # a stepper belongs to the flight of one reset
        self._k = 0
        self.model.fdm.set_dt(1.0 / self.internal_hz)
        model = self.model
        if self.driven and not model.has(DRIVE_ON):
            raise ValueError(f"{model.name}: surfaces='driven' needs an aircraft augmented "
                             "with surface_drive=True (flightid.sim.augment)")
        # the raw columns of a sample: fixed for the aircraft, so decided once
        flap = (_FLAP,) if model.has(_FLAP) else ()
        self._rpm = next((p for p in _RPM if model.has(p)), None)
        self.columns: tuple[str, ...] = _RAW + flap + ((self._rpm,) if self._rpm else ())
        self._col = {name: i for i, name in enumerate(self.columns)}
        self._table = scaled_channels(model.reference)
        # what the flight loop reads per sample (the rest is filled in after the flight)
        self._calm = self.atmosphere.turbulence == "none"
        self._loop_columns = tuple(c for c in self.columns if c not in (_AGL, _WOW)
                                   and not (self._calm and c in _CALM_FILLED))
        self._bind()
        self._maps: dict[str, tuple[list[float], list[float]]] = {}
        self._trim_cmd: dict[str, float] = {}
        self._trim_pos: dict[str, float] = {}
        self._trim_throttle = 0.0

    def _bind(self) -> None:
        """Take the property nodes of the current FGFDMExec (again after a reload)."""
        model = self.model
        # gear/wow is absent on aircraft without gear: created, it stays 0
        node = {p: model.node(p, create=(p == _WOW)) for p in self.columns}
        self._agl_node, self._wow_node = node[_AGL], node[_WOW]
        self._nodes = [node[p] for p in self.columns]
        self._loop_nodes = [node[p] for p in self._loop_columns]
        # the unbound method, mapped over the nodes: the cheapest read from Python
        self._get = type(self._nodes[0]).get_double_value
        if self.driven:
            self._cmd_setters = {c: model.node(p).set_double_value for c, p in DRIVE.items()}
        else:
            self._cmd_setters = {c: model.node(COMMANDS[c][0]).set_double_value
                                 for c in ("de", "da", "dr") if model.has(COMMANDS[c][0])}
        self._throttle_setters = [model.node(p).set_double_value
                                  for p in model.throttle_props() if model.has(p)]
        self._gust_setters = [model.node(p).set_double_value for p in _GUST]
        self._run = model.fdm.run

    # -- setup ---------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Time since reset (s)."""
        return self._k / self.rate_hz

    def get(self, prop: str) -> float:
        """A JSBSim property of the current FGFDMExec (JSBSim units); valid across resets."""
        return self.model.get(prop)

    def set(self, prop: str, value: float) -> None:
        """Set a JSBSim property of the current FGFDMExec (JSBSim units); see ``get``."""
        self.model.node(prop).set_double_value(float(value))

    def _set_atmosphere(self) -> None:
        fdm, a = self.model.fdm, self.atmosphere
        fdm["simulation/randomseed"] = a.seed
        if self.model.has("atmosphere/randomseed"):
            fdm["atmosphere/randomseed"] = a.seed
        fdm["atmosphere/turb-type"] = TURBULENCE_TYPES[a.turbulence]
        fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = a.windspeed_20ft_m_s / FT
        fdm["atmosphere/turbulence/milspec/severity"] = a.severity
        fdm["atmosphere/turb-gain"] = a.turb_gain
        fdm["atmosphere/turb-rate"] = a.turb_rate

    def reset(self, trim: Trim, controls: Mapping[str, float] | None = None) -> dict[str, float]:
        """Restore the trimmed state (t = 0) with optional control increments; returns the sample.

        With a steady wind the aircraft keeps its trimmed airspeed and attitude relative to
        the air mass (the ground speed changes). Every reset after the first gives
        ``self.model`` a fresh FGFDMExec: property nodes taken from it before are stale
        (``get``/``set`` and the simulation's own nodes follow the new one).
        """
        self._reset(trim, controls)
        return self._sample(self._read())

    def _reset(self, trim: Trim, controls: Mapping[str, float] | None) -> None:
        if trim.aircraft != self.model.name:
            raise ValueError(f"trim is for {trim.aircraft!r}, simulation flies {self.model.name!r}")
        # a fresh FGFDMExec makes a flight independent of what the model did before
        # (JSBSim keeps roundoff-level traces of earlier runs through run_ic)
        if self._used:
            self.model.reload()
            self._bind()
        self._used = True
        self._resets += 1
        model, fdm = self.model, self.model.fdm
        apply(model, trim)  # the same sequence on every reset: identical flights
        if self.trim is not trim:
            self._trim_pos = {"de": trim.elevator, "da": trim.aileron, "dr": trim.rudder}
            if self.driven:  # the drive takes positions: the map is the identity
                self._maps = {c: ([-_DRIVE_SPAN, _DRIVE_SPAN], [-_DRIVE_SPAN, _DRIVE_SPAN])
                              for c in self._cmd_setters}
                self._trim_cmd = dict(self._trim_pos)
            else:
                self._maps = {c: (pos.tolist(), cmds.tolist())
                              for c, (pos, cmds) in _command_maps(model, trim).items()}
                self._trim_cmd = {c: trim.jsbsim.get(COMMANDS[c][0], 0.0)
                                  for c in self._cmd_setters}
            self._trim_throttle = trim.throttle
            self.trim = trim
        self._restart(trim)
        if self.driven:
            fdm[DRIVE_ON] = 1.0
        self._k = 0
        self._envelope = self._bounds()
        self._lat0 = fdm["position/lat-geod-rad"]
        self._lon0 = fdm["position/long-gc-rad"]
        self._apply_controls(controls)
        fdm.set_trim_status(True)
        try:
            fdm.run_ic()
        finally:
            fdm.set_trim_status(False)
        fdm.get_propulsion().get_steady_state()
        fdm.run_ic()
        if self.atmosphere.wind_ned_m_s[2]:
            # run_ic resets the wind to the IC's (horizontal only): add the vertical part
            # and re-evaluate every model at t = 0 without integrating
            fdm["atmosphere/wind-down-fps"] = self.atmosphere.wind_ned_m_s[2] / FT
            self._evaluate()

    def _evaluate(self) -> None:
        """Re-run every JSBSim model at the current time without integrating."""
        fdm = self.model.fdm
        fdm.suspend_integration()
        fdm.run()
        fdm.resume_integration()

    def _restart(self, trim: Trim) -> None:
        """Re-initialise every JSBSim model (turbulence filters, actuators) at the trim state."""
        fdm = self.model.fdm
        for prop, value in trim.jsbsim.items():
            if not prop.startswith("ic/"):
                fdm[prop] = value
        for prop in _IC_ORDER:
            fdm[prop] = trim.jsbsim[prop]
        # IC body velocities are ground-relative: add the wind so the airspeed stays trimmed
        n, e, d = self.atmosphere.wind_ned_m_s
        wind = np.array([n, e, d], dtype=float) / FT
        w_body = _ned_to_body(wind[:, None], *(np.array([trim.jsbsim[f"ic/{a}"]])
                              for a in ("phi-rad", "theta-rad", "psi-true-rad")))[:, 0]
        for i, axis in enumerate("uvw"):
            fdm[f"ic/{axis}-fps"] = trim.jsbsim[f"ic/{axis}-fps"] + w_body[i]
        # JSBSim's IC takes the horizontal wind as magnitude and direction (ic/vw-north-fps
        # does not stick in 1.3.3); the vertical wind is set after run_ic (see reset)
        fdm["ic/vw-mag-fps"] = math.hypot(n, e) / FT
        fdm["ic/vw-dir-deg"] = math.degrees(math.atan2(e, n))
        with quiet():
            fdm.reset_to_initial_conditions(0)  # InitModel() of every model, then run_ic
        for prop, value in trim.jsbsim.items():  # the FCS re-initialisation cleared them
            if not prop.startswith("ic/"):
                fdm[prop] = value
        fdm["propulsion/set-running"] = -1
        set_integrators(fdm)  # InitModel restored JSBSim's defaults
        self._set_atmosphere()

    # -- controls ------------------------------------------------------------------
    def travel(self, control: str) -> tuple[float, float] | None:
        """(lowest, highest) surface position (rad) the command path of ``control`` reaches,
        or None when the aircraft has no command map for it; valid after ``reset``."""
        m = self._maps.get(control)
        return None if m is None else (m[0][0], m[0][-1])

    def _command_for(self, control: str, increment: float) -> float:
        """JSBSim pilot command that puts the surface at trim + increment (rad)."""
        m = self._maps.get(control)
        if m is None:
            return self._trim_cmd[control]
        return _interp(self._trim_pos[control] + increment, *m)

    def _apply_controls(self, controls: Mapping[str, float] | None) -> None:
        controls = controls or {}
        unknown = controls.keys() - {"de", "da", "dr", "throttle"}
        if unknown:
            raise ValueError(f"unknown controls {sorted(unknown)}; use de, da, dr, throttle")
        for c, set_cmd in self._cmd_setters.items():
            inc = controls.get(c, 0.0)
            set_cmd(self._command_for(c, inc) if inc else self._trim_cmd[c])
        thr = min(1.0, max(0.0, self._trim_throttle + controls.get("throttle", 0.0)))
        for set_thr in self._throttle_setters:
            set_thr(thr)

    def _command_schedule(self, inputs: Mapping[str, np.ndarray], n: int
                          ) -> list[tuple[Callable[[float], None], np.ndarray]]:
        """(setter, command per sample) of every pilot command node for a whole flight.

        The same mapping as ``_apply_controls`` (a zero increment keeps the trim command
        exactly), one vectorised call per control.
        """
        out = []
        for c, set_cmd in self._cmd_setters.items():
            inc = inputs.get(c)
            trim_cmd = self._trim_cmd[c]
            if inc is None or c not in self._maps:
                cmd = np.full(n, trim_cmd)
            else:
                pos, cmds = self._maps[c]
                cmd = np.where(inc != 0.0, np.interp(self._trim_pos[c] + inc, pos, cmds),
                               trim_cmd)
            out.append((set_cmd, cmd))
        thr = np.clip(self._trim_throttle + inputs.get("throttle", np.zeros(n)), 0.0, 1.0)
        out.extend((set_thr, thr) for set_thr in self._throttle_setters)
        return out

    # -- stepping ------------------------------------------------------------------
    def _read(self) -> list[float]:
        return list(map(self._get, self._nodes))

    def step(self, controls: Mapping[str, float] | None = None) -> dict[str, float]:
        """Advance one record interval; ``controls`` (trim increments) act from the new sample.

        Returns the canonical SI channels of the new sample (floats).
        """
        if self.trim is None:
            raise RuntimeError("call reset(trim) before step()")
        run = self._run
        for _ in range(self.substeps - 1):
            run()
        self._apply_controls(controls)
        run()
        self._k += 1
        row = self._read()
        reason = self._departure(row, self._col)
        if reason:
            raise DepartureError(reason, self.time)
        return self._sample(row)

    def stepper(self, channels: Sequence[str]) -> Callable[[Sequence[float]], list[float]]:
        """A lean ``step`` for a loop that needs only a few channels (a gym environment).

        ``advance((de, da, dr))`` (trim increments, rad) advances one record interval as
        ``step({"de": de, "da": da, "dr": dr})`` does (the same commands, set before the
        last substep; the same departure checks as ``fly``, raising DepartureError) and
        returns the SI values of ``channels`` in that order, reading only their JSBSim
        properties: no sample is kept. ``channels`` must be ones of ``scaled_channels``.
        A stepper belongs to the flight of its ``reset``: called after the next one, it
        raises RuntimeError.
        """
        if self.trim is None:
            raise RuntimeError("call reset(trim) before stepper()")
        table = self._table
        unknown = [c for c in channels if c not in table]
        if unknown:
            raise ValueError(f"stepper reads only channels of scaled_channels; not {unknown}")
        alpha, vt, h = "aero/alpha-rad", "velocities/vt-fps", "position/h-sl-ft"
        props = list(dict.fromkeys([alpha, vt, h, *(p for c in channels
                                                     for p in table[c][::2] if p)]))
        col = {p: i for i, p in enumerate(props)}
        spec = [(col[p], k, col[d] if d else None) for p, k, d in map(table.get, channels)]
        get, nodes = self._get, [self.model.node(p) for p in props]
        run, substeps = self._run, range(self.substeps - 1)
        commands = [(i, c, self._cmd_setters[c], self._trim_cmd[c])
                    for i, c in enumerate(("de", "da", "dr")) if c in self._cmd_setters]
        command_for = self._command_for
        a_lo, a_hi, v_lo, v_hi = self._envelope
        h_guard = self.trim.terrain_m / FT + _NEAR_GROUND_FT
        flight = self._resets

        def advance(increments: Sequence[float]) -> list[float]:
            if self._resets != flight:
                raise RuntimeError("this stepper belongs to the flight before the last reset; "
                                   "take a new one with stepper()")
            for _ in substeps:
                run()
            for i, c, set_cmd, trim_cmd in commands:
                inc = increments[i]
                set_cmd(command_for(c, inc) if inc else trim_cmd)
            run()
            self._k += 1
            row = list(map(get, nodes))
            # (a non-finite state makes the airspeed nan or inf: it fails here too)
            if not (a_lo <= row[0] <= a_hi and v_lo <= row[1] <= v_hi and row[2] > h_guard):
                reason = self._departure(row, col)
                if reason:
                    raise DepartureError(reason, self.time)
            try:
                return [row[i] * k if j is None else row[i] * k / row[j] for i, k, j in spec]
            except ZeroDivisionError:  # qbar or V = 0 (limits allowing it): inf or nan
                return [row[i] * k if j is None else _divide(row[i] * k, row[j])
                        for i, k, j in spec]

        return advance

    def fly(self, trim: Trim, controls: Mapping[str, Control] | None = None,
            duration_s: float = 10.0, *, wind: np.ndarray | None = None,
            turbulence: np.ndarray | None = None,
            progress: Callable[[int, int], None] | None = None,
            scenario: dict[str, Any] | None = None) -> FlightRecord:
        """Fly from trim for duration_s (s), recording every 1 / rate_hz s: the flight loop.

        ``controls``: de/da/dr (rad) and throttle (fraction) increments, as arrays on the
        record grid (at least duration_s * rate_hz + 1 samples), callables of time (s) or
        constants. ``wind`` (gusts, booked as wind_north/east/down) and ``turbulence``
        (booked as turb_u/v/w): n x 3 NED velocities (m/s) on the record grid, written
        into JSBSim's gust properties and held over the substeps. ``progress(k, n)`` is
        called every second of flight. Raises DepartureError with the record up to the
        departure.
        """
        if not duration_s > 0:
            raise ValueError(f"duration_s must be positive, got {duration_s}")
        rate_hz = self.rate_hz
        n = int(round(duration_s * rate_hz)) + 1
        inputs = _sampled(controls or {}, n, rate_hz)
        if self.driven:  # positions of a continuous surface: each taken where it acts
            grid, at = np.arange(n), np.arange(n) + hold_center(rate_hz) * rate_hz
            inputs.update({c: np.interp(at, grid, u) for c, u in inputs.items() if c in DRIVE})
        extra = np.zeros((n, 3))
        for label, part in (("wind", wind), ("turbulence", turbulence)):
            if part is not None:
                part = np.asarray(part, dtype=float)
                if part.shape != (n, 3):
                    raise ValueError(f"{label} schedule has shape {part.shape}, needs ({n}, 3)")
                if not np.all(np.isfinite(part)):
                    raise ValueError(f"{label} schedule has non-finite values")
                extra = extra + part
        gust_fps = extra / FT
        self._reset(trim, {c: float(v[0]) for c, v in inputs.items()})
        # JSBSim's pilot commands and gust velocities are inputs that no JSBSim model writes:
        # set at reset, they need writing again only when they change; turbulence changes
        # every sample and is written every sample
        commands = _changes(self._command_schedule(inputs, n), n)
        every_sample = np.count_nonzero(np.any(np.diff(extra, axis=0), axis=1)) > n // 4
        gusts = _changes([] if every_sample else zip(self._gust_setters, gust_fps.T, strict=True),
                         n)
        gust_n, gust_e, gust_d = gust_fps.T.tolist() if every_sample else ([], [], [])
        set_n, set_e, set_d = self._gust_setters
        if np.any(extra[0]):  # (reset left the gusts at zero)
            for set_gust, value in zip(self._gust_setters, gust_fps[0].tolist(), strict=True):
                set_gust(value)
            self._evaluate()  # t = 0 with the gust, without integrating
        columns, col = self._loop_columns, {c: i for i, c in enumerate(self._loop_columns)}
        get, nodes = self._get, self._loop_nodes
        row = list(map(get, nodes))
        departure = self._departure(row, col)
        # each row is packed into one growing buffer of doubles (struct is the cheapest way
        # from Python floats to a C array): its floats die young, no list of lists builds up
        pack = struct.Struct(f"{len(columns)}d").pack
        buffer = bytearray(pack(*row))

        # the loop: locals only, no dicts, no numpy
        run, store = self._run, buffer.extend
        substeps = range(self.substeps - 1)
        a_lo, a_hi, v_lo, v_hi = self._envelope
        i_alpha, i_vt = col["aero/alpha-rad"], col["velocities/vt-fps"]
        i_h, h_guard = col["position/h-sl-ft"], trim.terrain_m / FT + _NEAR_GROUND_FT
        every = max(1, int(round(rate_hz)))
        k = 1
        while departure is None and k < n:
            if every_sample:
                set_n(gust_n[k])
                set_e(gust_e[k])
                set_d(gust_d[k])
            for set_gust, value in gusts[k]:
                set_gust(value)
            for _ in substeps:
                run()
            for set_cmd, value in commands[k]:
                set_cmd(value)
            run()
            row = tuple(map(get, nodes))
            store(pack(*row))
            # (a non-finite state makes the airspeed nan or inf: it fails here too)
            if not (a_lo <= row[i_alpha] <= a_hi and v_lo <= row[i_vt] <= v_hi
                    and row[i_h] > h_guard):
                departure = self._departure(row, col)
            if progress is not None and k % every == 0:
                progress(k, n)
            k += 1
        self._k = k - 1
        values = np.frombuffer(buffer, dtype=float).reshape(k, len(columns))
        raw = {c: values[:, i] for i, c in enumerate(columns)}
        if self._calm:
            self._fill_calm(raw, gust_fps[:k])
        channels = self.convert(raw)
        if turbulence is not None and np.any(turbulence):
            _book_turbulence(channels, np.asarray(turbulence, dtype=float)[:k])
        record = FlightRecord(np.arange(k) / rate_hz, channels, self.meta(scenario))
        if departure is not None:
            raise DepartureError(departure, (k - 1) / rate_hz, record)
        return record

    def _fill_calm(self, raw: dict[str, np.ndarray], gust_fps: np.ndarray) -> None:
        """Columns not read with JSBSim's turbulence off, from what JSBSim computes them of.

        Checked against JSBSim's own values at the last sample, so that a JSBSim whose
        winds work otherwise fails loudly instead of recording wrong winds.
        """
        steady = [self.get(p) for p in _STEADY_WIND]
        n = len(gust_fps)
        for p, aero in zip(_RATES, _AERO_RATES, strict=True):
            raw[aero] = raw[p]
        for i in range(3):
            raw[_TURB[i]] = np.zeros(n)
            raw[_TOTAL_WIND[i]] = steady[i] + gust_fps[:, i]
        for p in _CALM_FILLED:
            actual, filled = self.get(p), float(raw[p][-1])
            if not (actual == filled or (math.isnan(actual) and math.isnan(filled))):
                raise RuntimeError(f"{p} is {actual!r} in JSBSim but {filled!r} as filled in "
                                   "with its turbulence off: JSBSim's wind model changed")

    # -- departure -------------------------------------------------------------------
    def _bounds(self) -> tuple[float, float, float, float]:
        lim, trim = self.limits, self.trim
        if lim.alpha_rad is not None:
            a_lo, a_hi = lim.alpha_rad
        elif self.model.alpha_limits is not None:
            a_lo = self.model.alpha_limits[0] - math.radians(5)
            a_hi = self.model.alpha_limits[1] + math.radians(5)
        else:
            a_lo, a_hi = math.radians(-20), math.radians(30)
        v_hi = lim.max_speed_m_s if lim.max_speed_m_s is not None else 2.0 * trim.speed_m_s
        v_lo = lim.min_speed_m_s if lim.min_speed_m_s is not None else 0.3 * trim.speed_m_s
        return a_lo, a_hi, v_lo / FT, v_hi / FT

    def _departure(self, row: Sequence[float], col: Mapping[str, int]) -> str | None:
        """Why the sample ``row`` (raw values, column index ``col``) left the envelope, or None."""
        if not all(map(math.isfinite, row)):
            bad = [p for p, i in col.items() if not math.isfinite(row[i])]
            return f"state is not finite ({', '.join(bad[:4])})"
        alpha, vt = row[col["aero/alpha-rad"]], row[col["velocities/vt-fps"]]
        a_lo, a_hi, v_lo, v_hi = self._envelope
        agl = row[col[_AGL]] if _AGL in col else self._agl_node.get_double_value()
        wow = row[col[_WOW]] if _WOW in col else self._wow_node.get_double_value()
        if agl <= 0 or wow > 0:
            return f"ground contact (altitude AGL {agl * FT:.1f} m)"
        if not a_lo <= alpha <= a_hi:
            return (f"alpha {math.degrees(alpha):.1f} deg left the range "
                    f"{math.degrees(a_lo):.1f}..{math.degrees(a_hi):.1f} deg")
        if vt > v_hi:
            return f"over-speed: {vt * FT:.1f} m/s > {v_hi * FT:.1f} m/s"
        if vt < v_lo:
            return f"airspeed {vt * FT:.1f} m/s fell below {v_lo * FT:.1f} m/s"
        return None

    # -- conversion --------------------------------------------------------------------
    def _sample(self, row: Sequence[float]) -> dict[str, float]:
        """Canonical SI channels of one raw sample (all columns), as floats."""
        raw = dict(zip(self.columns, row, strict=True))
        try:
            return _channels(raw, self._table, self._lat0, self._lon0, self._rpm,
                             math.sin, math.cos)
        except ZeroDivisionError:  # qbar or V = 0: let numpy give inf / nan as in a record
            arrays = {k: np.array([v]) for k, v in raw.items()}
            return {k: float(v[0]) for k, v in self.convert(arrays).items()}

    def convert(self, raw: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Canonical SI channels from raw JSBSim columns (property -> array), vectorised."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return _channels(raw, self._table, self._lat0, self._lon0, self._rpm,
                             np.sin, np.cos)

    def meta(self, scenario: dict[str, Any] | None = None) -> RecordMeta:
        """Record metadata for flights of this simulation."""
        trim = self.trim
        a = self.atmosphere
        return RecordMeta(
            aircraft=self.model.name,
            condition=trim.condition if trim else {},
            sample_rate=self.rate_hz,
            provenance=f"{self.model.version}; internal rate {self.internal_hz:g} Hz",
            scenario=dict(scenario or {}),
            reference=self.model.reference,
            extra={"atmosphere": {"wind_ned_m_s": list(a.wind_ned_m_s),
                                  "turbulence": a.turbulence,
                                  "windspeed_20ft_m_s": a.windspeed_20ft_m_s,
                                  "severity": a.severity, "seed": a.seed},
                   "aircraft_file": str(self.model.xml_path)},
        )


def scaled_channels(ref: Reference) -> dict[str, tuple[str, float, str | None]]:
    """The channels that are one raw JSBSim property times a constant, or over a second one:
    channel -> (property, factor, divisor property or None); SI value = raw * factor [/ divisor].

    ``_channels`` converts them with this table, and ``Simulation.stepper`` reads only the
    properties of the channels it is asked for.
    """
    qs = PSF * ref.area  # N per psf of dynamic pressure
    two_ft = 2.0 * FT  # phat = p b / 2V = p (b / 2 FT) / vt
    table: dict[str, tuple[str, float, str | None]] = {
        "u": ("velocities/u-aero-fps", FT, None), "v": ("velocities/v-aero-fps", FT, None),
        "w": ("velocities/w-aero-fps", FT, None),
        "p": ("velocities/p-rad_sec", 1.0, None), "q": ("velocities/q-rad_sec", 1.0, None),
        "r": ("velocities/r-rad_sec", 1.0, None),
        "phi": ("attitude/phi-rad", 1.0, None), "theta": ("attitude/theta-rad", 1.0, None),
        "psi": ("attitude/psi-rad", 1.0, None),
        "alpha": ("aero/alpha-rad", 1.0, None), "beta": ("aero/beta-rad", 1.0, None),
        "V": ("velocities/vt-fps", FT, None), "qbar": ("aero/qbar-psf", PSF, None),
        "rho": ("atmosphere/rho-slugs_ft3", SLUG_FT3, None),
        "h": ("position/h-sl-ft", FT, None), "mach": ("velocities/mach", 1.0, None),
        # specific force = non-gravitational force / mass (what an accelerometer reads)
        "ax": ("forces/fbx-total-lbs", FT, "inertia/mass-slugs"),
        "ay": ("forces/fby-total-lbs", FT, "inertia/mass-slugs"),
        "az": ("forces/fbz-total-lbs", FT, "inertia/mass-slugs"),
        "pdot": ("accelerations/pdot-rad_sec2", 1.0, None),
        "qdot": ("accelerations/qdot-rad_sec2", 1.0, None),
        "rdot": ("accelerations/rdot-rad_sec2", 1.0, None),
        "de": ("fcs/elevator-pos-rad", SURFACES["de"][1], None),
        "da": ("fcs/left-aileron-pos-rad", SURFACES["da"][1], None),
        "dr": ("fcs/rudder-pos-rad", SURFACES["dr"][1], None),
        "throttle": ("fcs/throttle-pos-norm", 1.0, None),
        "thrust": ("forces/fbx-prop-lbs", LBF, None),
        "L_prop": ("moments/l-prop-lbsft", LBF * FT, None),
        "M_prop": ("moments/m-prop-lbsft", LBF * FT, None),
        "N_prop": ("moments/n-prop-lbsft", LBF * FT, None),
        "mass": ("inertia/mass-slugs", SLUG, None),
        "Ixx": ("inertia/ixx-slugs_ft2", SLUG_FT2, None),
        "Iyy": ("inertia/iyy-slugs_ft2", SLUG_FT2, None),
        "Izz": ("inertia/izz-slugs_ft2", SLUG_FT2, None),
        # JSBSim reports the tensor element -Ixz; the channel is Etkin's Ixz
        "Ixz": ("inertia/ixz-slugs_ft2", -SLUG_FT2, None),
        "CX": ("forces/fbx-aero-lbs", LBF / qs, "aero/qbar-psf"),
        "CY": ("forces/fby-aero-lbs", LBF / qs, "aero/qbar-psf"),
        "CZ": ("forces/fbz-aero-lbs", LBF / qs, "aero/qbar-psf"),
        "Cl": ("moments/l-aero-lbsft", LBF * FT / (qs * ref.span), "aero/qbar-psf"),
        "Cm": ("moments/m-aero-lbsft", LBF * FT / (qs * ref.chord), "aero/qbar-psf"),
        "Cn": ("moments/n-aero-lbsft", LBF * FT / (qs * ref.span), "aero/qbar-psf"),
        "phat": ("velocities/p-aero-rad_sec", ref.span / two_ft, "velocities/vt-fps"),
        "qhat": ("velocities/q-aero-rad_sec", ref.chord / two_ft, "velocities/vt-fps"),
        "rhat": ("velocities/r-aero-rad_sec", ref.span / two_ft, "velocities/vt-fps"),
        "latitude": ("position/lat-geod-rad", 1.0, None),
        "longitude": ("position/long-gc-rad", 1.0, None),
    }
    return table


def _channels(c: Mapping[str, Any], table: Mapping[str, tuple[str, float, str | None]],
              lat0: float, lon0: float, rpm: str | None, sin: Callable, cos: Callable
              ) -> dict[str, Any]:
    """Canonical SI channels from raw JSBSim values: floats (math) or arrays (numpy);
    ``table`` is ``scaled_channels`` of the aircraft's reference."""
    out = {ch: c[p] * k if d is None else c[p] * k / c[d] for ch, (p, k, d) in table.items()}
    alpha, fx, fz = out["alpha"], out["CX"], out["CZ"]
    out["CL"] = fx * sin(alpha) - fz * cos(alpha)
    out["CD"] = -fx * cos(alpha) - fz * sin(alpha)
    for axis, total, turb in zip(_AXES, _TOTAL_WIND, _TURB, strict=True):
        out[f"wind_{axis}"] = (c[total] - c[turb]) * FT
    out["turb_u"], out["turb_v"], out["turb_w"] = _rotate_to_body(
        *(c[p] * FT for p in _TURB), out["phi"], out["theta"], out["psi"], sin, cos)
    out["north"] = (out["latitude"] - lat0) * EARTH_RADIUS_M
    out["east"] = (out["longitude"] - lon0) * EARTH_RADIUS_M * math.cos(lat0)
    if _FLAP in c:
        out["df"] = c[_FLAP]
    if rpm is not None:
        out["rpm"] = c[rpm]
    return out


def _changes(schedules: Iterable[tuple[Callable[[float], None], np.ndarray]], n: int
             ) -> list[tuple[tuple[Callable[[float], None], float], ...]]:
    """Per sample k, the (setter, value) pairs to write before it: those whose value
    differs from sample k - 1, or every sample for a schedule that changes most of them."""
    dense = []
    sparse: dict[int, list[tuple[Callable[[float], None], float]]] = {}
    for setter, values in schedules:
        values = np.asarray(values, dtype=float)
        changed = np.flatnonzero(values[1:] != values[:-1]) + 1
        if len(changed) > n // 4:
            dense.append(zip(itertools.repeat(setter), values.tolist(), strict=False))
        else:
            for k in changed.tolist():
                sparse.setdefault(k, []).append((setter, float(values[k])))
    out: list[tuple[tuple[Callable[[float], None], float], ...]]
    out = list(zip(*dense, strict=True)) if dense else [()] * n
    for k, pairs in sparse.items():
        out[k] = out[k] + tuple(pairs)
    return out


def _rotate_to_body(n: Any, e: Any, d: Any, phi: Any, theta: Any, psi: Any,
                    sin: Callable, cos: Callable) -> tuple[Any, Any, Any]:
    """NED components into body axes with the 3-2-1 Euler angles (Etkin); floats or arrays."""
    cf, sf, ct, st, cp, sp = cos(phi), sin(phi), cos(theta), sin(theta), cos(psi), sin(psi)
    x = ct * cp * n + ct * sp * e - st * d
    y = (sf * st * cp - cf * sp) * n + (sf * st * sp + cf * cp) * e + sf * ct * d
    z = (cf * st * cp + sf * sp) * n + (cf * st * sp - sf * cp) * e + cf * ct * d
    return x, y, z


def _ned_to_body(vec: np.ndarray, phi: np.ndarray, theta: np.ndarray,
                 psi: np.ndarray) -> np.ndarray:
    """Rotate NED vectors (3 x n) into body axes with the 3-2-1 Euler angles (Etkin)."""
    return np.stack(_rotate_to_body(*vec, phi, theta, psi, np.sin, np.cos))


def _book_turbulence(ch: dict[str, np.ndarray], turb_ned: np.ndarray) -> None:
    """Book a turbulence schedule (n x 3 NED, m/s) under turb_u/v/w, not wind_*."""
    for i, axis in enumerate(_AXES):
        ch[f"wind_{axis}"] = ch[f"wind_{axis}"] - turb_ned[:, i]
    body = _rotate_to_body(*turb_ned.T, ch["phi"], ch["theta"], ch["psi"], np.sin, np.cos)
    for axis, b in zip("uvw", body, strict=True):
        ch[f"turb_{axis}"] = ch[f"turb_{axis}"] + b


def _sampled(controls: Mapping[str, Control], n: int, rate_hz: float) -> dict[str, np.ndarray]:
    """Control increments sampled at the record times (arrays checked, callables evaluated)."""
    out: dict[str, np.ndarray] = {}
    t = np.arange(n) / rate_hz
    for name, c in controls.items():
        if name not in ("de", "da", "dr", "throttle"):
            raise ValueError(f"unknown control {name!r}; use de, da, dr, throttle")
        if callable(c):
            arr = np.array([float(c(ti)) for ti in t])
        elif np.isscalar(c):
            arr = np.full(n, float(c))
        else:
            arr = np.asarray(c, dtype=float)
            if arr.ndim != 1 or arr.size < n:
                raise ValueError(
                    f"control {name!r} has {arr.size} samples; {n} needed for the flight "
                    f"({(n - 1) / rate_hz:g} s at {rate_hz:g} Hz, both ends included)"
                )
            arr = arr[:n]
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"control {name!r} has non-finite values")
        out[name] = arr
    return out


def fly(model: Model | str, trim: Trim, controls: Mapping[str, Control] | None = None,
        duration_s: float = 10.0, rate_hz: float = 100.0,
        atmosphere: Atmosphere | None = None, limits: Limits | None = None,
        scenario: dict[str, Any] | None = None, *, wind: np.ndarray | None = None,
        turbulence: np.ndarray | None = None,
        progress: Callable[[int, int], None] | None = None,
        surfaces: str = "commanded") -> FlightRecord:
    """Fly from trim for duration_s (s) with control increments, recording at rate_hz (Hz).

    ``controls`` maps de/da/dr (rad) and throttle (fraction) to arrays sampled at rate_hz
    (at least duration_s * rate_hz + 1 samples), callables of time (s) or constants.
    ``wind`` / ``turbulence``: optional n x 3 NED schedules (m/s) of gusts and turbulence,
    ``progress(k, n)``: called every second of flight (see ``Simulation.fly``).
    ``surfaces``: "commanded" (through the FCS) or "driven" (positions; see the module note).
    Raises DepartureError (with ``.record`` up to the departure) if the flight departs.
    """
    if not duration_s > 0:
        raise ValueError(f"duration_s must be positive, got {duration_s}")
    sim = Simulation(model, rate_hz=rate_hz, atmosphere=atmosphere, limits=limits,
                     surfaces=surfaces)
    return sim.fly(trim, controls, duration_s, wind=wind, turbulence=turbulence,
                   progress=progress, scenario=scenario)


__all__ = ["Atmosphere", "DepartureError", "Limits", "Simulation", "fly", "scaled_channels"]
