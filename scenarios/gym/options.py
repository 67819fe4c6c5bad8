"""The options of ``ExcitationEnv``: the observed channels, target presets, residual
stds, the safe envelope, the linear range, the rewards and observation modes, and the
checks of each option (a bad one raises a ValueError naming it)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from flightid.channels import CONTROL_SURFACES
from flightid.sim.jsbsim.condition import FlightCondition
from flightid.units import G0

OBS_CHANNELS = ("t", "V", "alpha", "beta", "p", "q", "r", "phi", "theta", "ax", "ay", "az",
                "de", "da", "dr", "h")
CONTROLS = CONTROL_SURFACES
# |value| bounds of the observation space (far outside the envelope, which ends episodes)
OBS_BOUNDS = {"V": 400.0, "alpha": math.pi, "beta": math.pi, "p": 20.0, "q": 20.0, "r": 20.0,
              "phi": math.pi, "theta": math.pi, "ax": 200.0, "ay": 200.0, "az": 200.0,
              "de": 1.6, "da": 1.6, "dr": 1.6, "h": 30000.0}
PRESETS = {
    "lateral": ("Cl_beta", "Cl_p", "Cl_r", "Cl_da", "Cl_dr",
                "Cn_beta", "Cn_p", "Cn_r", "Cn_da", "Cn_dr"),
    "longitudinal": ("CZ_alpha", "CZ_q", "CZ_de", "Cm_alpha", "Cm_q", "Cm_de"),
}
# std of the equation-error residual of each coefficient (nominal, stated): moments 1e-3,
# forces 1e-2 (the order of the Navion's residuals with the research suite)
SIGMA = {"Cl": 1e-3, "Cm": 1e-3, "Cn": 1e-3, "CX": 1e-2, "CY": 1e-2, "CZ": 1e-2}
# regressor variables: observed channels (p, q, r enter as phat, qhat, rhat)
VARIABLES = ("alpha", "beta", "p", "q", "r", "de", "da", "dr")
# the safe envelope: alpha (deg), |bank| (deg), load factor n = -az / g, airspeed as a
# fraction of the trim airspeed, altitude loss below the trim altitude (m)
LIMITS = {"alpha_deg": (-6.0, 14.0), "bank_deg": 60.0, "load_factor": (-1.0, 3.5),
          "speed_ratio": (0.7, 1.4), "altitude_loss_m": 150.0}
PENALTY = 20.0
# the linear range of the regression: the largest perturbation from trim of each variable
# (deg, deg/s; airspeed as a fraction of the trim airspeed) at which a sample's information
# counts in full under the "valid-information" reward; it counts less beyond, nothing at
# twice it. The 3211 and multisine baselines (0.2 of travel) stay inside on the Navion.
LINEAR_RANGE = {"alpha_deg": 5.0, "beta_deg": 10.0, "p_deg_s": 30.0, "q_deg_s": 15.0,
                "r_deg_s": 30.0, "speed_ratio": 0.1}
REWARDS = ("valid-information", "information", "accuracy")
ACCURACY_SCALE = 100.0  # "accuracy": return of an exact estimate
OBSERVATIONS = ("si", "scaled")
# "scaled" observations: (value - trim value) / scale, so that 1 is the edge of the linear
# range (alpha, beta, rates, airspeed), of the envelope (bank, altitude loss), of the surface
# travel (de, da, dr: the larger of its two sides) or of the episode (t: value / episode_s);
# scales in SI, None where they come from the environment
OBS_SCALES = {"t": None, "V": None,
              **{c: math.radians(LINEAR_RANGE[k]) for c, k in (
                  ("alpha", "alpha_deg"), ("beta", "beta_deg"), ("p", "p_deg_s"),
                  ("q", "q_deg_s"), ("r", "r_deg_s"))},
              "phi": math.radians(LIMITS["bank_deg"]), "theta": math.radians(15.0), "ax": 0.5 * G0,
              "ay": 0.5 * G0, "az": G0, "de": None, "da": None, "dr": None,
              "h": LIMITS["altitude_loss_m"]}
DEFAULT_CONDITION = (1524.0, 46.3)  # trim altitude (m), true airspeed (m/s)
MAX_RATE_HZ = 1000.0  # decision and record rates (Hz)
MAX_DECISIONS = 1_000_000  # decisions per episode (its noise is drawn at reset)
TURBULENCE = ("none", "light")
# light turbulence: MIL-F-8785C Dryden, 15 kt at 20 ft, POE 1e-2 (JSBSim severity 3)
LIGHT = {"turbulence": "milspec", "windspeed_20ft_m_s": 15 * 0.514444, "severity": 3}


def check_one_of(option: str, value: Any, choices: Sequence[str]) -> None:
    """A ValueError naming ``option`` unless ``value`` is one of the strings ``choices``.

    Parameters
    ----------
    option : str
        Option name for the error.
    value : Any
        The given value.
    choices : Sequence[str]
        The allowed strings.
    """
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{option} must be one of {', '.join(map(repr, choices))}; "
                         f"got {value!r}")


def check_positive(option: str, value: Any, most: float = math.inf, zero: bool = False) -> float:
    """``value`` as a finite float in (0, most] ([0, most] with ``zero``), or a ValueError
    naming ``option``.

    Parameters
    ----------
    option : str
        Option name for the error.
    value : Any
        The given value.
    most : float, optional
        Upper bound (inclusive). Default infinity.
    zero : bool, optional
        Allow 0. Default False.

    Returns
    -------
    float
        The value.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if (isinstance(value, bool) or not math.isfinite(v) or not (0.0 <= v if zero else 0.0 < v)
            or not v <= most):
        bound = f"{'>= 0' if zero else '> 0'}" + (f" and <= {most:g}" if most < math.inf else "")
        raise ValueError(f"{option} must be a finite number {bound}; got {value!r}")
    return v


