"""Readers of flight data that flightid did not write: delimited text with its own column
names and units (``ascii``), ArduPilot DataFlash logs (``dataflash``) and PX4 ULog files
(``ulog``), each turned into a FlightRecord in SI units under the canonical channel names,
through a column map (``mapping``) or a servo mapping (``servos``) and the aircraft's
constants (``constants``). They sit with the
record readers at the bottom layer; the unit check and the time-base re-grid that every
command applies are the command line's (``flightid import``).
"""
