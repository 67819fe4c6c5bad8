"""Aerodynamic effects written into the JSBSim XML: derivative deltas (rotated into the
aircraft's axes), control effectiveness and tail ice."""

from __future__ import annotations

import xml.etree.ElementTree as ET

from flightid.sim.augment.document import (
    FT_PER_M,
    MASS_KEYWORD,
    POSITIONS,
    AugmentError,
    Document,
    prop_el,
    trig_el,
    val_el,
    xml_el,
)
from flightid.sim.effects.airframe import (
    ControlEffectiveness,
    DerivativeDelta,
    DerivativeTable,
    TailIce,
)

ET.register_namespace("xsi", "http://www.w3.org/2001/XMLSchema-instance")
def _variable(var: str, axes: str) -> tuple[list[ET.Element], float]:
    """The factors of the variable ``var`` in a product, and its sign."""
    p, r = prop_el("velocities/p-aero-rad_sec"), prop_el("velocities/r-aero-rad_sec")
    if var == "0":
        return [], 1.0
    if var in ("alpha", "beta"):
        return [prop_el(f"aero/{var}-rad")], 1.0
    if var == "q":
        return [prop_el("aero/ci2vel"), prop_el("velocities/q-aero-rad_sec")], 1.0
    if var == "alphadot":
        return [prop_el("aero/ci2vel"), prop_el("aero/alphadot-rad_sec")], 1.0
    if var in ("p", "r") and axes == "body":
        return [prop_el("aero/bi2vel"), p if var == "p" else r], 1.0
    if var == "p":  # stability axes: p cos a + r sin a
        return [prop_el("aero/bi2vel"), xml_el("sum", xml_el("product", p, trig_el("cos")),
                                          xml_el("product", r, trig_el("sin")))], 1.0
    if var == "r":  # r cos a - p sin a
        return [prop_el("aero/bi2vel"), xml_el("difference", xml_el("product", r, trig_el("cos")),
                                          xml_el("product", p, trig_el("sin")))], 1.0
    prop, sign = POSITIONS[var][0]
    return [prop_el(prop)], sign


# (stated axes, coefficient letter, model frame) -> [(axis, trig factor or None, sign)]
_S, _C = "sin", "cos"
_TARGETS: dict[tuple[str, str, str], list[tuple[str, str | None, float]]] = {
    ("stability", "L", "wind"): [("LIFT", None, 1.0)],
    ("stability", "D", "wind"): [("DRAG", None, 1.0)],
    ("stability", "L", "stability"): [("Z", None, 1.0)],
    ("stability", "D", "stability"): [("X", None, 1.0)],
    ("stability", "L", "body"): [("X", _S, 1.0), ("Z", _C, -1.0)],
    ("stability", "D", "body"): [("X", _C, -1.0), ("Z", _S, -1.0)],
    ("body", "X", "wind"): [("LIFT", _S, 1.0), ("DRAG", _C, -1.0)],
    ("body", "Z", "wind"): [("LIFT", _C, -1.0), ("DRAG", _S, -1.0)],
    ("body", "X", "stability"): [("Z", _S, 1.0), ("X", _C, -1.0)],
    ("body", "Z", "stability"): [("Z", _C, -1.0), ("X", _S, -1.0)],
    ("body", "X", "body"): [("X", None, 1.0)],
    ("body", "Z", "body"): [("Z", None, 1.0)],
    ("stability", "l", "body"): [("ROLL", _C, 1.0), ("YAW", _S, 1.0)],
    ("stability", "n", "body"): [("YAW", _C, 1.0), ("ROLL", _S, -1.0)],
    ("body", "l", "stability"): [("ROLL", _C, 1.0), ("YAW", _S, -1.0)],
    ("body", "n", "stability"): [("YAW", _C, 1.0), ("ROLL", _S, 1.0)],
}


def _targets(axes: str, coef: str, force: str, moment: str) -> list[tuple[str, str | None, float]]:
    if coef == "Y":
        return [("SIDE" if force == "wind" else "Y", None, 1.0)]
    if coef == "m":
        return [("PITCH", None, 1.0)]
    if coef in ("l", "n"):
        if axes == moment:
            return [("ROLL" if coef == "l" else "YAW", None, 1.0)]
        return _TARGETS[(axes, coef, moment)]
    return _TARGETS[(axes, coef, force)]


