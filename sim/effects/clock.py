"""Recorder clocks (catalogue ``clock``): the time stamps a separately clocked recorder writes.

The bridge already models them (``flightid.sim.bridge.air.schedule.StreamSpec``): a recorder
stream stamps its messages with its own clock, t_local = clock_offset + (1 +
clock_drift) t (the three recorders of the Monash Boomerang 60 paper, c. 2008;
``boomerang()`` gives each its own), and the ground side aligns them again
(``flightid.sim.bridge.ground.align.ClockMap``, the same parametrisation). The catalogue's
``clock`` entry names that class and maps its parameters ``offset`` (s) and ``drift``
(fraction) to ``clock_offset`` and ``clock_drift``.
"""

from __future__ import annotations

from flightid.sim.effects.base import ExternalImplementation

RECORDER_CLOCK = ExternalImplementation(
    "flightid.sim.bridge.air.schedule:StreamSpec",
    (("offset", "clock_offset"), ("drift", "clock_drift")),
    "dataclasses.replace(stream, clock_offset=..., clock_drift=...) for a recorder stream "
    "of BridgeConfig.streams",
)
