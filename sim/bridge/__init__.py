"""The MAVLink/serial recorder bridge: a simulated flight carried the way an onboard
recorder would carry it (as on the Monash Boomerang 60 UAV, c. 2008), and the ground side
that records and converts it.

Both sides: ``messages`` (MAVLink 2 encoding of canonical channels and its inverse),
``frames`` (resynchronising frame scanner, .tlog files), ``link`` (serial, pty and UDP
links and their faults).
Air side (``air/``): ``serve`` (stream a FlightRecord or fly a simulation in the loop),
``schedule`` (recorder streams and the link budget), ``signing`` (who may send controls:
the ground station's ids, MAVLink 2 signing), ``dataflash`` and ``ulog`` (the onboard
log of the same flight as an ArduPilot DataFlash or PX4 ULog file).
Ground side (``ground/``): ``recording`` (record a stream), ``sources`` (per-source
sequence losses), ``tlog`` (convert a tlog to a FlightRecord, without importing the air
side), ``gaps`` (its time base and the gaps too long to interpolate), ``align`` (clock
alignment of separately clocked recorders).
``loopback`` joins both sides on this machine.

The package imports nothing itself: import the module that holds what you need, e.g.
``from flightid.sim.bridge.air.serve import serve_record``. The command line for it lives
in ``flightid.cli.bridge``.
"""
