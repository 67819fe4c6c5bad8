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
- ``derivative_table``: the same term with a ``<table>`` in the true airspeed or alpha in
  place of the constant delta (a condition-dependent model error).
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
import shutil
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from flightid.channels import CONTROL_SURFACES
from flightid.sim.augment.aero import (
    control_effectiveness,
    derivative_delta,
    derivative_table,
    tail_ice,
)
from flightid.sim.augment.document import (
    AugmentError,
    Document,
)
from flightid.sim.augment.fcs import dynamic, linkage, surface_drive_switches
from flightid.sim.augment.mass import cg_offset, inertia_scale, mass_scale, thrust_moment
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
    DerivativeTable,
    InertiaScale,
    MassScale,
    RateLimit,
    TailIce,
    ThrustMoment,
)
from flightid.sim.jsbsim.model import locate

ET.register_namespace("xsi", "http://www.w3.org/2001/XMLSchema-instance")
def cache_folder(base: Path, aircraft: str, effects: Sequence[AugmentEffect],
                 surface_drive: bool = False) -> Path:
    """A folder under ``base`` keyed by the aircraft, the effects and the drive (for reuse).

    Parameters
    ----------
    base : pathlib.Path
        The cache folder.
    aircraft : str
        Aircraft name or XML path.
    effects : sequence of AugmentEffect
        The effects added.
    surface_drive : bool, optional
        Whether the surface drive switches are added. Default False.

    Returns
    -------
    pathlib.Path
        ``base / <16 hex digits of a SHA-256 of the key>``.
    """
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

    Parameters
    ----------
    aircraft : str or pathlib.Path
        A name (project or jsbsim) or an XML path.
    effects : sequence of AugmentEffect
        The effects to add.
    base : str or pathlib.Path
        The cache folder.
    name : str, optional
        The new aircraft's name; default ``<aircraft>-augmented``.
    surface_drive : bool, optional
        Add the surface drive switches. Default False.

    Returns
    -------
    pathlib.Path
        The augmented aircraft's XML.
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
    """Move ``tmp/aircraft``, written whole, to ``folder/aircraft`` in one rename.

    A process reading the cache so never sees half an aircraft; ``tmp`` is removed, and a
    folder another process published first is kept.

    Parameters
    ----------
    tmp : pathlib.Path
        The temporary folder written.
    folder : pathlib.Path
        The cache folder to publish into.
    """
    folder.mkdir(parents=True, exist_ok=True)
    try:
        (tmp / "aircraft").rename(folder / "aircraft")
    except OSError:  # another process wrote it first
        pass
    shutil.rmtree(tmp, ignore_errors=True)


def augment(aircraft: str | Path, effects: Sequence[AugmentEffect], folder: str | Path,
            name: str | None = None, surface_drive: bool = False) -> Path:
    """Write the aircraft with ``effects`` added under ``folder``; the new XML's path.

    Effects at their neutral value are only noted in a comment.
    ``flightid.sim.jsbsim.model.load`` takes the path.

    Parameters
    ----------
    aircraft : str or pathlib.Path
        A name (project or jsbsim) or an XML path; the original stays untouched.
    effects : sequence of AugmentEffect
        The effects to add.
    folder : str or pathlib.Path
        Output folder; the aircraft goes to ``folder/aircraft/<name>``, replacing it.
    name : str, optional
        The new aircraft's name; default ``<aircraft>-augmented``.
    surface_drive : bool, optional
        Add the switches that let a flight set the surface positions directly (module note).
        Default False.

    Returns
    -------
    pathlib.Path
        The new aircraft's XML.
    """
    old, xml, _ = locate(str(aircraft))
    new = name or f"{old}-augmented"
    dest = Path(folder) / "aircraft" / new
    if dest.exists():
        shutil.rmtree(dest)
    shutil.copytree(xml.parent, dest, ignore=shutil.ignore_patterns(
        "__pycache__", xml.name, "*.toml"))
    doc = Document(xml, dest)
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
    for surface in CONTROL_SURFACES:
        dyn = [e for e in effects if isinstance(e, DYNAMIC) and e.surface == surface
               and not e.neutral()]
        link = [e for e in effects if isinstance(e, LINKAGE) and e.surface == surface
                and not e.neutral()]
        if dyn:
            dynamic(doc, surface, dyn)
        if link:
            linkage(doc, surface, link)
    if surface_drive:
        surface_drive_switches(doc)
    doc.write(dest / f"{new}.xml")
    return dest / f"{new}.xml"


def _check_unique(effects: Sequence[AugmentEffect]) -> None:
    seen: set[tuple] = set()
    for e in effects:
        if isinstance(e, DerivativeDelta | DerivativeTable | ControlEffectiveness):
            continue  # these add up
        key = (e.name, e.options().get("surface", ""))
        if key in seen:
            raise AugmentError(f"{e.label()}: given twice; give each {e.name} once"
                               + (" per surface" if "surface" in e.options() else ""))
        seen.add(key)


_APPLY = {
    DerivativeDelta: derivative_delta,
    DerivativeTable: derivative_table,
    ControlEffectiveness: control_effectiveness,
    CgOffset: cg_offset,
    MassScale: mass_scale,
    InertiaScale: inertia_scale,
    ThrustMoment: thrust_moment,
    TailIce: tail_ice,
    ActuatorLag: lambda doc, e: None,  # written per surface, with the other dynamics
    RateLimit: lambda doc, e: None,
    Deadband: lambda doc, e: None,
    Backlash: lambda doc, e: None,
    ActuatorBias: lambda doc, e: None,
}
