"""The parameters of flight path reconstruction (instrument biases, scale factors, time
shifts, vane positions, wind, initial states), their units and a priori values, and the
effect-catalogue entries they correspond to.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flightid.channels import CHANNELS
from flightid.record import FlightRecord

METHOD = "compatibility"
INPUTS: tuple[str, ...] = ("ax", "ay", "az", "p", "q", "r")
STATES: tuple[str, ...] = ("u", "v", "w", "phi", "theta", "psi", "h", "north", "east")
OUTPUTS: tuple[str, ...] = ("V", "alpha", "beta", "phi", "theta", "psi", "h", "north", "east")
DEFAULT_OUTPUTS: tuple[str, ...] = ("V", "alpha", "beta", "phi", "theta", "psi", "h")
REQUIRED: tuple[str, ...] = (*INPUTS, "V", "alpha", "beta", "phi", "theta")
VANE_POSITIONS: tuple[str, ...] = tuple(
    f"vane_{angle}_{axis}" for angle in ("alpha", "beta") for axis in "xyz")
WIND: tuple[str, ...] = ("wind_north", "wind_east", "wind_down")

# WGS84 ellipsoid (NIMA TR8350.2, 3rd ed.): semi-major axis, first eccentricity squared
WGS84_A, WGS84_E2 = 6378137.0, 0.00669437999013
DEFAULT_LATITUDE = math.radians(45.0)
EARTH_RATE = 7.292115e-5  # rad/s, WGS84
MIN_SAMPLES = 50
# an output that repeats its previous sample this often is a slow source held between
# updates (the Twin Otter heading: 98 %); it is left out of the default outputs
MAX_HELD = 0.95
# sensor parameters whose estimates correlate more than this cannot be told apart by the
# maneuver (e.g. bias_ay and bias_r, b_ay = u b_r, without a heading output)
MAX_CORRELATION = 0.99
START_WINDOW_S = 0.5  # initial states from a line fit over this much of the record


# ------------------------------------------------------------------ parameters


@dataclass(frozen=True)
class Parameter:
    """One parameter of the reconstruction: its unit, a priori value and what it means."""

    name: str
    unit: str
    default: float
    step: float  # finite-difference half step for the sensitivities
    in_states: bool  # changes the integrated states (else only the output equations)
    description: str


def _catalogue() -> dict[str, Parameter]:
    out: dict[str, Parameter] = {}

    def add(name, unit, step, in_states, text, default=0.0):
        out[name] = Parameter(name, unit, default, step, in_states, text)

    for c in INPUTS:
        unit = CHANNELS[c].unit
        step = 1e-3 if c.startswith("a") else 1e-5
        add(f"bias_{c}", unit, step, True, f"bias of the {c} sensor ({unit})")
        add(f"scale_{c}", "-", 1e-4, True, f"scale-factor error of the {c} sensor: m = (1+s) x")
    for c in OUTPUTS:
        unit = CHANNELS[c].unit
        step = {"m/s": 1e-3, "rad": 1e-5, "m": 1e-2}[unit]
        add(f"bias_{c}", unit, step, False, f"bias of the measured {c} ({unit})")
        add(f"delay_{c}", "s", 1e-3, False, f"time delay of {c} behind the inertial inputs (s)")
    add("scale_V", "-", 1e-4, False, "airspeed scale-factor error: m = (1+s) V + b")
    add("upwash_alpha", "-", 1e-4, False, "alpha vane flow amplification: K_alpha = 1 + k")
    add("sidewash_beta", "-", 1e-4, False, "beta vane flow amplification: K_beta = 1 + k")
    for name in VANE_POSITIONS:
        axis = name[-1]
        add(name, "m", 1e-2, False, f"{name.split('_')[1]} vane position, body {axis} from the CG")
    for name in WIND:
        add(name, "m/s", 1e-3, True, f"constant wind, {name[5:]} component (m/s)")
    for s in STATES:
        unit = CHANNELS[s].unit
        step = {"m/s": 1e-3, "rad": 1e-5, "m": 1e-2}[unit]
        add(f"x0_{s}", unit, step, True, f"initial {s} ({unit})")
    return out


PARAMETERS: dict[str, Parameter] = _catalogue()


def _catalogue_effects() -> dict[str, tuple[str, str]]:
    """Parameter -> (entry, parameter) of the effect catalogue (``flightid effects``)."""
    out: dict[str, tuple[str, str]] = {}
    for name in PARAMETERS:
        kind, _, rest = name.partition("_")
        if kind == "bias":
            out[name] = ("bias", "value")  # bias_<c>: the bias on channel c
        elif kind == "scale":
            out[name] = ("scale", "factor")  # scale_<c> = factor - 1
        elif kind == "delay":
            out[name] = ("delay", "tau")
        elif kind == "vane":
            out[name] = ("vanes", rest)  # vane_alpha_x -> vanes.alpha_x
        elif kind == "wind":
            out[name] = ("wind", rest)
    out["upwash_alpha"] = ("vanes", "upwash")
    out["sidewash_beta"] = ("vanes", "sidewash")
    return out


# which injectable effect each sensor parameter estimates: name -> (catalogue entry, its
# parameter); the initial states x0_<state> are not effects
CATALOGUE_EFFECTS: dict[str, tuple[str, str]] = _catalogue_effects()


def default_free(record: FlightRecord, outputs: Sequence[str] | None = None) -> list[str]:
    """The parameters estimated unless told otherwise.

    The six inertial biases, the alpha and beta vane bias and flow amplification, and the
    airspeed bias, each vane and airspeed term only when its output is fitted (initial states
    are always added).

    Parameters
    ----------
    record : FlightRecord
        The flight.
    outputs : sequence of str, optional
        The outputs fitted. Default ``default_outputs(record)``.

    Returns
    -------
    list of str
        The parameter names.
    """
    outputs = list(outputs or default_outputs(record))
    free = [f"bias_{c}" for c in INPUTS]
    if "alpha" in outputs:
        free += ["bias_alpha", "upwash_alpha"]
    if "beta" in outputs:
        free += ["bias_beta", "sidewash_beta"]
    if "V" in outputs:
        free += ["bias_V"]
    return free


def default_outputs(record: FlightRecord) -> list[str]:
    """The outputs flight path reconstruction fits by default: those of ``DEFAULT_OUTPUTS``
    the record has, without the channels held for ``MAX_HELD`` of their samples or more.

    Parameters
    ----------
    record : FlightRecord
        The flight record.

    Returns
    -------
    list of str
        The output channels.
    """
    return [c for c in DEFAULT_OUTPUTS if c in record and held_fraction(record[c]) < MAX_HELD]


def held_fraction(x: np.ndarray) -> float:
    """Fraction of samples that repeat the previous one exactly (a slow or held source).

    Parameters
    ----------
    x : numpy.ndarray
        A channel's samples.

    Returns
    -------
    float
        The fraction, 1; 0 for fewer than two samples.
    """
    return float(np.mean(np.diff(np.asarray(x)) == 0)) if len(x) > 1 else 0.0