def derivative_delta(doc: Document, e: DerivativeDelta) -> None:
    """Add a constant delta to one derivative: a term ``delta x variable`` (``x abs(variable)``
    for the even form) on the coefficient's axis.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : DerivativeDelta
        The effect: the derivative, its axes and the delta (per rad).
    """
    form = " x abs(variable)" if e.form == "even" else ""
    _derivative_term(doc, e.derivative, e.axes, lambda s: [val_el(s * e.delta)],
                     f"derivative_delta {e.derivative} {e.delta:+.6g} per rad{form}",
                     even=e.form == "even")


# what a derivative_table reads, and the factor from the card's unit to the property's
SCHEDULE_PROPERTY = {"airspeed": ("velocities/vt-fps", FT_PER_M), "alpha": ("aero/alpha-rad", 1.0)}


def derivative_table(doc: Document, e: DerivativeTable) -> None:
    """Add a delta to one derivative that changes with airspeed or alpha: a JSBSim ``<table>``
    of the property ``SCHEDULE_PROPERTY`` names, through (``low``, ``delta_low``) and
    (``high``, ``delta_high``), held constant beyond them.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : DerivativeTable
        The effect: the derivative, the schedule (airspeed in m/s or alpha in rad) and the
        deltas (per rad) at its two points.
    """
    prop, scale = SCHEDULE_PROPERTY[e.schedule]

    def table(s: float) -> list[ET.Element]:
        rows = (f"\n{e.low * scale!r} {s * e.delta_low!r}\n"
                f"{e.high * scale!r} {s * e.delta_high!r}\n")
        return [xml_el("table", xml_el("independentVar", text=prop, lookup="row"),
                       xml_el("tableData", text=rows))]

    unit = "m/s" if e.schedule == "airspeed" else "rad"
    _derivative_term(doc, e.derivative, e.axes, table,
                     f"derivative_table {e.derivative} {e.delta_low:+.6g} at {e.schedule} "
                     f"{e.low:g} {unit} to {e.delta_high:+.6g} at {e.high:g} {unit} per rad")


def _derivative_term(doc: Document, derivative: str, axes: str, value, what: str,
                     even: bool = False) -> None:
    """Add ``value(sign)`` (the delta's elements, times the sign) x the derivative's
    variable (its absolute value when ``even``) as a term of the derivative's
    coefficient, rotated into the model's axes."""
    coef, var = derivative[1:].split("_", 1)
    force, moment = doc.frames()
    factors, sign = _variable(var, axes)
    if even:  # delta x |variable|: its sign no longer matters
        factors, sign = [*factors[:-1], xml_el("abs", factors[-1])], 1.0
    length = {"l": "metrics/bw-ft", "n": "metrics/bw-ft", "m": "metrics/cbarw-ft"}.get(coef)
    n = sum(1 for _ in doc.aero().iter("function"))
    for axis, trig, s in _targets(axes, coef, force, moment):
        product = [prop_el("aero/qbar-area"), *([prop_el(length)] if length else []),
                   *[_clone(f) for f in factors], *([trig_el(trig)] if trig else []),
                   *value(s * sign)]
        fn = xml_el("function", xml_el("description", text=f"augment: {what} ({axes} axes)"),
                    xml_el("product", *product), name=f"aero/augment/{derivative}-{n}-{axis}")
        n += 1
        rot = f" x {trig}(alpha), rotated into this {axis} axis" if trig else ""
        doc.add_term(axis, f"added by flightid augment: {what} ({axes} axes){rot}: "
                     "model mismatch", fn)


def _clone(el: ET.Element) -> ET.Element:
    return ET.fromstring(ET.tostring(el))


# -- control effectiveness ------------------------------------------------------------------


