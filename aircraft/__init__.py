"""JSBSim aircraft definitions and their truth files; ``path()`` finds them.

Each aircraft lives in ``aircraft/<name>/<name>.xml`` (engines and systems either in the
folder's own ``Engines/`` and ``Systems/`` or taken from the jsbsim package), with an
optional ``truth.toml`` naming the source of every derivative.

Contract with ``flightid.sim`` (so that trim, fly and truth work on any aircraft): the
flight control system takes ``fcs/elevator-cmd-norm``, ``fcs/aileron-cmd-norm``,
``fcs/rudder-cmd-norm``, ``fcs/throttle-cmd-norm[i]`` (and ``fcs/flap-cmd-norm``) and the
aerodynamics read the JSBSim surface positions ``fcs/elevator-pos-rad`` (trailing edge
down +), ``fcs/left-aileron-pos-rad`` (left trailing edge down +, i.e. right roll +; the
project's da is its negative) and ``fcs/rudder-pos-rad`` (trailing edge left +).
"""

from __future__ import annotations

from pathlib import Path

FOLDER = Path(__file__).resolve().parent


def names() -> list[str]:
    """Names of the aircraft in this folder (those with ``<name>/<name>.xml``).

    Returns
    -------
    list of str
        Aircraft names, sorted.
    """
    return sorted(p.name for p in FOLDER.iterdir() if (p / f"{p.name}.xml").is_file())


def path(name: str) -> Path:
    """Path of ``aircraft/<name>/<name>.xml``.

    Parameters
    ----------
    name : str
        Aircraft name, e.g. "navion".

    Returns
    -------
    pathlib.Path
        The JSBSim model file.

    Raises
    ------
    FileNotFoundError
        Listing the available names if the file is absent.
    """
    xml = FOLDER / name / f"{name}.xml"
    if not xml.is_file():
        known = ", ".join(names()) or "none yet"
        raise FileNotFoundError(f"no project aircraft {name!r} ({xml} missing); available: {known}")
    return xml


def truth_path(name: str) -> Path | None:
    """Path of ``aircraft/<name>/truth.toml`` if that aircraft has a truth file, else None.

    Parameters
    ----------
    name : str
        Aircraft name.

    Returns
    -------
    pathlib.Path or None
        The truth file, or None.
    """
    toml = FOLDER / name / "truth.toml"
    return toml if toml.is_file() else None
