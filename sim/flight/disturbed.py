"""Atmospheric and engine disturbances: turbulence, steady wind, discrete gusts, vibration.

Each disturbance is a named dataclass of float parameters (SI) declared in the effect
catalogue (``flightid.sim.effects.catalogue``; ``DISTURBANCES`` is its view for
``[[disturbance]]`` tables) and implemented in ``flightid.sim.effects.disturbance``, built
from a flight-card table by ``disturbance_from_dict`` (e.g. ``{kind = "gust", start = 20,
rise = 1, down = 3}``), so that a gap diagnosis can fit it back. How each one reaches
JSBSim (this module):

- ``wind``: steady NED wind through the flight core's ``Atmosphere`` (the aircraft keeps
  its trimmed airspeed; the ground speed changes).
- ``gust``: a 1-cosine gust (MIL-F-8785C 3.7.5; the profile of JSBSim's cosine gust:
  rise, hold, fall) written into JSBSim's ``atmosphere/gust-*-fps``.
- ``turbulence``: continuous turbulence with Dryden or von Karman spectra (MIL-F-8785C
  3.7.2-3.7.4; von Karman by the rational fits of MIL-HDBK-1797), intensity by
  probability of exceedance (light, moderate, severe) or by sigma, scale lengths from
  the height above ground or given. Generated here and written into the same gust
  properties, so JSBSim's aerodynamics fly through it. ``model = "jsbsim"`` uses
  JSBSim's own MIL-F-8785C Dryden generator instead (turb-type 3 through ``Atmosphere``,
  intensity by severity only). We generate our own because JSBSim 1.3.3 evaluates the
  MIL-F-8785C altitude functions at the height above *sea level* clipped at 10 ft (a
  "sea level" flight gets 10 ft scale lengths and sigma_u = 2 sigma_w, measured), cannot
  be given a sigma above 2000 ft, has no von Karman form, and its Tustin form (turb-type
  4) returns NaN from the first step (tan(0) at the zero-dt initialisation).
- ``engine_vibration``: ``flightid.sim.effects.vibration.EngineVibration``, one catalogue
  entry (acts on ``vibration``) that cards accept here or in the sensor suite's mounting
  list; it acts on the IMU inside ``sim.sensors.suites.measure``, so it joins the suite's
  mounting effects and leaves the truth alone.

Time series are generated on the record grid as samples of a continuous wind; the flight
core writes them at each JSBSim substep, linear between the record's samples, so the gust
booked at t_k is the one acting at t_k.
``fly_disturbed`` flies them through the flight core's one loop (``sim.flight.simulation.fly`` with
its ``wind`` and ``turbulence`` schedules); the truth channels ``turb_u/v/w`` carry all
turbulence (JSBSim's and ours, body axes) and ``wind_north/east/down`` the steady wind
plus gusts.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from flightid.record import FlightRecord
from flightid.sim.effects.catalogue import CATALOGUE, ActsOn
from flightid.sim.effects.disturbance import (
    INTENSITIES,
    JSBSIM_SEVERITY,
    TURBULENCE_MODELS,
    W20_KT,
    Gust,
    Turbulence,
    Wind,
    filtered_noise,
    mil_f_8785c,
)
from flightid.sim.effects.vibration import EngineVibration
from flightid.sim.flight.simulation import Atmosphere, Limits, fly
from flightid.sim.jsbsim.model import Model
from flightid.sim.jsbsim.trim import Trim
from flightid.units import KT

# the [[disturbance]] section's effects: disturbances and engine vibration, from the catalogue
DISTURBANCES: dict[str, type] = CATALOGUE.classes(ActsOn.DISTURBANCE, ActsOn.VIBRATION)
TURBULENCE_SIZES = ("intensity", "sigma", "sigma_u", "sigma_v", "sigma_w")


def disturbance_from_dict(d: Mapping[str, Any], context: str = "") -> Any:
    """Build a disturbance from ``{"kind": name, ...}``; errors name ``context.field``.

    The kind is resolved through the effect catalogue (``SECTIONS['disturbance']``).
    Wind may also be given as ``speed`` (m/s) and ``from_deg`` (meteorological: the
    direction it blows from, deg true). ``engine_vibration`` takes the fields of
    ``flightid.sim.effects.vibration.EngineVibration`` (gyro amplitudes also as ``p_deg``...).

    Parameters
    ----------
    d : Mapping
        The disturbance table.
    context : str, optional
        Where the table is, prefixed to field names in messages.

    Returns
    -------
    NamedEffect
        The disturbance.
    """
    pre = f"{context}." if context else ""
    entry = CATALOGUE.lookup_table(d, "disturbance", context)
    body = dict(d)
    if entry.name == "wind" and ("speed" in body or "from_deg" in body):
        if any(k in body for k in ("north", "east")):
            raise ValueError(f"field {pre + 'speed'!r}: give speed/from_deg or north/east, "
                             "not both")
        speed = _number(body.pop("speed", 0.0), pre + "speed")
        frm = math.radians(_number(body.pop("from_deg", 0.0), pre + "from_deg"))
        body["north"], body["east"] = -speed * math.cos(frm), -speed * math.sin(frm)
    if entry.name == "turbulence" and not any(k in body for k in TURBULENCE_SIZES):
        raise ValueError(f"field {pre + 'intensity'!r}: give an intensity (light, moderate, "
                         "severe) or a sigma")
    return entry.from_dict(body, context, skip=("kind",))


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"field {where!r} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"field {where!r} must be finite, got {value!r}")
    return float(value)


# -- putting them together ----------------------------------------------------------------


def atmosphere_for(disturbances: Sequence[Any], seed: int) -> Atmosphere:
    """The flight core's Atmosphere: summed steady winds, JSBSim turbulence, JSBSim seed.

    Parameters
    ----------
    disturbances : sequence
        The disturbances.
    seed : int
        Random seed (taken modulo 2^31).

    Returns
    -------
    Atmosphere
        Steady wind (NED, m/s) and JSBSim turbulence settings.
    """
    wind = np.zeros(3)
    severity = 0
    for d in disturbances:
        if isinstance(d, Wind):
            wind += (d.north, d.east, d.down)
        elif isinstance(d, Turbulence) and d.model == "jsbsim":
            severity = max(severity, JSBSIM_SEVERITY[d.intensity])
    w20 = 0.0
    if severity:
        name = {v: k for k, v in JSBSIM_SEVERITY.items()}[severity]
        w20 = W20_KT[name] * KT
    return Atmosphere(wind_ned_m_s=tuple(float(x) for x in wind),
                      turbulence="milspec" if severity else "none",
                      windspeed_20ft_m_s=w20, severity=severity, seed=int(seed) % 2**31)


def wind_schedule(disturbances: Sequence[Any], n: int, rate_hz: float, trim: Trim,
                  rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(gusts, turbulence): wind velocities on the record grid.

    Parameters
    ----------
    disturbances : sequence
        The disturbances; gusts and non-JSBSim turbulence are scheduled.
    n : int
        Number of samples.
    rate_hz : float
        Record rate, Hz.
    trim : Trim
        The trim (airspeed, height above ground, heading).
    rng : numpy.random.Generator
        Random source.

    Returns
    -------
    tuple of numpy.ndarray
        (gusts, turbulence), NED, m/s; each shape (n, 3).
    """
    t = np.arange(n) / rate_hz
    gusts = np.zeros((n, 3))
    turb = np.zeros((n, 3))
    h_agl = trim.altitude_m - trim.terrain_m
    psi = trim.jsbsim.get("ic/psi-true-rad", 0.0)
    c, s = math.cos(psi), math.sin(psi)
    for d in disturbances:
        if isinstance(d, Gust):
            gusts += d.velocities(t)
        elif isinstance(d, Turbulence) and d.model != "jsbsim":
            uvw = d.velocities(n, rate_hz, trim.speed_m_s, h_agl, rng)
            turb[:, 0] += c * uvw[:, 0] - s * uvw[:, 1]
            turb[:, 1] += s * uvw[:, 0] + c * uvw[:, 1]
            turb[:, 2] += uvw[:, 2]
    return gusts, turb


