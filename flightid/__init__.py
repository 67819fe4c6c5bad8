"""flightid: a testbed for aircraft system identification.

The folders are the architecture (DESIGN.md): ``aircraft`` (JSBSim definitions and
truth files), ``sim`` (JSBSim flight core, truth, sensors, disturbances, bridge),
``identification`` (estimation methods), ``scenarios`` (inputs, flight cards, CLI).
They install as ``flightid.aircraft``, ``flightid.sim``, ``flightid.identification``
and ``flightid.scenarios``; this package holds the shared types: the flight record,
channel and derivative names, and unit conversions.
"""

__version__ = "0.1.0"
