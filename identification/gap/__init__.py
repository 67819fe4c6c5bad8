"""Sim-to-real gap diagnosis: where a JSBSim model departs from flight data, which effect
of the catalogue causes it, and how far the gap shrinks on held-out data.

``linearise`` (the model at the record's condition), ``segments`` (maneuver windows),
``fit`` (output error on one window), ``where`` (gap map), ``candidates`` and ``rank``
(which effect; the families in ``sensor_candidates``, ``actuator_candidates`` and
``mass_candidates`` on ``effect_model``; ``identifiable`` the entries that are not
candidates, ``ranges`` the physical ranges, ``classes`` the equivalence classes),
``shrink`` (how far), ``correct`` (the corrected aircraft), ``diagnose`` (all of it),
``report`` (HTML); ``envelope`` (records from several conditions: each diagnosed at
its own, where in the envelope the model departs, and a derivative error's trend).
"""

from flightid.identification.gap.correct import write_aircraft
from flightid.identification.gap.diagnose import GapResult, diagnose
from flightid.identification.gap.envelope import EnvelopeResult, envelope

__all__ = ["EnvelopeResult", "GapResult", "diagnose", "envelope", "write_aircraft"]