def vibration_of(disturbances: Sequence[Any]) -> EngineVibration | None:
    """The engine vibration among the disturbances (at most one), or None.

    Parameters
    ----------
    disturbances : sequence
        The disturbances.

    Returns
    -------
    EngineVibration or None
        The vibration.

    Raises
    ------
    ValueError
        With more than one engine vibration.
    """
    vib = [d for d in disturbances if isinstance(d, EngineVibration)]
    if len(vib) > 1:
        raise ValueError("at most one engine_vibration disturbance")
    return vib[0] if vib else None


def fly_disturbed(model: Model, trim: Trim, controls: Mapping[str, np.ndarray],
                  duration_s: float, rate_hz: float, atmosphere: Atmosphere | None = None,
                  wind: np.ndarray | None = None, turbulence: np.ndarray | None = None,
                  limits: Limits | None = None, scenario: dict[str, Any] | None = None,
                  progress: Callable[[int, int], None] | None = None) -> FlightRecord:
    """Fly from trim through the flight core's loop with wind schedules.

    The loop is ``sim.flight.simulation.fly``. ``wind`` and ``turbulence`` are samples of a
    continuous wind on the record grid, written into JSBSim's gust properties at each
    substep, linearly interpolated between the record's samples: the forces at t_k use
    sample k, the value booked at t_k (``turb_u/v/w``, ``wind_*``).

    Parameters
    ----------
    model : Model
        The loaded JSBSim model.
    trim : Trim
        The trim to start from.
    controls : Mapping of str to numpy.ndarray
        Increment arrays of exactly n = duration_s * rate_hz + 1 samples (rad; throttle as a
        fraction).
    duration_s : float
        Flight duration, s.
    rate_hz : float
        Record rate, Hz.
    atmosphere : Atmosphere, optional
        Steady wind and JSBSim turbulence.
    wind : numpy.ndarray, optional
        Gusts, NED, m/s; shape (n, 3), e.g. from :func:`wind_schedule`.
    turbulence : numpy.ndarray, optional
        Turbulence, NED, m/s; shape (n, 3).
    limits : Limits, optional
        Departure limits.
    scenario : dict, optional
        Stored in the record's metadata.
    progress : callable, optional
        ``progress(k, n)``, called every second of flight.

    Returns
    -------
    FlightRecord
        The flight, SI channels.

    Raises
    ------
    ValueError
        For a control with the wrong number of samples.
    DepartureError
        With the record up to the departure.
    """
    n = int(round(duration_s * rate_hz)) + 1
    for c, col in controls.items():
        shape = np.shape(col)
        if shape != (n,):
            raise ValueError(f"control {c!r} has {shape} samples, the flight needs {n}")
    return fly(model, trim, controls, duration_s, rate_hz, atmosphere, limits, scenario,
               wind=wind, turbulence=turbulence, progress=progress)


__all__ = ["DISTURBANCES", "INTENSITIES", "TURBULENCE_MODELS", "Gust", "Turbulence", "Wind",
           "atmosphere_for", "disturbance_from_dict", "filtered_noise", "fly_disturbed",
           "mil_f_8785c", "vibration_of", "wind_schedule"]
