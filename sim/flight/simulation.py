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
controls act from t_k on (held for one interval): a record pairs each state with the
surfaces acting then, and a controller driving ``step`` sees a one-sample delay. Gusts
are written before each substep, linear between the record's samples
(``atmosphere.substep_gusts``): the forces at t_k use sample k, the gust booked at t_k.

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

Speed. Per sample the loop steps JSBSim, writes only the pilot commands and gusts that
changed (``controls.command_schedule`` maps a whole flight's commands before it), reads
the raw properties through cached property nodes into one buffer of doubles and converts
them to SI channels once, vectorised, after the flight (with JSBSim's turbulence off, the
winds are filled in: ``atmosphere.fill_calm``). ``step`` converts its one sample by the same
formulas in floats; ``stepper(channels)`` reads only the channels a gym environment needs
(0.9 of bare JSBSim stepping, against 0.6 for ``step``; benchmarks/gym_throughput.py).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from flightid.record import FlightRecord, RecordMeta
from flightid.sim.flight.atmosphere import Atmosphere, fill_calm, substep_gusts
from flightid.sim.flight.controls import (
    Control,
    command_schedule,
    hold_center,
    sampled_controls,
    schedule_writes,
)
from flightid.sim.flight.departure import DepartureError, Limits, departure_reason
from flightid.sim.flight.initial import evaluate
from flightid.sim.flight.properties import (
    NEAR_GROUND_FT,
    book_turbulence,
    channels_from_raw,
    divide,
    scaled_channels,
)
from flightid.sim.flight.simulation_base import SimulationBase
from flightid.sim.jsbsim.model import DRIVE, Model
from flightid.sim.jsbsim.trim import Trim
from flightid.units import FT


class Simulation(SimulationBase):
    """Stepping core: ``reset(trim)``, then ``step(controls)`` per interval, or ``fly``."""

    def reset(self, trim: Trim, controls: Mapping[str, float] | None = None) -> dict[str, float]:
        """Restore the trimmed state (t = 0) with optional control increments; returns the sample.

        With a steady wind the aircraft keeps its trimmed airspeed and attitude relative to
        the air mass (the ground speed changes). Every reset after the first gives
        ``self.model`` a fresh FGFDMExec: property nodes taken from it before are stale
        (``get``/``set`` and the simulation's own nodes follow the new one).
        """
        self._reset(trim, controls)
        return self._sample(self._read())

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
        h_guard = self.trim.terrain_m / FT + NEAR_GROUND_FT
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
                return [row[i] * k if j is None else divide(row[i] * k, row[j])
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
        into JSBSim's gust properties at each substep, linear between the record's samples
        (sample k acting at t_k). ``progress(k, n)`` is
        called every second of flight. Raises DepartureError with the record up to the
        departure.
        """
        if not duration_s > 0:
            raise ValueError(f"duration_s must be positive, got {duration_s}")
        rate_hz = self.rate_hz
        n = int(round(duration_s * rate_hz)) + 1
        inputs = sampled_controls(controls or {}, n, rate_hz)
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
        # set at reset, they need writing again only when they change
        commands = schedule_writes(command_schedule(
            self._cmd_setters, self._maps, self._trim_cmd, self._trim_pos, self._trim_throttle,
            self._throttle_setters, inputs, n), n)
        # gusts: a continuous wind, written at each substep where it changes
        changed, *ramps = substep_gusts(gust_fps, self.substeps)
        next_n, next_e, next_d = (iter(ramp).__next__ for ramp in ramps)
        set_n, set_e, set_d = self._gust_setters
        if np.any(extra[0]):  # (reset left the gusts at zero)
            for set_gust, value in zip(self._gust_setters, gust_fps[0].tolist(), strict=True):
                set_gust(value)
            evaluate(self.model)  # t = 0 with the gust, without integrating
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
        i_h, h_guard = col["position/h-sl-ft"], trim.terrain_m / FT + NEAR_GROUND_FT
        every = max(1, int(round(rate_hz)))
        k = 1
        while departure is None and k < n:
            if changed[k]:
                for _ in substeps:
                    set_n(next_n())
                    set_e(next_e())
                    set_d(next_d())
                    run()
                set_n(next_n())
                set_e(next_e())
                set_d(next_d())
            else:
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
            fill_calm(raw, gust_fps[:k], self.get)
        channels = self.convert(raw)
        if turbulence is not None and np.any(turbulence):
            book_turbulence(channels, np.asarray(turbulence, dtype=float)[:k])
        record = FlightRecord(np.arange(k) / rate_hz, channels, self.meta(scenario))
        if departure is not None:
            raise DepartureError(departure, (k - 1) / rate_hz, record)
        return record

    # -- departure -------------------------------------------------------------------
    def _departure(self, row: Sequence[float], col: Mapping[str, int]) -> str | None:
        """Why the sample ``row`` (raw values, column index ``col``) left the envelope, or None."""
        return departure_reason(row, col, self._envelope, self._agl_node, self._wow_node)

    # -- conversion --------------------------------------------------------------------
    def _sample(self, row: Sequence[float]) -> dict[str, float]:
        """Canonical SI channels of one raw sample (all columns), as floats."""
        raw = dict(zip(self.columns, row, strict=True))
        try:
            return channels_from_raw(raw, self._table, self._lat0, self._lon0, self._rpm,
                             math.sin, math.cos)
        except ZeroDivisionError:  # qbar or V = 0: let numpy give inf / nan as in a record
            arrays = {k: np.array([v]) for k, v in raw.items()}
            return {k: float(v[0]) for k, v in self.convert(arrays).items()}

    def convert(self, raw: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Canonical SI channels from raw JSBSim columns (property -> array), vectorised."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return channels_from_raw(raw, self._table, self._lat0, self._lon0, self._rpm,
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


def fly(model: Model | str, trim: Trim, controls: Mapping[str, Control] | None = None,
        duration_s: float = 10.0, rate_hz: float = 100.0,
        atmosphere: Atmosphere | None = None, limits: Limits | None = None,
        scenario: dict[str, Any] | None = None, *, wind: np.ndarray | None = None,
        turbulence: np.ndarray | None = None,
        progress: Callable[[int, int], None] | None = None,
        surfaces: str = "commanded") -> FlightRecord:
    """Fly from trim for duration_s with control increments, recording at rate_hz.

    Parameters
    ----------
    model : Model or str
        The loaded JSBSim model, or an aircraft name or XML path.
    trim : Trim
        The trim to start from.
    controls : Mapping of str to Control, optional
        de/da/dr (rad) and throttle (fraction): arrays sampled at rate_hz (at least
        duration_s * rate_hz + 1 samples), callables of time (s) or constants.
    duration_s : float, optional
        Flight duration, s. Default 10.
    rate_hz : float, optional
        Record rate, Hz. Default 100.
    atmosphere : Atmosphere, optional
        Steady wind and JSBSim turbulence.
    limits : Limits, optional
        Departure limits.
    scenario : dict, optional
        Stored in the record's metadata.
    wind, turbulence : numpy.ndarray, optional
        Gust and turbulence schedules, NED, m/s; shape (n, 3).
    progress : callable, optional
        ``progress(k, n)``, called every second of flight (see ``Simulation.fly``).
    surfaces : str, optional
        "commanded" (default; through the FCS) or "driven" (positions; see the module note).

    Returns
    -------
    FlightRecord
        The flight, SI channels.

    Raises
    ------
    ValueError
        For a duration that is not positive.
    DepartureError
        With ``.record`` up to the departure, if the flight departs.
    """
    if not duration_s > 0:
        raise ValueError(f"duration_s must be positive, got {duration_s}")
    sim = Simulation(model, rate_hz=rate_hz, atmosphere=atmosphere, limits=limits,
                     surfaces=surfaces)
    return sim.fly(trim, controls, duration_s, wind=wind, turbulence=turbulence,
                   progress=progress, scenario=scenario)


__all__ = ["Atmosphere", "DepartureError", "Limits", "Simulation", "fly", "scaled_channels"]
