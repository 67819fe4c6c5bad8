"""The flight core's set-up: ``SimulationBase``, the part of ``Simulation`` before stepping.

It holds the private model copy and its cached property nodes, the reset to a trim
(``_reset``) and the control increments turned into JSBSim commands (``travel``,
``_apply_controls``). ``sim.flight.simulation.Simulation`` adds the sample reads, ``step``,
``stepper`` and the flight loop ``fly``.
"""

from __future__ import annotations

from collections.abc import Mapping

from flightid.sim.flight.atmosphere import Atmosphere
from flightid.sim.flight.controls import command_maps, interp_point, substeps
from flightid.sim.flight.departure import Limits, envelope
from flightid.sim.flight.initial import evaluate, restart
from flightid.sim.flight.properties import (
    AGL,
    CALM_FILLED,
    FLAP,
    GUST,
    RAW,
    RPM,
    WOW,
    scaled_channels,
)
from flightid.sim.jsbsim.model import COMMANDS, DRIVE, DRIVE_ON, Model, as_model
from flightid.sim.jsbsim.trim import Trim, apply, steady_engines
from flightid.units import FT

SURFACE_MODES = ("commanded", "driven")
_DRIVE_SPAN = 10.0  # rad: the driven surfaces' identity map spans any position


class SimulationBase:
    """Set-up of the stepping core: model, property nodes, reset to trim, control commands."""

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
        flap = (FLAP,) if model.has(FLAP) else ()
        self._rpm = next((p for p in RPM if model.has(p)), None)
        self.columns: tuple[str, ...] = RAW + flap + ((self._rpm,) if self._rpm else ())
        self._col = {name: i for i, name in enumerate(self.columns)}
        self._table = scaled_channels(model.reference)
        # what the flight loop reads per sample (the rest is filled in after the flight)
        self._calm = self.atmosphere.turbulence == "none"
        self._loop_columns = tuple(c for c in self.columns if c not in (AGL, WOW)
                                   and not (self._calm and c in CALM_FILLED))
        self._bind()
        self._maps: dict[str, tuple[list[float], list[float]]] = {}
        self._trim_cmd: dict[str, float] = {}
        self._trim_pos: dict[str, float] = {}
        self._trim_throttle = 0.0

    def _bind(self) -> None:
        """Take the property nodes of the current FGFDMExec (again after a reload)."""
        model = self.model
        # gear/wow is absent on aircraft without gear: created, it stays 0
        node = {p: model.node(p, create=(p == WOW)) for p in self.columns}
        self._agl_node, self._wow_node = node[AGL], node[WOW]
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
        self._gust_setters = [model.node(p).set_double_value for p in GUST]
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
                              for c, (pos, cmds) in command_maps(model, trim).items()}
                self._trim_cmd = {c: trim.jsbsim.get(COMMANDS[c][0], 0.0)
                                  for c in self._cmd_setters}
            self._trim_throttle = trim.throttle
            self.trim = trim
        restart(self.model, trim, self.atmosphere)
        if self.driven:
            fdm[DRIVE_ON] = 1.0
        self._k = 0
        self._envelope = envelope(self.limits, self.model, trim)
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
        steady_engines(model)
        if self.atmosphere.wind_ned_m_s[2]:
            # run_ic resets the wind to the IC's (horizontal only): add the vertical part
            # and re-evaluate every model at t = 0 without integrating
            fdm["atmosphere/wind-down-fps"] = self.atmosphere.wind_ned_m_s[2] / FT
            evaluate(self.model)

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
        return interp_point(self._trim_pos[control] + increment, *m)

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
