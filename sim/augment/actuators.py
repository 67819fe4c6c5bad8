"""The surface actuators of a JSBSim aircraft as its XML declares them.

A record of surface *commands* (docs/record.md, ``meta.extra["surfaces"]``) passes through
the aircraft's own actuators before the aerodynamics see it; a model of that record needs
them. ``actuator_lags`` reads the first-order lag of each ``<actuator>`` that writes a
surface position (``fcs/elevator-pos-rad``, ``fcs/left-aileron-pos-rad``,
``fcs/rudder-pos-rad``): JSBSim's ``<lag>`` is the break frequency C1 of C1/(s + C1) (JSBSim
reference manual, FGActuator), so the time constant is 1/C1. Actuators in series (an
augmented aircraft's added lag after the original) add their time constants (the
low-frequency sum of two first-order lags). ``actuator_chains`` reads each actuator's lag
and ``<rate_limit>`` (rad/s) in series, for a model that runs them as JSBSim does.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from flightid.sim.augment.document import POSITIONS
from flightid.sim.jsbsim.model import locate

MAX_CHAIN = 8  # actuators followed in series


@dataclass(frozen=True)
class Actuator:
    """One JSBSim ``<actuator>``: its first-order lag's time constant (s; 0 without a
    ``<lag>``) and its rate limit (rad/s; inf without a ``<rate_limit>``)."""

    tau: float = 0.0
    rate_limit: float = math.inf


def _number(text: str | None, default: float) -> float:
    """A plain number of the XML, else ``default`` (a property-valued rate limit is not
    read here)."""
    try:
        return float(text) if text is not None else default
    except ValueError:
        return default


def actuator_chains(aircraft: str) -> dict[str, list[Actuator]]:
    """Per surface, the ``<actuator>`` elements writing its position in the aircraft's XML.

    In series from the command to the position; [] for a surface without one (or an FCS kept
    in a separate systems file).

    Parameters
    ----------
    aircraft : str
        A project name, stock JSBSim name or XML path.

    Returns
    -------
    dict of str to list of Actuator
        Chain by surface (``de``, ``da``, ``dr``); each Actuator's lag time constant (s) and
        rate limit (rad/s).
    """
    _, xml, _ = locate(aircraft)
    root = ET.parse(xml).getroot()
    writers = {}
    for act in root.iter("actuator"):
        out = act.findtext("output")
        if out:
            writers[out.strip()] = act
    chains = {}
    for surface, props in POSITIONS.items():
        prop, chain = props[0][0], []
        for _ in range(MAX_CHAIN):
            act = writers.get(prop)
            if act is None:
                break
            lag = _number(act.findtext("lag"), 0.0)
            limit = _number(act.findtext("rate_limit"), math.inf)
            chain.append(Actuator(1.0 / lag if lag > 0 else 0.0,
                                  limit if limit > 0 else math.inf))
            prop = (act.findtext("input") or "").strip().lstrip("-")
        chains[surface] = chain[::-1]
    return chains


def actuator_lags(aircraft: str) -> dict[str, float]:
    """Per surface, the time constant of the actuator lags writing its position.

    Taken from :func:`actuator_chains`; lags in series add.

    Parameters
    ----------
    aircraft : str
        A project name, stock JSBSim name or XML path.

    Returns
    -------
    dict of str to float
        Time constant (s) by surface (``de``, ``da``, ``dr``); 0 for a surface without one.
    """
    return {s: sum((a.tau for a in chain), 0.0) for s, chain in actuator_chains(aircraft).items()}
