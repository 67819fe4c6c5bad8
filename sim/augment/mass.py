"""Mass effects written into the ``<mass_balance>`` section: CG offset, mass and inertia
scales, and the thrust moment term."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from flightid.sim.augment.document import (
    FT_PER_M,
    LENGTH_TO_M,
    AugmentError,
    Document,
    prop_el,
    val_el,
    xml_el,
)
from flightid.sim.effects.airframe import (
    CgOffset,
    InertiaScale,
    MassScale,
    ThrustMoment,
)

ET.register_namespace("xsi", "http://www.w3.org/2001/XMLSchema-instance")
def _mass_balance(doc: Document) -> ET.Element:
    mb = doc.root.find("mass_balance")
    if mb is None:
        raise AugmentError("no <mass_balance> section")
    return mb


def _scale_text(el: ET.Element, factor: float, why: str, parent: ET.Element) -> None:
    old = float(el.text)
    el.text = f" {old * factor!r} "
    idx = list(parent).index(el)
    parent.insert(idx, ET.Comment(f" {why}: {el.tag} {old:g} x {factor:.6g} "))


def cg_offset(doc: Document, e: CgOffset) -> None:
    """Move every location of the mass balance (the empty-weight CG, the point masses) and
    of the tanks by the effect's offset, which moves the CG by the same amount.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : CgOffset
        The effect: ``x`` (m forward) and ``z`` (m down).
    """
    mb = _mass_balance(doc)
    locations = [loc for loc in mb.iter("location")]
    prop = doc.root.find("propulsion")
    if prop is not None:
        locations += [loc for tank in prop.iter("tank") for loc in tank.iter("location")]
    for loc in locations:
        unit = LENGTH_TO_M[loc.get("unit", "IN").upper()]
        for axis, d in (("x", e.x), ("z", e.z)):  # structural frame: x aft, z up
            c = loc.find(axis)
            if c is not None and d:
                c.text = f" {float(c.text) - d / unit!r} "
        loc.insert(0, ET.Comment(f" moved by flightid augment: cg_offset x {e.x:+g} m forward, "
                                 f"z {e.z:+g} m down (every mass item) "))


def mass_scale(doc: Document, e: MassScale) -> None:
    """Scale the empty weight and every point mass by a factor.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : MassScale
        The effect: the factor (dimensionless).
    """
    mb = _mass_balance(doc)
    why = "flightid augment: mass_scale (mass error)"
    for el in [mb.find("emptywt"), *(pm.find("weight") for pm in mb.iter("pointmass"))]:
        if el is not None:
            parent = mb if el.tag == "emptywt" else next(
                pm for pm in mb.iter("pointmass") if el in list(pm))
            _scale_text(el, e.factor, why, parent)


def inertia_scale(doc: Document, e: InertiaScale) -> None:
    """Scale the moments of inertia by their factors (``ixz`` by the geometric mean of the
    ``ixx`` and ``izz`` factors).

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : InertiaScale
        The effect: the ``ixx``, ``iyy`` and ``izz`` factors (dimensionless).
    """
    mb = _mass_balance(doc)
    why = "flightid augment: inertia_scale (inertia error)"
    for tag, f in (("ixx", e.ixx), ("iyy", e.iyy), ("izz", e.izz),
                   ("ixz", math.sqrt(e.ixx * e.izz))):
        el = mb.find(tag)
        if el is not None and f != 1.0:
            _scale_text(el, f, why, mb)


def thrust_moment(doc: Document, e: ThrustMoment) -> None:
    """Add a pitching moment of the engines' total thrust times an arm (a thrust line off
    the CG, or propwash).

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : ThrustMoment
        The effect: the arm (m; N m per N of thrust, nose up positive).

    Raises
    ------
    AugmentError
        When the aircraft has no engine.
    """
    prop = doc.root.find("propulsion")
    n = len(prop.findall("engine")) if prop is not None else 0
    if not n:
        raise AugmentError(f"{e.label()}: the aircraft has no engine")
    thrust = xml_el("sum", *(prop_el(f"propulsion/engine[{i}]/thrust-lbs") for i in range(n)),
                 val_el(0.0))
    fn = xml_el("function", xml_el("description", text=f"augment: thrust moment, arm {e.arm:g} m"),
             xml_el("product", thrust, val_el(e.arm * FT_PER_M)), name="aero/augment/thrust-moment")
    doc.add_term("PITCH", f"added by flightid augment: thrust_moment arm {e.arm:+.6g} m "
                 f"(N m per N of thrust, nose up +): thrust line / propwash", fn)