def check_condition(condition: Sequence[float] | None) -> FlightCondition:
    """(altitude m, true airspeed m/s) as a FlightCondition; None: ``DEFAULT_CONDITION``.

    Parameters
    ----------
    condition : Sequence[float] or None
        (altitude m >= 0, true airspeed m/s > 0), or None.

    Returns
    -------
    FlightCondition
        The condition.
    """
    if condition is None:
        return FlightCondition(*DEFAULT_CONDITION)
    try:
        alt, speed = (float(v) for v in condition)
    except (TypeError, ValueError):
        alt = speed = math.nan
    if not (math.isfinite(alt) and alt >= 0.0 and math.isfinite(speed) and speed > 0.0):
        raise ValueError("condition must be (altitude m >= 0, true airspeed m/s > 0), finite; "
                         f"got {condition!r}")
    return FlightCondition(alt, speed)


def check_targets(targets: str | Sequence[str]) -> tuple[str, ...]:
    """The target derivatives: a preset's or the given names, checked.

    Parameters
    ----------
    targets : str or Sequence[str]
        A preset name (``PRESETS``) or distinct derivative names ``C{l,m,n,X,Y,Z}_<variable>``.

    Returns
    -------
    tuple[str, ...]
        The target derivative names.
    """
    if isinstance(targets, str):
        check_one_of("targets", targets, tuple(PRESETS))
        return PRESETS[targets]
    names = tuple(targets) if isinstance(targets, Sequence) else ()
    usage = (f"targets must be {' or '.join(map(repr, PRESETS))} or a non-empty list of "
             f"distinct C{{l,m,n,X,Y,Z}}_{{{','.join(VARIABLES)}}}")
    if not names or not all(isinstance(n, str) for n in names):
        raise ValueError(f"{usage}; got {targets!r}")
    for name in names:
        coef, _, var = name.partition("_")
        if coef not in SIGMA or var not in VARIABLES:
            raise ValueError(f"{usage}; got unsupported target {name!r}")
    if len(set(names)) < len(names):
        raise ValueError(f"{usage}; got a repeated target in {targets!r}")
    return names
