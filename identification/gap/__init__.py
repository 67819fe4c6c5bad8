"""Sim-to-real gap diagnosis: where a JSBSim model departs from flight data, which effect
of the catalogue causes it, and how far the gap shrinks on held-out data.

``model`` (the model under test: the aircraft linearised at the record's condition, with
its actuators on a record of commands), ``segments`` (maneuver windows), ``fit`` (output
error or filter error on one window), ``verdict`` (is there a gap), ``residual_map``
(where the gap lies), ``candidates`` (the catalogue's entries as candidates, their physical
ranges and equivalence classes), ``rank`` (which effect), ``turbulence`` (the leading
candidates judged with the turbulence modelled), ``sequence`` (several effects, and how far
the gap shrinks), ``jsbsim`` (the corrected aircraft written, refined and flown again),
``diagnosis`` (all of it: ``diagnose``), ``report`` (HTML); ``envelope`` (records from
several conditions: each diagnosed at its own, where in the envelope the model departs)
and ``trend`` (a derivative error's trend over the conditions).
"""

from flightid.identification.gap.diagnosis import GapResult, diagnose
from flightid.identification.gap.envelope import EnvelopeResult, envelope
from flightid.identification.gap.jsbsim.write import write_aircraft

__all__ = ["EnvelopeResult", "GapResult", "diagnose", "envelope", "write_aircraft"]
