"""Actuator effects written into the flight control system: lag and rate limit after the
component that writes a surface position, deadband, backlash and bias in the linkage,
and the switches that let a record's measured surfaces drive the aircraft."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from flightid.sim.augment.document import (
    COMPONENTS,
    POSITIONS,
    AugmentError,
    Document,
    xml_el,
)
from flightid.sim.effects.airframe import (
    ActuatorBias,
    ActuatorLag,
    AugmentEffect,
    Backlash,
    Deadband,
    RateLimit,
)
from flightid.sim.jsbsim.model import DRIVE, DRIVE_ON

ET.register_namespace("xsi", "http://www.w3.org/2001/XMLSchema-instance")
def _producer(doc: Document, prop: str) -> tuple[Path | None, ET.Element, ET.Element] | None:
    """(system file or None, parent, component) of the FCS component writing ``prop``."""
    for path, root in doc.fcs_roots():
        for parent in root.iter():
            for comp in parent:
                if not isinstance(comp.tag, str) or comp.tag not in COMPONENTS:
                    continue
                outs = [(o.text or "").strip() for o in comp.findall("output")]
                if prop in outs or (not outs and comp.get("name") == prop):
                    return path, parent, comp
    return None


def _reads(comp: ET.Element, prop: str) -> bool:
    return any((i.text or "").strip().lstrip("-") == prop for i in comp.findall("input"))


def _insert_actuator(doc: Document, prop: str, new_input: str | None, children: list[ET.Element],
                     comment: str, stem: str, output: str | None = None) -> bool:
    """Insert an <actuator> after the component writing ``prop``.

    Dynamic (``output`` None): the component now writes ``new_input`` and the actuator
    writes ``prop``. Linkage: the actuator reads ``prop`` and writes ``output``.
    """
    found = _producer(doc, prop)
    if found is None:
        return False
    path, parent, comp = found
    if output is None:
        outs = [o for o in comp.findall("output") if (o.text or "").strip() == prop]
        if outs:
            for o in outs:
                o.text = new_input
        else:
            comp.set("name", new_input)
        src, dst = new_input, prop
    else:
        src, dst = prop, output
    act = xml_el("actuator", xml_el("input", text=src), *children, xml_el("output", text=dst),
              name=f"fcs/augment/{stem}")
    idx = list(parent).index(comp) + 1
    parent.insert(idx, ET.Comment(f" {comment} "))
    parent.insert(idx + 1, act)
    if path is not None:
        doc.changed.add(path)
    return True


def _positions(doc: Document, surface: str) -> list[tuple[str, float]]:
    """The surface's position properties this aircraft writes independently."""
    out = []
    first = POSITIONS[surface][0][0]
    for prop, sign in POSITIONS[surface]:
        found = _producer(doc, prop)
        if found is None:
            continue
        if prop != first and _reads(found[2], first):
            continue  # follows the first (e.g. right aileron = -left): already augmented
        out.append((prop, sign))
    if not out:
        raise AugmentError(f"no FCS component writes {first}")
    return out


def dynamic(doc: Document, surface: str, effects: list[AugmentEffect]) -> None:
    """Actuator dynamics in series with a surface: a lag and a rate limit in the flight
    control system, so that the surface position shows them.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    surface : str
        The surface (``de``, ``da``, ``dr``).
    effects : list of AugmentEffect
        The surface's ``actuator_lag`` (time constant in s) and ``rate_limit`` (rad/s).
    """
    children = []
    for e in effects:
        if isinstance(e, ActuatorLag):
            children.append(xml_el("lag", text=repr(1.0 / e.tau)))
        elif isinstance(e, RateLimit):
            children.append(xml_el("rate_limit", text=repr(e.rate)))
    what = "; ".join(e.label() for e in effects)
    for prop, _ in _positions(doc, surface):
        stem = prop.removeprefix("fcs/").removesuffix("-pos-rad")
        _insert_actuator(doc, prop, f"fcs/augment/{stem}-pos-rad-unaugmented", children,
                         f"added by flightid augment: {what} (actuator dynamics, in series; "
                         f"the surface position shows them)", f"{stem}-actuator")


