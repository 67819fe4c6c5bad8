"""The aircraft document an augmentation edits: the main JSBSim XML plus the system files
it references (copied beside it), and small element builders."""

from __future__ import annotations

import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

from flightid.sim.jsbsim.model import PACKAGE_ENGINES, PACKAGE_SYSTEMS

ET.register_namespace("xsi", "http://www.w3.org/2001/XMLSchema-instance")
FT_PER_M = 1 / 0.3048
LENGTH_TO_M = {"IN": 0.0254, "FT": 0.3048, "M": 1.0, "MM": 0.001}
MASS_KEYWORD = {"de": "elevator", "da": "aileron", "dr": "rudder"}
# surface -> (position properties, sign of each to the project convention)
POSITIONS = {"de": (("fcs/elevator-pos-rad", 1.0),),
             "da": (("fcs/left-aileron-pos-rad", -1.0), ("fcs/right-aileron-pos-rad", 1.0)),
             "dr": (("fcs/rudder-pos-rad", 1.0),)}
COMPONENTS = ("actuator", "aerosurface_scale", "pure_gain", "summer", "fcs_function",
              "switch", "kinematic", "lag_filter", "lead_lag_filter", "scheduled_gain",
              "deadband", "filter", "integrator", "washout_filter", "second_order_filter")



class AugmentError(ValueError):
    """The aircraft cannot take an effect (its XML lacks what the effect needs)."""


def parse_xml(path: Path) -> ET.ElementTree:
    """A JSBSim XML file parsed with its comments kept.

    Parameters
    ----------
    path : Path
        The XML file.

    Returns
    -------
    ElementTree
        The parsed tree.
    """
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    return ET.parse(path, parser)


class Document:
    def __init__(self, xml: Path, dest: Path) -> None:
        self.tree = parse_xml(xml)
        self.root = self.tree.getroot()
        self.dest = dest
        self.systems: dict[Path, ET.ElementTree] = {}
        self._copy_support(xml)
        self.changed: set[Path] = set()

    def _copy_support(self, xml: Path) -> None:
        """Engine, thruster and system files JSBSim finds only in its package: copy them."""
        for tag, sub, package in (("engine", "Engines", PACKAGE_ENGINES),
                                  ("thruster", "Engines", PACKAGE_ENGINES),
                                  ("system", "Systems", PACKAGE_SYSTEMS)):
            for el in self.root.iter(tag):
                f = el.get("file")
                if not f:
                    continue
                fname = f if f.endswith(".xml") else f"{f}.xml"
                here = self.dest / sub / fname
                if tag == "system":
                    if not here.is_file() and (package / fname).is_file():
                        here.parent.mkdir(exist_ok=True)
                        shutil.copy2(package / fname, here)
                    if here.is_file():
                        self.systems[here] = parse_xml(here)
                elif not here.is_file() and (package / fname).is_file():
                    here.parent.mkdir(exist_ok=True)
                    shutil.copy2(package / fname, here)

    def fcs_roots(self) -> list[tuple[Path | None, ET.Element]]:
        return [(None, self.root), *((p, t.getroot()) for p, t in self.systems.items())]

    def write(self, path: Path) -> None:
        self.tree.write(path, encoding="utf-8", xml_declaration=True)
        for p in self.changed:
            self.systems[p].write(p, encoding="utf-8", xml_declaration=True)

    def aero(self) -> ET.Element:
        el = self.root.find("aerodynamics")
        if el is None:
            raise AugmentError(f"{self.root.get('name')}: no <aerodynamics> section")
        return el

    def frames(self) -> tuple[str, str]:
        """(force frame: wind, body or stability; moment frame: body or stability)."""
        names = {a.get("name", "").upper(): a.get("frame", "BODY").upper()
                 for a in self.aero().findall("axis")}
        if names.keys() & {"LIFT", "DRAG", "SIDE"}:
            force = "wind"
        elif names.keys() & {"AXIAL", "NORMAL"}:
            raise AugmentError("AXIAL/NORMAL force axes are not supported")
        else:
            force = "stability" if names.get("X", names.get("Z", "BODY")) == "STABILITY" \
                else "body"
        moment = "stability" if names.get("ROLL", names.get("YAW", "BODY")) == "STABILITY" \
            else "body"
        return force, moment

    def axis(self, name: str) -> ET.Element:
        for a in self.aero().findall("axis"):
            if a.get("name", "").upper() == name:
                return a
        frames = self.frames()
        a = ET.SubElement(self.aero(), "axis", {"name": name})
        frame = frames[1] if name in ("ROLL", "PITCH", "YAW") else frames[0]
        if frame == "stability":
            a.set("frame", "STABILITY")
        return a

    def add_term(self, axis: str, comment: str, fn: ET.Element) -> None:
        a = self.axis(axis)
        a.append(ET.Comment(f" {comment} "))
        a.append(fn)


def xml_el(tag: str, *children: ET.Element, text: str | None = None, **attrs: str) -> ET.Element:
    """An XML element.

    Parameters
    ----------
    tag : str
        The element's tag.
    *children : Element
        Its children, in order.
    text : str or None
        Its text.
    **attrs : str
        Its attributes.

    Returns
    -------
    Element
        The element.
    """
    e = ET.Element(tag, attrs)
    e.text = text
    e.extend(children)
    return e


def prop_el(p: str) -> ET.Element:
    """A JSBSim ``<property>`` element.

    Parameters
    ----------
    p : str
        The property's name (``aero/alpha-rad``).

    Returns
    -------
    Element
        The element.
    """
    return xml_el("property", text=p)


def val_el(v: float) -> ET.Element:
    """A JSBSim ``<value>`` element holding a number exactly (``repr``).

    Parameters
    ----------
    v : float
        The number.

    Returns
    -------
    Element
        The element.
    """
    return xml_el("value", text=repr(float(v)))


def trig_el(kind: str) -> ET.Element:
    """A JSBSim trigonometric function of alpha (``<sin>``, ``<cos>``, ...).

    Parameters
    ----------
    kind : str
        The function's tag.

    Returns
    -------
    Element
        The element, reading ``aero/alpha-rad``.
    """
    return xml_el(kind, prop_el("aero/alpha-rad"))


