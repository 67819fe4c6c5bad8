"""Write an augmented copy of a JSBSim aircraft: the original plus airframe/actuator effects.

``augment(aircraft, effects, folder)`` copies the aircraft's folder (engines, systems) to
``<folder>/aircraft/<new name>/`` and writes ``<new name>.xml`` with every effect added by
JSBSim's own means, each preceded by an XML comment naming the effect and its magnitude:

- ``derivative_delta``: an extra ``<function>`` term in the aerodynamic axes, built from
  JSBSim properties (``aero/qbar-area``, ``metrics/bw-ft``, ``aero/alpha-rad``, ...). The
  delta is stated in stability or body axes and rotated with the current alpha into the
  frame the aircraft's axes use (LIFT/DRAG/SIDE, X/Y/Z in BODY or STABILITY frame), so the
  numerical truth (``flightid.sim.jsbsim.truth.derivatives``) in the stated axes moves by exactly
  the delta. (Exact for every derivative but the alpha derivatives of a rotated lateral
  moment when an added lateral term is nonzero at trim.)
- ``control_effectiveness``: every aerodynamic term that reads the surface (directly or
  through a helper function of the aerodynamics section) multiplied by the factor.
- ``cg_offset``, ``mass_scale``, ``inertia_scale``: the ``<mass_balance>`` section (the CG
  offset moves every mass item: CG, point masses and tanks).
- ``thrust_moment``: a PITCH term arm x the engines' thrust.
- ``tail_ice``: the PITCH terms scaled by what they read (the elevator, alpha, the pitch
  rate or alphadot, directly or through helper functions); the defaults turn ``twinotter``
  into ``twinotter-iced``.
- ``actuator_lag``, ``rate_limit``: an ``<actuator>`` in series after the component that
  writes the surface position (``fcs/elevator-pos-rad``, ...), so the record's de/da/dr show
  them. ``deadband``, ``backlash``, ``actuator_bias``: an ``<actuator>`` between the
  measured position and the aerodynamics (the linkage): the aerodynamic terms read its
  output. The flight core commands surface positions through the FCS's static map, which
  would invert a static effect placed before the position.

``surface_drive=True`` adds, after everything else, a switch behind each surface position
(``drive``): while ``fcs/drive/on`` is 0 the FCS drives the surface as before (trim works as
usual); set to 1, the positions follow ``fcs/drive/de-rad``, ``-da-rad`` and ``-dr-rad``
(project signs, rad), bypassing the actuator. A record's *measured* surfaces have already
passed the real actuator: an aircraft flown from them must not lag them again
(``sim.flight.simulation.Simulation(..., surfaces="driven")`` writes them there).

The result loads in plain JSBSim: ``FGFDMExec(root_dir=folder).load_model(name)``.
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from flightid.sim.effects.airframe import (
    DYNAMIC,
    LINKAGE,
    ActuatorBias,
    ActuatorLag,
    AugmentEffect,
    Backlash,
    CgOffset,
    ControlEffectiveness,
    Deadband,
    DerivativeDelta,
    InertiaScale,
    MassScale,
    RateLimit,
    TailIce,
    ThrustMoment,
)
from flightid.sim.jsbsim.model import DRIVE, DRIVE_ON, PACKAGE_ENGINES, PACKAGE_SYSTEMS, locate

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


def cache_folder(base: Path, aircraft: str, effects: Sequence[AugmentEffect],
                 surface_drive: bool = False) -> Path:
    """A folder under ``base`` keyed by the aircraft, the effects and the drive (for reuse)."""
    key = json.dumps([aircraft, [e.to_dict() for e in effects]]
                     + (["surface_drive"] if surface_drive else []),
                     sort_keys=True, default=str)
    return base / hashlib.sha256(key.encode()).hexdigest()[:16]


def augment_cached(aircraft: str | Path, effects: Sequence[AugmentEffect], base: str | Path,
                   name: str | None = None, surface_drive: bool = False) -> Path:
    """The augmented XML's path under ``base``, written once per aircraft and effect list.

    The folder is ``cache_folder(base, aircraft, effects, surface_drive)``; a process that
    finds the XML there reuses it. Written into a temporary folder and renamed, so processes
    that write the same aircraft at once do not see half a folder.
    """
    old = locate(str(aircraft))[0]
    new = name or f"{old}-augmented"
    folder = cache_folder(Path(base), str(aircraft), effects, surface_drive)
    xml = folder / "aircraft" / new / f"{new}.xml"
    if not xml.is_file():
        Path(base).mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix="writing-", dir=base))
        augment(aircraft, effects, tmp, name=new, surface_drive=surface_drive)
        publish(tmp, folder)
    return xml


def publish(tmp: Path, folder: Path) -> None:
    """Move ``tmp/aircraft``, written whole, to ``folder/aircraft`` in one rename (so that
    a process reading the cache never sees half an aircraft), and remove ``tmp``; a folder
    another process published first is kept."""
    folder.mkdir(parents=True, exist_ok=True)
    try:
        (tmp / "aircraft").rename(folder / "aircraft")
    except OSError:  # another process wrote it first
        pass
    shutil.rmtree(tmp, ignore_errors=True)


def augment(aircraft: str | Path, effects: Sequence[AugmentEffect], folder: str | Path,
            name: str | None = None, surface_drive: bool = False) -> Path:
    """Write the aircraft with ``effects`` added under ``folder``; the new XML's path.

    ``aircraft``: a name (project or jsbsim) or an XML path; the original stays untouched.
    ``name``: the new aircraft's name (default ``<aircraft>-augmented``). Effects at their
    neutral value are only noted in a comment. ``surface_drive``: add the switches that let
    a flight set the surface positions directly (module note). ``flightid.sim.jsbsim.model.load``
    takes the path.
    """
    old, xml, _ = locate(str(aircraft))
    new = name or f"{old}-augmented"
    dest = Path(folder) / "aircraft" / new
    if dest.exists():
        shutil.rmtree(dest)
    shutil.copytree(xml.parent, dest, ignore=shutil.ignore_patterns(
        "__pycache__", xml.name, "*.toml"))
    doc = _Doc(xml, dest)
    doc.root.set("name", new)
    header = [f"augmented by flightid from {old} ({xml.name}); effects added:"]
    for e in effects:
        header.append(f"  {e.label()}" + ("  (neutral: nothing written)" if e.neutral() else ""))
    doc.root.insert(0, ET.Comment("\n    " + "\n    ".join(header) + "\n  "))
    doc.root[0].tail = "\n  "
    _check_unique(effects)
    for e in effects:
        if not e.neutral():
            _APPLY[type(e)](doc, e)
    for surface in ("de", "da", "dr"):
        dyn = [e for e in effects if isinstance(e, DYNAMIC) and e.surface == surface
               and not e.neutral()]
        link = [e for e in effects if isinstance(e, LINKAGE) and e.surface == surface
                and not e.neutral()]
        if dyn:
            _dynamic(doc, surface, dyn)
        if link:
            _linkage(doc, surface, link)
    if surface_drive:
        _surface_drive(doc)
    doc.write(dest / f"{new}.xml")
    return dest / f"{new}.xml"


def _check_unique(effects: Sequence[AugmentEffect]) -> None:
    seen: set[tuple] = set()
    for e in effects:
        if isinstance(e, DerivativeDelta | ControlEffectiveness):
            continue  # these add up
        key = (e.name, e.options().get("surface", ""))
        if key in seen:
            raise AugmentError(f"{e.label()}: given twice; give each {e.name} once"
                               + (" per surface" if "surface" in e.options() else ""))
        seen.add(key)


# -- the document: main XML plus the system files it references ------------------------------


def _parse(path: Path) -> ET.ElementTree:
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    return ET.parse(path, parser)


class _Doc:
    def __init__(self, xml: Path, dest: Path) -> None:
        self.tree = _parse(xml)
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
                        self.systems[here] = _parse(here)
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


def _el(tag: str, *children: ET.Element, text: str | None = None, **attrs: str) -> ET.Element:
    e = ET.Element(tag, attrs)
    e.text = text
    e.extend(children)
    return e


def _prop(p: str) -> ET.Element:
    return _el("property", text=p)


def _val(v: float) -> ET.Element:
    return _el("value", text=repr(float(v)))


def _trig(kind: str) -> ET.Element:
    return _el(kind, _prop("aero/alpha-rad"))


# -- derivative deltas ------------------------------------------------------------------------


def _variable(var: str, axes: str) -> tuple[list[ET.Element], float]:
    """The factors of the variable ``var`` in a product, and its sign."""
    p, r = _prop("velocities/p-aero-rad_sec"), _prop("velocities/r-aero-rad_sec")
    if var == "0":
        return [], 1.0
    if var in ("alpha", "beta"):
        return [_prop(f"aero/{var}-rad")], 1.0
    if var == "q":
        return [_prop("aero/ci2vel"), _prop("velocities/q-aero-rad_sec")], 1.0
    if var == "alphadot":
        return [_prop("aero/ci2vel"), _prop("aero/alphadot-rad_sec")], 1.0
    if var in ("p", "r") and axes == "body":
        return [_prop("aero/bi2vel"), p if var == "p" else r], 1.0
    if var == "p":  # stability axes: p cos a + r sin a
        return [_prop("aero/bi2vel"), _el("sum", _el("product", p, _trig("cos")),
                                          _el("product", r, _trig("sin")))], 1.0
    if var == "r":  # r cos a - p sin a
        return [_prop("aero/bi2vel"), _el("difference", _el("product", r, _trig("cos")),
                                          _el("product", p, _trig("sin")))], 1.0
    prop, sign = POSITIONS[var][0]
    return [_prop(prop)], sign


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


def _derivative_delta(doc: _Doc, e: DerivativeDelta) -> None:
    coef, var = e.derivative[1:].split("_", 1)
    force, moment = doc.frames()
    factors, sign = _variable(var, e.axes)
    if e.form == "even":  # delta x |variable|: its sign no longer matters
        factors, sign = [*factors[:-1], _el("abs", factors[-1])], 1.0
    length = {"l": "metrics/bw-ft", "n": "metrics/bw-ft", "m": "metrics/cbarw-ft"}.get(coef)
    n = sum(1 for _ in doc.aero().iter("function"))
    for axis, trig, s in _targets(e.axes, coef, force, moment):
        product = [_prop("aero/qbar-area"), *([_prop(length)] if length else []),
                   *[_clone(f) for f in factors], *([_trig(trig)] if trig else []),
                   _val(s * sign * e.delta)]
        form = " x abs(variable)" if e.form == "even" else ""
        fn = _el("function", _el("description", text=f"augment: {e.derivative} delta "
                                 f"{e.delta:g}{form} ({e.axes} axes)"),
                 _el("product", *product), name=f"aero/augment/{e.derivative}-{n}-{axis}")
        n += 1
        rot = f" x {trig}(alpha), rotated into this {axis} axis" if trig else ""
        doc.add_term(axis, f"added by flightid augment: derivative_delta {e.derivative} "
                     f"{e.delta:+.6g} per rad{form} ({e.axes} axes){rot}: model mismatch", fn)


def _clone(el: ET.Element) -> ET.Element:
    return ET.fromstring(ET.tostring(el))


# -- control effectiveness ------------------------------------------------------------------


def _mentions(el: ET.Element, words: set[str], keyword: str) -> bool:
    for sub in el.iter():
        text = (sub.text or "").strip() if sub.tag in ("property", "independentVar") else ""
        if text and (keyword in text or text.lstrip("-") in words):
            return True
    return False


def _control_effectiveness(doc: _Doc, e: ControlEffectiveness) -> None:
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
            fn.append(_el("product", _val(e.factor), *ops))
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


def _tail_ice(doc: _Doc, e: TailIce) -> None:
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
        fn.append(_el("product", _val(scale), *ops))
        pitch.insert(list(pitch).index(fn), ET.Comment(
            f" scaled by flightid augment: tail_ice {', '.join(what)}: horizontal-tail ice "))
        count += 1
    if not count:
        raise AugmentError(f"{e.label()}: no pitching-moment term reads the elevator, alpha "
                           "or the pitch rate")


# -- mass balance ------------------------------------------------------------------------------


def _mass_balance(doc: _Doc) -> ET.Element:
    mb = doc.root.find("mass_balance")
    if mb is None:
        raise AugmentError("no <mass_balance> section")
    return mb


def _scale_text(el: ET.Element, factor: float, why: str, parent: ET.Element) -> None:
    old = float(el.text)
    el.text = f" {old * factor!r} "
    idx = list(parent).index(el)
    parent.insert(idx, ET.Comment(f" {why}: {el.tag} {old:g} x {factor:.6g} "))


def _cg_offset(doc: _Doc, e: CgOffset) -> None:
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


def _mass_scale(doc: _Doc, e: MassScale) -> None:
    mb = _mass_balance(doc)
    why = "flightid augment: mass_scale (mass error)"
    for el in [mb.find("emptywt"), *(pm.find("weight") for pm in mb.iter("pointmass"))]:
        if el is not None:
            parent = mb if el.tag == "emptywt" else next(
                pm for pm in mb.iter("pointmass") if el in list(pm))
            _scale_text(el, e.factor, why, parent)


def _inertia_scale(doc: _Doc, e: InertiaScale) -> None:
    mb = _mass_balance(doc)
    why = "flightid augment: inertia_scale (inertia error)"
    for tag, f in (("ixx", e.ixx), ("iyy", e.iyy), ("izz", e.izz),
                   ("ixz", math.sqrt(e.ixx * e.izz))):
        el = mb.find(tag)
        if el is not None and f != 1.0:
            _scale_text(el, f, why, mb)


def _thrust_moment(doc: _Doc, e: ThrustMoment) -> None:
    prop = doc.root.find("propulsion")
    n = len(prop.findall("engine")) if prop is not None else 0
    if not n:
        raise AugmentError(f"{e.label()}: the aircraft has no engine")
    thrust = _el("sum", *(_prop(f"propulsion/engine[{i}]/thrust-lbs") for i in range(n)),
                 _val(0.0))
    fn = _el("function", _el("description", text=f"augment: thrust moment, arm {e.arm:g} m"),
             _el("product", thrust, _val(e.arm * FT_PER_M)), name="aero/augment/thrust-moment")
    doc.add_term("PITCH", f"added by flightid augment: thrust_moment arm {e.arm:+.6g} m "
                 f"(N m per N of thrust, nose up +): thrust line / propwash", fn)


# -- actuators ----------------------------------------------------------------------------------


def _producer(doc: _Doc, prop: str) -> tuple[Path | None, ET.Element, ET.Element] | None:
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


def _insert_actuator(doc: _Doc, prop: str, new_input: str | None, children: list[ET.Element],
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
    act = _el("actuator", _el("input", text=src), *children, _el("output", text=dst),
              name=f"fcs/augment/{stem}")
    idx = list(parent).index(comp) + 1
    parent.insert(idx, ET.Comment(f" {comment} "))
    parent.insert(idx + 1, act)
    if path is not None:
        doc.changed.add(path)
    return True


def _positions(doc: _Doc, surface: str) -> list[tuple[str, float]]:
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


def _dynamic(doc: _Doc, surface: str, effects: list[AugmentEffect]) -> None:
    children = []
    for e in effects:
        if isinstance(e, ActuatorLag):
            children.append(_el("lag", text=repr(1.0 / e.tau)))
        elif isinstance(e, RateLimit):
            children.append(_el("rate_limit", text=repr(e.rate)))
    what = "; ".join(e.label() for e in effects)
    for prop, _ in _positions(doc, surface):
        stem = prop.removeprefix("fcs/").removesuffix("-pos-rad")
        _insert_actuator(doc, prop, f"fcs/augment/{stem}-pos-rad-unaugmented", children,
                         f"added by flightid augment: {what} (actuator dynamics, in series; "
                         f"the surface position shows them)", f"{stem}-actuator")


def _linkage(doc: _Doc, surface: str, effects: list[AugmentEffect]) -> None:
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
                children.append(_el("deadband_width", text=repr(e.width)))
            elif isinstance(e, Backlash):
                children.append(_el("hysteresis_width", text=repr(e.width)))
            elif isinstance(e, ActuatorBias):
                children.append(_el("bias", text=repr(sign * e.bias)))
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


def _surface_drive(doc: _Doc) -> None:
    """A switch behind each surface position: the FCS's value, or the drive when on."""
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
                added.append(_el("pure_gain", _el("input", text=drive),
                                 _el("gain", text=repr(sign)), name=source))
            test = _el("test", text=f"{DRIVE_ON} GE 0.5", logic="AND", value=source)
            added.append(_el("switch", _el("default", value=fcs_value), test,
                             _el("output", text=prop), name=f"fcs/drive/{stem}-switch"))
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
                props = [_el("property", text=p, value="0") for p in (DRIVE_ON, *DRIVE.values())]
                for k, el in enumerate(props):
                    section.insert(k, el)
                declared = True


_APPLY = {
    DerivativeDelta: _derivative_delta,
    ControlEffectiveness: _control_effectiveness,
    CgOffset: _cg_offset,
    MassScale: _mass_scale,
    InertiaScale: _inertia_scale,
    ThrustMoment: _thrust_moment,
    TailIce: _tail_ice,
    ActuatorLag: lambda doc, e: None,  # written per surface, with the other dynamics
    RateLimit: lambda doc, e: None,
    Deadband: lambda doc, e: None,
    Backlash: lambda doc, e: None,
    ActuatorBias: lambda doc, e: None,
}