def linkage(doc: Document, surface: str, effects: list[AugmentEffect]) -> None:
    """A linkage between a surface's position and the aerodynamics: a deadband, backlash
    (hysteresis) and a bias, which the aerodynamic terms read and the position does not show.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    surface : str
        The surface (``de``, ``da``, ``dr``).
    effects : list of AugmentEffect
        The surface's ``deadband`` and ``backlash`` (widths in rad) and ``actuator_bias`` (rad).
    """
    what = "; ".join(e.label() for e in effects)
    aero = doc.aero()
    for prop, sign in POSITIONS[surface]:
        if not any((el.text or "").strip() == prop for el in aero.iter()
                   if el.tag in ("property", "independentVar")):
            continue
        stem = prop.removeprefix("fcs/").removesuffix("-pos-rad")
        out = f"fcs/augment/{stem}-aero-rad"
        children = []
        for e in effects:
            if isinstance(e, Deadband):
                children.append(xml_el("deadband_width", text=repr(e.width)))
            elif isinstance(e, Backlash):
                children.append(xml_el("hysteresis_width", text=repr(e.width)))
            elif isinstance(e, ActuatorBias):
                children.append(xml_el("bias", text=repr(sign * e.bias)))
        if not _insert_actuator(doc, prop, None, children,
                                f"added by flightid augment: {what} (linkage between the "
                                f"measured surface position and the surface the air sees)",
                                f"{stem}-linkage", output=out):
            raise AugmentError(f"no FCS component writes {prop}")
        for el in aero.iter():
            if el.tag in ("property", "independentVar") and (el.text or "").strip() == prop:
                el.text = out
        aero.insert(0, ET.Comment(f" flightid augment: the aerodynamics read {out} "
                                  f"(the linkage output) instead of {prop} "))


def surface_drive_switches(doc: Document) -> None:
    """A switch behind each surface position: the FCS's value, or the drive when on.

    Parameters
    ----------
    doc : Document
        The aircraft being augmented; changed in place.

    Raises
    ------
    AugmentError
        When a surface position is written outside <flight_control> and <system>.
    """
    declared = False
    for surface, drive in DRIVE.items():
        for prop, sign in _positions(doc, surface):
            path, parent, comp = _producer(doc, prop)  # type: ignore[misc]
            stem = prop.removeprefix("fcs/").removesuffix("-pos-rad")
            fcs_value = f"fcs/drive/{stem}-fcs-rad"
            outs = [o for o in comp.findall("output") if (o.text or "").strip() == prop]
            for o in outs:
                o.text = fcs_value
            if not outs:
                comp.set("name", fcs_value)
            source = drive
            added = []
            if sign != 1.0:
                source = f"fcs/drive/{stem}-rad"
                added.append(xml_el("pure_gain", xml_el("input", text=drive),
                                 xml_el("gain", text=repr(sign)), name=source))
            test = xml_el("test", text=f"{DRIVE_ON} GE 0.5", logic="AND", value=source)
            added.append(xml_el("switch", xml_el("default", value=fcs_value), test,
                             xml_el("output", text=prop), name=f"fcs/drive/{stem}-switch"))
            idx = list(parent).index(comp) + 1
            parent.insert(idx, ET.Comment(f" added by flightid augment: {prop} follows "
                                          f"{drive} while {DRIVE_ON} is 1 "))
            for k, el in enumerate(added):
                parent.insert(idx + 1 + k, el)
            if path is not None:
                doc.changed.add(path)
            if not declared:  # the drive's properties, declared where the FCS is
                section = (doc.root.find("flight_control") if path is None
                           else doc.systems[path].getroot())
                if section is None:
                    raise AugmentError(f"{prop} is written outside <flight_control> and "
                                       "<system>: the surface drive cannot be declared")
                props = [xml_el("property", text=p, value="0") for p in (DRIVE_ON, *DRIVE.values())]
                for k, el in enumerate(props):
                    section.insert(k, el)
                declared = True


