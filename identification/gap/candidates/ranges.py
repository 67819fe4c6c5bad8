"""Physical ranges: a candidate whose fitted parameters leave the range the catalogue
states is not the mechanism it is named after, and ``out_of_range`` names the family
that fits instead.

The ranges are the catalogue's (``flightid.sim.effects.catalogue``): each parameter's
allowed range (tail ice only reduces: factors in (0, 1]; a delay or lag is >= 0; a CG
shift within 0.5 m; ...) and, for a ``derivative_delta``, the range of the derivative it
moves the model's value to (``DERIVATIVE_RANGES``: what an airframe can have). On the
NASA longitudinal records a ``tail_ice`` with an elevator factor of 1.38 fits (a tail more
effective than the model, which ice cannot produce): that is "horizontal-tail
effectiveness +38 %", and a Cm_alphadot delta of +19.7 is dynamics the model lacks.
"""

from __future__ import annotations

from collections.abc import Mapping

from flightid.identification.gap.model.edits import Candidate
from flightid.identification.models.linear import LinearModel
from flightid.sim.effects.catalogue import CATALOGUE, DERIVATIVE_RANGES

# the tail-ice factors outside (0, 1]: what the fitted scaling is then
TAIL_FAMILY = {"elevator": "horizontal-tail effectiveness (Cm_de)",
               "stability": "horizontal-tail stability contribution (Cm_alpha)",
               "damping": "pitch damping (Cm_q, Cm_alphadot)"}
RATE_TERMS = ("_p", "_q", "_r", "_alphadot")
# an inertial sensor's scale (rate gyros, attitude, accelerometers) within this range; the
# catalogue's (0, 2] is for flow angles, whose vane K with upwash is 1.0-1.3 (Morelli &
# Klein 2016 sec. 10.2). A gyro calibrated to a few per cent that reads 1.5 times the rate
# is a mapping or unit error, or the model's dynamics: on the NASA record against the stock
# DHC6, scale(p) 1.49 and scale(phi) 1.40 together are the roll response, not two sensors
INERTIAL = ("p", "q", "r", "phi", "theta", "psi", "ax", "ay", "az")
INERTIAL_SCALE = (0.75, 1.33)


def _percent(factor: float) -> str:
    return f"{(factor - 1.0) * 100:+.0f} %"


def derivative_outside(name: str, value: float) -> str | None:
    """None when the derivative ``name`` at ``value`` (per rad, or per unit nondimensional
    rate) is inside ``DERIVATIVE_RANGES`` (or has no range there); else why not.

    Parameters
    ----------
    name : str
        The derivative, e.g. "Cn_beta".
    value : float
        Its value, per rad (or per unit nondimensional rate).

    Returns
    -------
    str or None
        None inside the range; else the value, the range and what fits instead.
    """
    if name not in DERIVATIVE_RANGES:
        return None
    lo, hi = DERIVATIVE_RANGES[name]
    if lo <= value <= hi:
        return None
    what = ("dynamics the model lacks (a lag or delay of a sensor or actuator) fitted as a "
            "damping term" if name.endswith(RATE_TERMS) else
            "a change no airframe has: a sensor scale or the wrong aircraft data")
    return f"{name} {value:+.3g} is outside [{lo:g}, {hi:g}]: {what}"


def _derivative(cand: Candidate, delta: float, model: LinearModel | None) -> str | None:
    name = cand.options["derivative"]
    if model is None or name not in model.start:
        return None
    return derivative_outside(name, model.start[name] + delta)


def _family(cand: Candidate, name: str, value: float) -> str:
    """What a parameter ``name`` of ``cand`` at ``value`` (outside its range) is."""
    entry, opts = cand.entry, cand.options
    if entry == "tail_ice":
        return (f"{TAIL_FAMILY[name]} {_percent(value)}" if value > 1.0
                else f"{TAIL_FAMILY[name]} reversed (factor {value:.3g})")
    if entry == "scale":
        ch = opts["channel"]
        return (f"a sign error of {ch} (factor {value:.3g})" if value <= 0.0
                else f"a unit or gain error of {ch} (x{value:.3g})")
    if entry in ("delay", "lag", "actuator_lag"):
        ch = opts.get("channel") or opts.get("surface")
        return f"{ch} leads the model by {-value:.3g} s: a model lag, not a {entry}"
    if entry == "control_effectiveness":
        return f"a reversal of {opts['surface']} (factor {value:.3g})"
    if entry == "mass_scale":
        return f"every force derivative scaled by {1.0 / value:.3g}, not a mass error"
    if entry == "inertia_scale":
        coef = {"ixx": "rolling", "iyy": "pitching", "izz": "yawing"}[name]
        return f"the {coef}-moment derivatives scaled by {1.0 / value:.3g}, not an inertia error"
    if entry == "cg_offset":
        return (f"moment derivatives changed by the force derivatives times {value:+.3g} m: "
                "a derivative change, not a CG shift")
    if entry == "misalignment":
        return f"a roll-yaw rate coupling of {value:+.3g} rad, not a mounting error"
    if entry == "thrust_moment":
        return f"a thrust-dependent pitching moment of {value:+.3g} m (propwash, not the line)"
    return f"{entry}.{name} {value:.4g}"


def out_of_range(candidate: Candidate, parameters: Mapping[str, Mapping[str, float]],
                 model: LinearModel | None = None) -> str | None:
    """None when every fitted parameter of ``candidate`` (``parameters`` in catalogue units:
    {name: {"value", ...}}, as ``Candidate.parameters`` gives them) is in the catalogue's
    physical range; else the family that fits, e.g. "horizontal-tail effectiveness +38 %"
    for a ``tail_ice`` elevator factor of 1.38. ``model``: the linear model the deltas are
    relative to (a ``derivative_delta`` is checked as the derivative it makes).

    Parameters
    ----------
    candidate : Candidate
        The candidate (a pair's parts each checked).
    parameters : mapping
        Its fitted parameters in catalogue units, {name: {"value", ...}}.
    model : LinearModel or None
        The model a derivative delta is relative to.

    Returns
    -------
    str or None
        None inside the range; else the family that fits.
    """
    if candidate.parts:
        found = []
        for p in candidate.parts:
            prefix = f"{p.label}."
            own = {k[len(prefix):]: v for k, v in parameters.items() if k.startswith(prefix)}
            if (f := out_of_range(p, own, model)) is not None:
                found.append(f)
        return "; ".join(found) or None
    if candidate.entry == "derivative_delta":
        return _derivative(candidate, float(parameters["delta"]["value"]), model)
    entry = CATALOGUE[candidate.entry]
    if candidate.entry == "scale" and candidate.options.get("channel") in INERTIAL:
        value = float(parameters["factor"]["value"])
        lo, hi = INERTIAL_SCALE
        if not lo <= value <= hi:
            return (f"{candidate.options['channel']} x{value:.3g} is outside the "
                    f"[{lo:g}, {hi:g}] of a calibrated inertial sensor: the model's "
                    "response, or a unit or mapping error")
    found = []
    for name, v in parameters.items():
        value = float(v["value"])
        if not entry.parameter(name).allows(value):
            found.append(_family(candidate, name, value))
    return ", ".join(found) or None
