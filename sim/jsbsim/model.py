"""Load a JSBSim aircraft (project folder, jsbsim package, or an XML path) into a Model.

A Model wraps one ``jsbsim.FGFDMExec`` with JSBSim's console output silenced, the
reference geometry in SI units, cached property nodes, and the mapping from JSBSim's
surface properties to the project's control convention (flightid/channels.py):

    de = fcs/elevator-pos-rad          (trailing edge down +, JSBSim's own sign)
    da = -fcs/left-aileron-pos-rad     (JSBSim: left aileron TE down + = right roll +)
    dr = fcs/rudder-pos-rad            (JSBSim: + gives Cn < 0, i.e. trailing edge left)
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import sys
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jsbsim

from flightid import aircraft as project_aircraft
from flightid.record import Reference
from flightid.units import DEG, FT, SLUG, SLUG_FT2

PACKAGE_ROOT = Path(jsbsim.get_default_root_dir())
PACKAGE_AIRCRAFT = PACKAGE_ROOT / "aircraft"
PACKAGE_ENGINES = PACKAGE_ROOT / "engine"
PACKAGE_SYSTEMS = PACKAGE_ROOT / "systems"

# canonical control -> (JSBSim surface-position property, sign to the project convention)
SURFACES: dict[str, tuple[str, float]] = {
    "de": ("fcs/elevator-pos-rad", 1.0),
    "da": ("fcs/left-aileron-pos-rad", -1.0),
    "dr": ("fcs/rudder-pos-rad", 1.0),
}
# canonical control -> JSBSim pilot command (normalised -1..1) and its trim companion
COMMANDS: dict[str, tuple[str, str]] = {
    "de": ("fcs/elevator-cmd-norm", "fcs/pitch-trim-cmd-norm"),
    "da": ("fcs/aileron-cmd-norm", "fcs/roll-trim-cmd-norm"),
    "dr": ("fcs/rudder-cmd-norm", "fcs/yaw-trim-cmd-norm"),
}

# surface drive of an aircraft augmented with surface_drive=True (sim.augment): while
# DRIVE_ON is 1 the surfaces sit at DRIVE's positions (rad, project signs), past the FCS
DRIVE_ON = "fcs/drive/on"
DRIVE: dict[str, str] = {c: f"fcs/drive/{c}-rad" for c in SURFACES}


class UnknownAircraftError(ValueError):
    """The named aircraft is neither in aircraft/ nor shipped with the jsbsim package."""


@dataclass
class Model:
    """One loaded JSBSim aircraft; ``fdm`` is the live FGFDMExec (not thread-safe)."""

    name: str
    xml_path: Path
    origin: str  # "project", "jsbsim" or "file"
    fdm: jsbsim.FGFDMExec
    reference: Reference  # S (m^2), b, cbar (m)
    n_engines: int
    propeller: bool
    uses_alphadot: bool
    uses_betadot: bool
    alpha_limits: tuple[float, float] | None  # rad, from <alphalimits> if given
    _nodes: dict[str, jsbsim.FGPropertyNode] = field(default_factory=dict, repr=False)

    @property
    def version(self) -> str:
        """Provenance string, e.g. 'jsbsim 1.3.3'."""
        return f"jsbsim {jsbsim.__version__}"

    def node(self, prop: str, create: bool = False) -> jsbsim.FGPropertyNode:
        """Cached property node (reading a node is much cheaper than fdm[name])."""
        n = self._nodes.get(prop)
        if n is None:
            n = self.fdm.get_property_manager().get_node(prop, create)
            if n is None:
                raise KeyError(f"{self.name}: JSBSim has no property {prop!r}")
            self._nodes[prop] = n
        return n

    def has(self, prop: str) -> bool:
        """True when the loaded model defines the property."""
        return self.fdm.get_property_manager().hasNode(prop)

    def get(self, prop: str) -> float:
        """Value of a JSBSim property (JSBSim units)."""
        return self.node(prop).get_double_value()

    def set(self, prop: str, value: float) -> None:
        """Set a JSBSim property (JSBSim units)."""
        self.fdm[prop] = float(value)

    def surface(self, control: str) -> float:
        """Actual surface position of 'de', 'da' or 'dr' in rad, project sign convention."""
        prop, sign = SURFACES[control]
        return sign * self.get(prop)

    def throttle_props(self) -> list[str]:
        """The per-engine throttle command properties."""
        return [f"fcs/throttle-cmd-norm[{i}]" for i in range(max(self.n_engines, 1))]

    def copy(self) -> Model:
        """A freshly loaded, independent Model of the same aircraft."""
        fresh = load(str(self.xml_path) if self.origin == "file" else self.name)
        fresh.fdm.set_dt(self.fdm.get_delta_t())
        return fresh

    def reload(self) -> None:
        """Replace the FGFDMExec by a freshly loaded one (bit-identical restarts).

        Property nodes taken from the old FGFDMExec must not be used afterwards.
        """
        self.fdm = self.copy().fdm
        self._nodes.clear()

    def mass_kg(self) -> float:
        """Current aircraft mass (kg)."""
        return self.get("inertia/mass-slugs") * SLUG

    def mass_properties(self) -> dict[str, float]:
        """Mass (kg) and inertias (kg m^2, Ixz positive as in Etkin) as loaded."""
        m = self.copy()
        m.fdm.run_ic()  # JSBSim balances mass (with fuel) on initialisation
        return {
            "mass": m.mass_kg(),
            "Ixx": m.get("inertia/ixx-slugs_ft2") * SLUG_FT2,
            "Iyy": m.get("inertia/iyy-slugs_ft2") * SLUG_FT2,
            "Izz": m.get("inertia/izz-slugs_ft2") * SLUG_FT2,
            # JSBSim reports the tensor element -Ixz; Etkin's Ixz is its negative
            "Ixz": -m.get("inertia/ixz-slugs_ft2") * SLUG_FT2,
        }


# jsbsim releases before the logger API have no FGLogger: nothing to route there
_LoggerBase: Any = getattr(jsbsim, "FGLogger", object)


class _ToPythonLogging(_LoggerBase):
    """JSBSim's log records (jsbsim >= 1.3 routes its messages through a logger, whose
    default prints to Python's stdout) sent to the ``flightid.jsbsim`` logger at DEBUG
    level: silent unless an application asks for them."""

    def __init__(self) -> None:
        super().__init__()
        self._parts: list[str] = []

    def set_level(self, level: Any) -> None:
        self._parts = []

    def file_location(self, filename: str, line: int) -> None:
        self._parts.append(f"{filename}:{line}: ")

    def message(self, message: str) -> None:
        self._parts.append(message)

    def format(self, format: Any) -> None:
        pass

    def flush(self) -> None:
        text = "".join(self._parts).strip()
        self._parts = []
        if text:
            JSBSIM_LOG.debug("%s", text)


JSBSIM_LOG = logging.getLogger("flightid.jsbsim")


def silence_jsbsim() -> None:
    """Route JSBSim's messages of the calling thread to the ``flightid.jsbsim`` logger
    (the logger is per thread in JSBSim; ``load`` calls this for its thread)."""
    if hasattr(jsbsim, "set_logger") and not isinstance(jsbsim.get_logger(), _ToPythonLogging):
        jsbsim.set_logger(_ToPythonLogging())


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Silence JSBSim's C++ console output (it writes to the process's stdout/stderr).

    Yields
    ------
    None
        File descriptors 1 and 2 go to the null device inside the block.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, devnull):
            os.close(fd)


def available() -> dict[str, list[str]]:
    """Aircraft names that :func:`load` accepts.

    Returns
    -------
    dict of str to list of str
        {'project': [...], 'jsbsim': [...]}.
    """
    shipped = sorted(
        p.name for p in PACKAGE_AIRCRAFT.iterdir() if (p / f"{p.name}.xml").is_file()
    )
    return {"project": project_aircraft.names(), "jsbsim": shipped}


def _locate(aircraft: str) -> tuple[str, Path, str]:
    """(name, xml path, origin) of an aircraft name or XML path."""
    candidate = Path(aircraft)
    if candidate.suffix.lower() == ".xml" or candidate.is_dir():
        xml = candidate
        if candidate.suffix.lower() != ".xml":
            xml = candidate / f"{candidate.name}.xml"
        if not xml.is_file():
            raise UnknownAircraftError(f"aircraft file {xml} does not exist")
        if xml.stem != xml.parent.name:
            raise UnknownAircraftError(
                f"{xml}: JSBSim needs <name>/<name>.xml; folder is {xml.parent.name!r}"
            )
        return xml.stem, xml.resolve(), "file"
    project = project_aircraft.FOLDER / aircraft / f"{aircraft}.xml"
    if project.is_file():
        return aircraft, project, "project"
    shipped = PACKAGE_AIRCRAFT / aircraft / f"{aircraft}.xml"
    if shipped.is_file():
        return aircraft, shipped, "jsbsim"
    known = available()
    raise UnknownAircraftError(
        f"unknown aircraft {aircraft!r}; project aircraft: "
        f"{', '.join(known['project']) or 'none'}; jsbsim aircraft: {', '.join(known['jsbsim'])}"
    )


def _alpha_limits(root: ET.Element) -> tuple[float, float] | None:
    el = root.find("aerodynamics/alphalimits")
    if el is None:
        return None
    scale = DEG if el.get("unit", "RAD").upper().startswith("DEG") else 1.0
    lo, hi = el.findtext("min"), el.findtext("max")
    if lo is None or hi is None:
        return None
    return float(lo) * scale, float(hi) * scale


# JSBSim integrates the body rates and the attitude quaternion with rectangular Euler by
# default: each lags half a step (1.25 ms at 400 Hz). The rate lag reads as extra damping
# to an exact 6-DOF model (Navion Cm_alphadot -1.24 % -> -0.05 %, CL_q -3.9 % -> +0.65 %);
# the attitude lag puts the Euler angles 1.25 ms behind the integral of the rates, which
# biased the Twin Otter's Cl derivatives by -0.6 % on research-grade data. Adams-Bashforth 2
# (JSBSim code 3) for both (tests/identification/test_truth_recovery.py).
# FGPropagate::InitModel restores
# JSBSim's defaults, so every reset applies these again.
INTEGRATORS = {"simulation/integrator/rate/rotational": 3,
               "simulation/integrator/position/rotational": 3}


def set_integrators(fdm: jsbsim.FGFDMExec) -> None:
    """Use the project's JSBSim integrators (see INTEGRATORS).

    Parameters
    ----------
    fdm : jsbsim.FGFDMExec
        The JSBSim executive; its integrator properties are set.
    """
    for prop, code in INTEGRATORS.items():
        fdm[prop] = code


def locate(aircraft: str) -> tuple[str, Path, str]:
    """(name, XML path, origin) of an aircraft name, XML path or aircraft folder.

    Parameters
    ----------
    aircraft : str
        Aircraft name, XML path or aircraft folder.

    Returns
    -------
    tuple of (str, pathlib.Path, str)
        Aircraft name, its XML file, and where it comes from ("project", "jsbsim" or
        "file").
    """
    return _locate(aircraft)


def load(aircraft: str, *, rate_hz: float = 400.0) -> Model:
    """Load an aircraft by name (project aircraft/ first, then jsbsim's) or XML path.

    Engines and systems are looked up in the aircraft's own ``Engines/`` and ``Systems/``
    folders, then in the jsbsim package.

    Parameters
    ----------
    aircraft : str
        Aircraft name or XML path.
    rate_hz : float, optional
        JSBSim's integration rate, Hz. Default 400.

    Returns
    -------
    Model
        The loaded model with its reference geometry (SI), engines and alpha limits.

    Raises
    ------
    ValueError
        Naming the XML when JSBSim cannot load the aircraft.
    """
    name, xml, origin = _locate(aircraft)
    # the static debug level silences the banner that the constructor prints
    jsbsim.FGJSBBase().debug_lvl = 0
    silence_jsbsim()
    fdm = jsbsim.FGFDMExec(str(PACKAGE_ROOT))
    fdm.set_debug_level(0)
    fdm.disable_output()
    # before loading: JSBSim's FCS components (actuator lag, rate limit, filters) take
    # their time step when they are built; set afterwards, a rate limit of R acts as
    # R x rate_hz / 120 (120 Hz is JSBSim's default)
    fdm.set_dt(1.0 / rate_hz)
    try:
        with quiet():
            ok = fdm.load_model_with_paths(
                name, str(xml.parent.parent), str(PACKAGE_ENGINES), str(PACKAGE_SYSTEMS), True
            )
    except Exception as exc:  # JSBSim raises BaseError subclasses with its parser message
        raise ValueError(f"{xml}: JSBSim could not load the aircraft: {exc}") from exc
    if not ok:
        raise ValueError(f"{xml}: JSBSim could not load the aircraft (see the XML)")
    fdm.set_dt(1.0 / rate_hz)
    set_integrators(fdm)
    text = xml.read_text(encoding="utf-8", errors="replace")
    root = ET.fromstring(text)
    propulsion = fdm.get_propulsion()
    n_engines = propulsion.get_num_engines()
    propeller = any(
        fdm.get_property_manager().hasNode(f"propulsion/engine[{i}]/propeller-rpm")
        for i in range(n_engines)
    ) or bool(re.search(r"<propeller\b|<thruster[^>]*file=\"[^\"]*prop", text, re.I))
    reference = Reference(
        area=fdm["metrics/Sw-sqft"] * FT**2,
        span=fdm["metrics/bw-ft"] * FT,
        chord=fdm["metrics/cbarw-ft"] * FT,
    )
    # also scan the aircraft's system files: they may compute aero terms too
    uses = text
    for sys_file in list(xml.parent.glob("Systems/*.xml")):
        uses += sys_file.read_text(encoding="utf-8", errors="replace")
    return Model(
        name=name,
        xml_path=xml,
        origin=origin,
        fdm=fdm,
        reference=reference,
        n_engines=n_engines,
        propeller=propeller,
        uses_alphadot="alphadot" in uses,
        uses_betadot="betadot" in uses,
        alpha_limits=_alpha_limits(root),
    )


def as_model(model_or_name: Model | str) -> Model:
    """A Model for a Model or an aircraft name.

    Parameters
    ----------
    model_or_name : Model or str
        A loaded model (returned as is) or a name for :func:`load`.

    Returns
    -------
    Model
        The model.
    """
    return model_or_name if isinstance(model_or_name, Model) else load(model_or_name)
