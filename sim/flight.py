"""Fly a trimmed JSBSim aircraft with scripted control inputs and record the truth channels.

``Simulation`` is the stepping core (reset to a trim, step one record interval, read
the channels); ``fly`` is a thin loop over it that returns a FlightRecord.

Timing. JSBSim integrates at ``substeps`` times the record rate (at least
``MIN_INTERNAL_HZ`` = 400 Hz: 100 Hz record -> 400 Hz internal, 4 substeps). JSBSim runs
its models in the order propagate -> FCS -> ... -> aerodynamics -> accelerations, so
after each ``run()`` every property belongs to the new state. ``step(controls)`` sets
the controls before the last substep of the interval: the returned sample at t_k holds
the state at t_k, the surfaces at ``controls`` and the forces they produce, and those
controls act from t_k on (held for one interval). A record therefore pairs each state
with the surface positions acting at that instant, with no hidden delay; a controller
driving ``step`` sees a one-sample transport delay, like a digital flight computer.

Controls are increments on the trim values: de, da, dr in rad (project signs,
flightid/channels.py), throttle as a fraction. Surface increments are mapped to JSBSim's
normalised pilot commands through the FCS's own command -> position map, measured at
reset (so gearing, asymmetric travel and trim summers are honoured); the recorded de,
da, dr are the actual surface positions JSBSim used.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from flightid.record import FlightRecord, RecordMeta
from flightid.sim.model import COMMANDS, SURFACES, Model, as_model, quiet
from flightid.sim.trim import _IC_STATE as _IC_ORDER
from flightid.sim.trim import Trim, apply
from flightid.units import FT, LBF, PSF, SLUG, SLUG_FT2, SLUG_FT3

MIN_INTERNAL_HZ = 400.0
EARTH_RADIUS_M = 6_378_137.0
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
    ``severity`` the probability-of-exceedance index (0..7, 3 = moderate) above 2000 ft.
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


# raw JSBSim properties read every sample, in this order (JSBSim units)
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
    "atmosphere/total-wind-north-fps", "atmosphere/total-wind-east-fps",
    "atmosphere/total-wind-down-fps",
    "atmosphere/turb-north-fps", "atmosphere/turb-east-fps", "atmosphere/turb-down-fps",
    "position/lat-geod-rad", "position/long-gc-rad", "position/h-agl-ft", "gear/wow",
)
_OPTIONAL = ("fcs/flap-pos-rad", "propulsion/engine[0]/propeller-rpm",
             "propulsion/engine[0]/engine-rpm")
_I = {name: i for i, name in enumerate(_RAW)}


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


class Simulation:
    """Stepping core: ``reset(trim)``, then ``step(controls)`` once per record interval."""

    def __init__(self, model: Model | str, rate_hz: float = 100.0,
                 atmosphere: Atmosphere | None = None, limits: Limits | None = None) -> None:
        if not rate_hz > 0:
            raise ValueError(f"rate_hz must be positive, got {rate_hz}")
        # a private copy: reset() reloads it, which must not touch the caller's model
        self.model = model.copy() if isinstance(model, Model) else as_model(model)
        self.rate_hz = float(rate_hz)
        self.substeps = max(1, math.ceil(MIN_INTERNAL_HZ / rate_hz - 1e-9))
        self.internal_hz = self.rate_hz * self.substeps
        self.atmosphere = atmosphere or Atmosphere()
        self.limits = limits or Limits()
        self.trim: Trim | None = None
        self._used = False  # the private model is fresh until the first reset
        self._k = 0
        self.model.fdm.set_dt(1.0 / self.internal_hz)
        self._bind()
        self._maps: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._trim_cmd: dict[str, float] = {}
        self._trim_throttle = 0.0

    def _bind(self) -> None:
        """Cache the property nodes of the current FGFDMExec."""
        model = self.model
        # gear/wow is absent on aircraft without gear: created, it stays 0
        self._nodes = [model.node(p, create=(p == "gear/wow")) for p in _RAW]
        self._optional_names = [p for p in _OPTIONAL if model.has(p)]
        self._optional = [model.node(p) for p in self._optional_names]
        self._cmd_nodes = {c: model.node(COMMANDS[c][0]) for c in ("de", "da", "dr")
                           if model.has(COMMANDS[c][0])}
        self._throttle_nodes = [model.node(p) for p in model.throttle_props() if model.has(p)]

    # -- setup ---------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Time since reset (s)."""
        return self._k / self.rate_hz

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
        the air mass (the ground speed changes).
        """
        if trim.aircraft != self.model.name:
            raise ValueError(f"trim is for {trim.aircraft!r}, simulation flies {self.model.name!r}")
        # a fresh FGFDMExec makes a flight independent of what the model did before
        # (JSBSim keeps roundoff-level traces of earlier runs through run_ic)
        if self._used:
            self.model.reload()
            self._bind()
        self._used = True
        model, fdm = self.model, self.model.fdm
        apply(model, trim)  # the same sequence on every reset: identical flights
        if self.trim is not trim:
            self._maps = _command_maps(model, trim)
            self._trim_cmd = {c: trim.jsbsim.get(COMMANDS[c][0], 0.0) for c in self._cmd_nodes}
            self._trim_throttle = trim.throttle
            self.trim = trim
        self._restart(trim)
        self._k = 0
        self._limits_cache = self._bounds()
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
            fdm.suspend_integration()
            fdm.run()
            fdm.resume_integration()
        row = self._read()
        return self._row_dict(np.asarray(row)[None, :])

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
        self._set_atmosphere()

    # -- stepping ------------------------------------------------------------------
    def _command_for(self, control: str, increment: float) -> float:
        """JSBSim pilot command that puts the surface at trim + increment (rad)."""
        m = self._maps.get(control)
        if m is None:
            return self._trim_cmd[control]
        pos, cmds = m
        trim_pos = {"de": self.trim.elevator, "da": self.trim.aileron, "dr": self.trim.rudder}
        return float(np.interp(trim_pos[control] + increment, pos, cmds))

    def _apply_controls(self, controls: Mapping[str, float] | None) -> None:
        controls = controls or {}
        for c, node in self._cmd_nodes.items():
            inc = controls.get(c, 0.0)
            node.set_double_value(self._command_for(c, inc) if inc else self._trim_cmd[c])
        thr = min(1.0, max(0.0, self._trim_throttle + controls.get("throttle", 0.0)))
        for node in self._throttle_nodes:
            node.set_double_value(thr)
        unknown = set(controls) - {"de", "da", "dr", "throttle"}
        if unknown:
            raise ValueError(f"unknown controls {sorted(unknown)}; use de, da, dr, throttle")

    def _read(self) -> list[float]:
        row = [n.get_double_value() for n in self._nodes]
        row.extend(n.get_double_value() for n in self._optional)
        return row

    def _advance(self, controls: Mapping[str, float] | None) -> list[float]:
        run = self.model.fdm.run
        for _ in range(self.substeps - 1):
            run()
        self._apply_controls(controls)
        run()
        self._k += 1
        return self._read()

    def step(self, controls: Mapping[str, float] | None = None) -> dict[str, float]:
        """Advance one record interval; ``controls`` (trim increments) act from the new sample."""
        if self.trim is None:
            raise RuntimeError("call reset(trim) before step()")
        row = self._advance(controls)
        self._check(row)
        return self._row_dict(np.asarray(row)[None, :])

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

    def _departure(self, row: list[float]) -> str | None:
        alpha, vt = row[_I["aero/alpha-rad"]], row[_I["velocities/vt-fps"]]
        if not all(map(math.isfinite, row)):
            bad = [p for p, x in zip(_RAW, row, strict=False) if not math.isfinite(x)]
            return f"state is not finite ({', '.join(bad[:4])})"
        a_lo, a_hi, v_lo, v_hi = self._limits_cache
        if row[_I["position/h-agl-ft"]] <= 0 or row[_I["gear/wow"]] > 0:
            return f"ground contact (altitude AGL {row[_I['position/h-agl-ft']] * FT:.1f} m)"
        if not a_lo <= alpha <= a_hi:
            return (f"alpha {math.degrees(alpha):.1f} deg left the range "
                    f"{math.degrees(a_lo):.1f}..{math.degrees(a_hi):.1f} deg")
        if vt > v_hi:
            return f"over-speed: {vt * FT:.1f} m/s > {v_hi * FT:.1f} m/s"
        if vt < v_lo:
            return f"airspeed {vt * FT:.1f} m/s fell below {v_lo * FT:.1f} m/s"
        return None

    def _check(self, row: list[float]) -> None:
        reason = self._departure(row)
        if reason:
            raise DepartureError(reason, self.time)

    # -- conversion --------------------------------------------------------------------
    def _row_dict(self, rows: np.ndarray) -> dict[str, float]:
        return {k: float(v[0]) for k, v in self.convert(rows).items()}

    def convert(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """Canonical SI channels from raw JSBSim rows (n x properties), vectorised."""
        col = {name: rows[:, i] for i, name in enumerate(_RAW)}
        for j, name in enumerate(self._optional_names):
            col[name] = rows[:, len(_RAW) + j]
        ref = self.model.reference
        V = col["velocities/vt-fps"] * FT
        alpha = col["aero/alpha-rad"]
        mass_slug = col["inertia/mass-slugs"]
        qs = col["aero/qbar-psf"] * PSF * ref.area  # N
        with np.errstate(divide="ignore", invalid="ignore"):
            fx, fy, fz = (col[f"forces/fb{a}-aero-lbs"] * LBF / qs for a in "xyz")
            cl = col["moments/l-aero-lbsft"] * LBF * FT / (qs * ref.span)
            cm = col["moments/m-aero-lbsft"] * LBF * FT / (qs * ref.chord)
            cn = col["moments/n-aero-lbsft"] * LBF * FT / (qs * ref.span)
            half_v = 2.0 * V
            phat = col["velocities/p-aero-rad_sec"] * ref.span / half_v
            qhat = col["velocities/q-aero-rad_sec"] * ref.chord / half_v
            rhat = col["velocities/r-aero-rad_sec"] * ref.span / half_v
        phi, theta, psi = (col[f"attitude/{a}-rad"] for a in ("phi", "theta", "psi"))
        turb_ned = np.stack([col[f"atmosphere/turb-{a}-fps"] * FT
                             for a in ("north", "east", "down")])
        turb_body = _ned_to_body(turb_ned, phi, theta, psi)
        lat, lon = col["position/lat-geod-rad"], col["position/long-gc-rad"]
        out = {
            "u": col["velocities/u-aero-fps"] * FT,
            "v": col["velocities/v-aero-fps"] * FT,
            "w": col["velocities/w-aero-fps"] * FT,
            "p": col["velocities/p-rad_sec"], "q": col["velocities/q-rad_sec"],
            "r": col["velocities/r-rad_sec"],
            "phi": phi, "theta": theta, "psi": psi,
            "alpha": alpha, "beta": col["aero/beta-rad"], "V": V,
            "qbar": col["aero/qbar-psf"] * PSF,
            "rho": col["atmosphere/rho-slugs_ft3"] * SLUG_FT3,
            "h": col["position/h-sl-ft"] * FT, "mach": col["velocities/mach"],
            # specific force = non-gravitational force / mass (what an accelerometer reads)
            "ax": col["forces/fbx-total-lbs"] / mass_slug * FT,
            "ay": col["forces/fby-total-lbs"] / mass_slug * FT,
            "az": col["forces/fbz-total-lbs"] / mass_slug * FT,
            "pdot": col["accelerations/pdot-rad_sec2"],
            "qdot": col["accelerations/qdot-rad_sec2"],
            "rdot": col["accelerations/rdot-rad_sec2"],
            "de": col["fcs/elevator-pos-rad"] * SURFACES["de"][1],
            "da": col["fcs/left-aileron-pos-rad"] * SURFACES["da"][1],
            "dr": col["fcs/rudder-pos-rad"] * SURFACES["dr"][1],
            "throttle": col["fcs/throttle-pos-norm"],
            "thrust": col["forces/fbx-prop-lbs"] * LBF,
            "mass": mass_slug * SLUG,
            "Ixx": col["inertia/ixx-slugs_ft2"] * SLUG_FT2,
            "Iyy": col["inertia/iyy-slugs_ft2"] * SLUG_FT2,
            "Izz": col["inertia/izz-slugs_ft2"] * SLUG_FT2,
            # JSBSim reports the tensor element -Ixz; the channel is Etkin's Ixz
            "Ixz": -col["inertia/ixz-slugs_ft2"] * SLUG_FT2,
            "CX": fx, "CY": fy, "CZ": fz, "Cl": cl, "Cm": cm, "Cn": cn,
            "CL": fx * np.sin(alpha) - fz * np.cos(alpha),
            "CD": -fx * np.cos(alpha) - fz * np.sin(alpha),
            "phat": phat, "qhat": qhat, "rhat": rhat,
            "wind_north": (col["atmosphere/total-wind-north-fps"]
                           - col["atmosphere/turb-north-fps"]) * FT,
            "wind_east": (col["atmosphere/total-wind-east-fps"]
                          - col["atmosphere/turb-east-fps"]) * FT,
            "wind_down": (col["atmosphere/total-wind-down-fps"]
                          - col["atmosphere/turb-down-fps"]) * FT,
            "turb_u": turb_body[0], "turb_v": turb_body[1], "turb_w": turb_body[2],
            "latitude": lat, "longitude": lon,
            "north": (lat - self._lat0) * EARTH_RADIUS_M,
            "east": (lon - self._lon0) * EARTH_RADIUS_M * math.cos(self._lat0),
        }
        if "fcs/flap-pos-rad" in col:
            out["df"] = col["fcs/flap-pos-rad"]
        rpm = col.get("propulsion/engine[0]/propeller-rpm",
                      col.get("propulsion/engine[0]/engine-rpm"))
        if rpm is not None:
            out["rpm"] = rpm
        return out

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


def _ned_to_body(vec: np.ndarray, phi: np.ndarray, theta: np.ndarray,
                 psi: np.ndarray) -> np.ndarray:
    """Rotate NED vectors (3 x n) into body axes with the 3-2-1 Euler angles (Etkin)."""
    cf, sf, ct, st, cp, sp = (np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta),
                              np.cos(psi), np.sin(psi))
    n, e, d = vec
    x = ct * cp * n + ct * sp * e - st * d
    y = (sf * st * cp - cf * sp) * n + (sf * st * sp + cf * cp) * e + sf * ct * d
    z = (cf * st * cp + sf * sp) * n + (cf * st * sp - sf * cp) * e + cf * ct * d
    return np.stack([x, y, z])


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
        scenario: dict[str, Any] | None = None) -> FlightRecord:
    """Fly from trim for duration_s (s) with control increments, recording at rate_hz (Hz).

    ``controls`` maps de/da/dr (rad) and throttle (fraction) to arrays sampled at rate_hz
    (at least duration_s * rate_hz + 1 samples), callables of time (s) or constants.
    Raises DepartureError (with ``.record`` up to the departure) if the flight departs.
    """
    if not duration_s > 0:
        raise ValueError(f"duration_s must be positive, got {duration_s}")
    sim = Simulation(model, rate_hz=rate_hz, atmosphere=atmosphere, limits=limits)
    n = int(round(duration_s * rate_hz)) + 1
    inputs = _sampled(controls or {}, n, rate_hz)
    names = list(inputs)
    columns = [inputs[c] for c in names]
    sim.reset(trim, {c: float(col[0]) for c, col in zip(names, columns, strict=True)})
    rows = np.empty((n, len(_RAW) + len(sim._optional)))
    rows[0] = sim._read()
    sim._limits_cache = sim._bounds()
    departure = sim._departure(list(rows[0]))
    k = 1
    while departure is None and k < n:
        rows[k] = sim._advance({c: col[k] for c, col in zip(names, columns, strict=True)})
        departure = sim._departure(list(rows[k])) if not _inside(rows[k], sim) else None
        k += 1
    record = FlightRecord(np.arange(k) / rate_hz, sim.convert(rows[:k]), sim.meta(scenario))
    if departure is not None:
        raise DepartureError(departure, (k - 1) / rate_hz, record)
    return record


def _inside(row: np.ndarray, sim: Simulation) -> bool:
    """Fast envelope test (the detailed reason is built only when it fails)."""
    a_lo, a_hi, v_lo, v_hi = sim._limits_cache
    alpha, vt = row[_I["aero/alpha-rad"]], row[_I["velocities/vt-fps"]]
    return (a_lo <= alpha <= a_hi and v_lo <= vt <= v_hi
            and row[_I["position/h-agl-ft"]] > 0 and row[_I["gear/wow"]] <= 0
            and math.isfinite(row[_I["velocities/u-aero-fps"]]))


__all__ = ["Atmosphere", "DepartureError", "Limits", "Simulation", "fly"]
