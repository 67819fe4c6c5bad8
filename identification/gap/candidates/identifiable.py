"""The catalogue entries that are not candidates for a record, each with the reason and
what would make it identifiable (``not_identifiable``). Every entry of the catalogue is
either a candidate (``build.catalogue_candidates``) or listed here; a test holds the
whole catalogue to it.
"""

from __future__ import annotations

from collections.abc import Sequence

from flightid.identification.gap.candidates.build import catalogue_candidates
from flightid.identification.gap.lines import ENTRY as LINE_ENTRY
from flightid.identification.gap.model.surfaces import SURFACES_KEY, surfaces_of
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord
from flightid.sim.effects.catalogue import CATALOGUE, ActsOn

COMMANDS = (f"a record of the commands (meta.extra[{SURFACES_KEY!r}] = 'command', or the "
            "surfaces='command' option) makes it identifiable")
BIAS = ("a constant offset is absorbed by the model's output and state biases (trim "
        "offsets, fitted on every window)")
# the IMU channels the spectral-line check (gap.lines) reads on either axis
LINE_CHANNELS = ("ax", "ay", "az", "p", "q", "r")
# the entries that are never candidates of the linear screening, and why
ALWAYS: dict[str, str] = {
    "noise": "white noise is no model error: it is the null level the gap is tested "
             "against (the output-error fit estimates its covariance)",
    "bias": BIAS + "; the trim-level check (gap.trim_level: the steady span before the "
            "first maneuver against the model's trim at the measured airspeed and "
            "altitude) names an alpha bias as 'alpha bias or CL_0 mismatch', a beta bias "
            "as 'beta bias or CY_0 / asymmetry' (the axis's 'trim' in the json)",
    "drift": "a slow ramp is taken mostly by each window's biases and initial state; a "
             "record long against 1/rate (a drift of 0.002/s over 60 s) with a ramp input "
             "would make it identifiable",
    "random_walk": "a random bias walk is a slow disturbance, absorbed per window like a "
                   "bias; a filter-error model with a bias state would make it identifiable",
    "quantize": "rounding to a count is white-noise-like below one count: part of the "
                "null level",
    "saturate": "clipping is nonlinear (the residual sits at the largest excursions: the "
                "gap map's regimes show it); not in the linear screening",
    "second_order": "in the rigid-body band a fast sensor mode is a delay of 2 zeta/wn: "
                    "the delay or lag candidate of the channel stands for it",
    "lowpass": "in the rigid-body band a low-pass filter is a delay of its group delay: "
               "the delay or lag candidate of the channel stands for it",
    "sample": "sampling and aliasing act above the rigid-body band the linear model fits",
    "wind": "a steady wind leaves the air-relative motion unchanged; the ground-relative "
            "velocities (GPS) against the airspeed would make it identifiable",
    "gust": "a discrete gust is an unmeasured input in one time span (the gap map's "
            "regimes show it); not a model error",
    "turbulence": "turbulence is no model error: it is part of the null level (process "
                  "noise)",
    "rate_limit": "a candidate on records of commands only (gap.candidates.linkage): on "
                  "a record of positions the limit has already acted on what was recorded",
    "deadband": "a candidate on the aileron and rudder (gap.candidates.linkage); the "
                "elevator is trimmed away from zero, where a deadband is a constant "
                "offset: the trim-level check's 'elevator bias, Cm_0 mismatch or tail "
                "effectiveness'",
    "backlash": "a candidate on the model's surface inputs (gap.candidates.linkage); the "
                "model has none",
    "actuator_bias": BIAS + "; the trim-level check (gap.trim_level) names a surface's "
                     "steady deflection against the model's trim one as 'elevator bias, "
                     "Cm_0 mismatch or tail effectiveness', 'aileron bias or Cl_0 "
                     "mismatch' or 'rudder bias or Cn_0 mismatch' (on a record of "
                     "positions, a rigging offset between the measured and the "
                     "aerodynamic deflection or the model's zero moment; on a record of "
                     "commands, an actuator bias or that mismatch)",
}
# the condition-dependent delta: a model linearised at one condition holds one value of it
TABLE = ("a delta that changes with airspeed or alpha: at one condition it is the "
         "derivative_delta of the derivative there (named as such); records at several "
         "conditions (flightid gap over them: identification.gap.envelope) fit its table "
         "and name it with its trend")
# the link and clock entries act on the bytes and time stamps of a telemetry link
LINK = ("acts on the telemetry link's packets or time stamps, not on the values of a "
        "decoded record; the bridge's own statistics (packets lost, CRC failures, arrival "
        "times) show it")
MISALIGNMENT = {
    "x": "a rotation about x mixes q into r and az into ay: the lateral model carries "
         "neither q nor az, the longitudinal neither r nor ay; a coupled six-degree-of-"
         "freedom model would make it identifiable",
    "z": "a rotation about z mixes q into p and ax into ay: neither axis's model carries "
         "both; a coupled six-degree-of-freedom model would make it identifiable",
}


def _reason(name: str, model: LinearModel, surfaces: str) -> str:
    entry = CATALOGUE[name]
    if entry.acts_on in (ActsOn.LINK, ActsOn.CLOCK):
        return LINK
    if name in ALWAYS:
        return ALWAYS[name]
    if name == "actuator_lag":
        if surfaces == "position":
            return ("the record's surfaces are positions: the actuator has already acted "
                    "on what was recorded; " + COMMANDS)
        return "the model has no surface input"
    if name == LINE_ENTRY:
        return (f"needs the IMU channels {', '.join(LINE_CHANNELS)} (gap.lines: a "
                "narrowband line on them, above the rigid-body band); a record with "
                "them makes it identifiable")
    if name == "derivative_table":
        return TABLE
    if name == "tail_ice":
        return ("tail ice acts on the pitching moment: the lateral axis does not carry it; "
                "a record with elevator maneuvers (the longitudinal axis) makes it "
                "identifiable")
    if name == "thrust_moment":
        return ("the model has no thrust input: a record with the measured thrust "
                "(channel 'thrust', N) on the longitudinal axis makes it identifiable")
    if name == "misalignment":
        return ("a rotation about y mixes p and r: a model with both outputs (the lateral "
                "axis) makes it identifiable")
    if name in ("lever_arm", "vanes", "scale", "delay", "lag"):
        return (f"the model has none of the outputs {name} acts on; a record with them "
                "makes it identifiable")
    return "the model carries none of the terms it changes"


def not_identifiable(model: LinearModel, records: Sequence[FlightRecord] = (), *,
                     surfaces: str | None = None) -> dict[str, str]:
    """Every catalogue entry (or entry with options, e.g. ``misalignment(x)``) that is not
    a candidate for ``model`` (the linearised aircraft of one axis, with the outputs the
    ``records`` carry), with the reason and what would make it identifiable.
    ``surfaces``: what the records' surface channels hold ("position" or "command"; None:
    their metadata).

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.
    records : sequence of FlightRecord
        The records.
    surfaces : str or None
        "position" or "command" (None: the records' metadata).

    Returns
    -------
    dict of str to str
        Entry (or entry with options) -> the reason, and what would make it identifiable.
    """
    kind = surfaces_of(records, surfaces)
    found = {c.entry for c in catalogue_candidates(model, surfaces=kind)}
    if any(all(c in r for c in LINE_CHANNELS) for r in records):  # the line check runs
        found.add(LINE_ENTRY)
    out = {name: _reason(name, model, kind) for name in CATALOGUE if name not in found}
    out.update({f"misalignment({axis})": why for axis, why in MISALIGNMENT.items()})
    return out
