"""The air a flight flies through: the steady wind and JSBSim's turbulence settings
(``Atmosphere``), written into JSBSim at each reset, and the wind channels filled in after
a flight flown with JSBSim's turbulence off."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from flightid.sim.flight.properties import (
    AERO_RATES,
    CALM_FILLED,
    RATES,
    STEADY_WIND,
    TOTAL_WIND,
    TURB,
)
from flightid.sim.jsbsim.model import Model
from flightid.units import FT

TURBULENCE_TYPES = {"none": 0, "standard": 1, "culp": 2, "milspec": 3, "tustin": 4}


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


def set_atmosphere(model: Model, a: Atmosphere) -> None:
    """Write the random seeds and the turbulence settings of ``a`` into the model's FGFDMExec.

    Values go in JSBSim units; the steady wind is set with the initial conditions.

    Parameters
    ----------
    model : Model
        The loaded JSBSim model.
    a : Atmosphere
        Seed, turbulence type, 20 ft wind speed (m/s), severity, gain and rate.
    """
    fdm = model.fdm
    fdm["simulation/randomseed"] = a.seed
    if model.has("atmosphere/randomseed"):
        fdm["atmosphere/randomseed"] = a.seed
    fdm["atmosphere/turb-type"] = TURBULENCE_TYPES[a.turbulence]
    fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = a.windspeed_20ft_m_s / FT
    fdm["atmosphere/turbulence/milspec/severity"] = a.severity
    fdm["atmosphere/turb-gain"] = a.turb_gain
    fdm["atmosphere/turb-rate"] = a.turb_rate


def fill_calm(raw: dict[str, np.ndarray], gust_fps: np.ndarray,
              get: Callable[[str], float]) -> None:
    """The columns not read with JSBSim's turbulence off, from what JSBSim computes them of.

    With ``Atmosphere.turbulence == "none"`` JSBSim's turbulence velocities and rates are
    zero, so the aero-relative rates equal the body rates and the total wind is the steady
    wind plus the gusts the loop wrote. Each filled column is checked against JSBSim's own
    value at the last sample, so that a JSBSim whose winds work otherwise fails loudly
    instead of recording wrong winds.

    Parameters
    ----------
    raw : dict of str to numpy.ndarray
        Raw JSBSim columns by property; the filled columns are added in place.
    gust_fps : numpy.ndarray
        Gusts the loop wrote, NED, ft/s; shape (n, 3).
    get : callable
        Reads a JSBSim property at the last sample.

    Raises
    ------
    RuntimeError
        When a filled column differs from JSBSim's value.
    """
    steady = [get(p) for p in STEADY_WIND]
    n = len(gust_fps)
    for p, aero in zip(RATES, AERO_RATES, strict=True):
        raw[aero] = raw[p]
    for i in range(3):
        raw[TURB[i]] = np.zeros(n)
        raw[TOTAL_WIND[i]] = steady[i] + gust_fps[:, i]
    for p in CALM_FILLED:
        actual, filled = get(p), float(raw[p][-1])
        if not (actual == filled or (math.isnan(actual) and math.isnan(filled))):
            raise RuntimeError(f"{p} is {actual!r} in JSBSim but {filled!r} as filled in "
                               "with its turbulence off: JSBSim's wind model changed")


def substep_gusts(gust_fps: np.ndarray, substeps: int
                  ) -> tuple[list[bool], list[float], list[float], list[float]]:
    """The gusts to write before each JSBSim substep: a continuous wind between samples.

    The gust schedule is a continuous wind sampled on the record grid: before the s-th of
    the ``substeps`` runs of interval k (s = 1..S) the value at t_{k-1} + s h is written,
    linear between samples k - 1 and k. JSBSim's ``run()`` propagates, then evaluates the
    forces with the gust written, so the forces at t_k use exactly sample k: the gust a
    record books at t_k is the one acting there, with no half-step lag of a held value.

    Parameters
    ----------
    gust_fps : numpy.ndarray
        Gust velocities on the record grid, NED, ft/s; shape (n, 3).
    substeps : int
        JSBSim runs per record interval (S >= 1).

    Returns
    -------
    tuple
        (changed, north, east, down): ``changed[k]`` whether sample k differs from sample
        k - 1 (where it does not, nothing is written: the last value holds); the three
        flat lists hold, for each changed interval in order, its S values (ft/s), the last
        one sample k exactly.
    """
    gust_fps = np.asarray(gust_fps, dtype=float)
    changed = np.zeros(len(gust_fps), dtype=bool)
    changed[1:] = np.any(gust_fps[1:] != gust_fps[:-1], axis=1)
    at = np.flatnonzero(changed)
    f = (np.arange(1, substeps + 1) / substeps)[None, :, None]
    # (1 - f) a + f b: f = 1 gives b exactly
    ramp = (1.0 - f) * gust_fps[at - 1][:, None, :] + f * gust_fps[at][:, None, :]
    north, east, down = (ramp[:, :, i].ravel().tolist() for i in range(3))
    return changed.tolist(), north, east, down
