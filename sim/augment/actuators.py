"""The surface actuators of a JSBSim aircraft as its XML declares them.

A record of surface *commands* (docs/record.md, ``meta.extra["surfaces"]``) passes through
the aircraft's own actuators before the aerodynamics see it; a model of that record needs
them. ``actuator_lags`` reads the first-order lag of each ``<actuator>`` that writes a
surface position (``fcs/elevator-pos-rad``, ``fcs/left-aileron-pos-rad``,
``fcs/rudder-pos-rad``): JSBSim's ``<lag>`` is the break frequency C1 of C1/(s + C1) (JSBSim
reference manual, FGActuator), so the time constant is 1/C1. Actuators in series (an
augmented aircraft's added lag after the original) add their time constants (the
low-frequency sum of two first-order lags). Rate limits are nonlinear and not read here.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from flightid.sim.augment.writer import POSITIONS
from flightid.sim.jsbsim.model import locate

MAX_CHAIN = 8  # actuators followed in series


def actuator_lags(aircraft: str) -> dict[str, float]:
    """Per surface (``de``, ``da``, ``dr``): the time constant (s) of the actuator lags
    writing its position in ``aircraft``'s XML (a project name, stock JSBSim name or XML
    path); 0 for a surface without one (or an FCS kept in a separate systems file)."""
    _, xml, _ = locate(aircraft)
    root = ET.parse(xml).getroot()
    writers = {}
    for act in root.iter("actuator"):
        out = act.findtext("output")
        if out:
            writers[out.strip()] = act
    lags = {}
    for surface, props in POSITIONS.items():
        prop, tau = props[0][0], 0.0
        for _ in range(MAX_CHAIN):
            act = writers.get(prop)
            if act is None:
                break
            lag = act.findtext("lag")
            if lag is not None and float(lag) > 0:
                tau += 1.0 / float(lag)
            prop = (act.findtext("input") or "").strip().lstrip("-")
        lags[surface] = tau
    return lags