def _mentions(el: ET.Element, words: set[str], keyword: str) -> bool:
    for sub in el.iter():
        text = (sub.text or "").strip() if sub.tag in ("property", "independentVar") else ""
        if text and (keyword in text or text.lstrip("-") in words):
            return True
    return False


def control_effectiveness(doc: Document, e: ControlEffectiveness) -> None:
    """Scale every aerodynamic term that reads a surface's deflection by a factor.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : ControlEffectiveness
        The effect: the surface (``de``, ``da``, ``dr``) and the factor (dimensionless).

    Raises
    ------
    AugmentError
        When no aerodynamic term reads the surface.
    """
    keyword = MASS_KEYWORD[e.surface]
    aero = doc.aero()
    helpers = {f.get("name", "") for f in aero.findall("function")
               if _mentions(f, set(), keyword)}
    count = 0
    for axis in aero.findall("axis"):
        for i, fn in enumerate(list(axis)):
            if fn.tag != "function" or not _mentions(fn, helpers, keyword):
                continue
            ops = [c for c in fn if c.tag not in ("description",) and isinstance(c.tag, str)]
            for c in ops:
                fn.remove(c)
            fn.append(xml_el("product", val_el(e.factor), *ops))
            axis.insert(i, ET.Comment(
                f" scaled by flightid augment: control_effectiveness surface={e.surface} "
                f"factor {e.factor:.6g}: loss of {keyword} effectiveness "))
            count += 1
    if not count:
        raise AugmentError(f"{e.label()}: no aerodynamic term reads the {keyword}")


# the properties (or their prefixes) a pitching-moment term reads, per tail_ice factor
TAIL_READS = {
    "stability": ("aero/alpha-rad", "aero/alpha-deg", "aero/alpha-wing-rad"),
    "damping": ("velocities/q-aero-rad_sec", "velocities/q-rad_sec", "aero/alphadot-rad_sec",
                "aero/alphadot-deg_sec"),
}


def _reads_any(el: ET.Element, props: set[str]) -> bool:
    return any(sub.tag in ("property", "independentVar")
               and (sub.text or "").strip().lstrip("-") in props for sub in el.iter())


def tail_ice(doc: Document, e: TailIce) -> None:
    """Horizontal-tail ice: scale the pitching-moment terms that read the elevator, alpha
    (``stability``) and pitch rate or alphadot (``damping``) by the effect's factors.

    Parameters
    ----------
    doc : Document
        The aircraft's JSBSim XML, changed in place.
    e : TailIce
        The effect: the ``elevator``, ``stability`` and ``damping`` factors (dimensionless).

    Raises
    ------
    AugmentError
        When no pitching-moment term reads any of them.
    """
    aero = doc.aero()
    helpers = aero.findall("function")
    reads: dict[str, set[str]] = {}
    for factor, props in TAIL_READS.items():
        found = set(props)
        for _ in range(3):  # helpers of helpers (qhat reads q, ...)
            found |= {f.get("name", "") for f in helpers if _reads_any(f, found)}
        reads[factor] = found
    elevator = {f.get("name", "") for f in helpers if _mentions(f, set(), "elevator")}
    pitch = doc.axis("PITCH")
    count = 0
    for fn in list(pitch):
        if fn.tag != "function":
            continue
        scale, what = 1.0, []
        if _mentions(fn, elevator, "elevator"):
            scale, what = scale * e.elevator, [*what, f"elevator x {e.elevator:.6g}"]
        for factor in ("stability", "damping"):
            if _reads_any(fn, reads[factor]):
                f = getattr(e, factor)
                scale, what = scale * f, [*what, f"{factor} x {f:.6g}"]
        if not what or scale == 1.0:
            continue
        ops = [c for c in fn if c.tag != "description" and isinstance(c.tag, str)]
        for c in ops:
            fn.remove(c)
        fn.append(xml_el("product", val_el(scale), *ops))
        pitch.insert(list(pitch).index(fn), ET.Comment(
            f" scaled by flightid augment: tail_ice {', '.join(what)}: horizontal-tail ice "))
        count += 1
    if not count:
        raise AugmentError(f"{e.label()}: no pitching-moment term reads the elevator, alpha "
                           "or the pitch rate")


