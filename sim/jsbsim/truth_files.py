"""Truth files (aircraft/<name>/truth.toml): reading them and checking a model against one.

:func:`truth_file` reads and validates the agreed format; :func:`compare_to_file` trims the
model at the file's condition and lists every derivative the exact truth
(:mod:`flightid.sim.jsbsim.truth`) does not reproduce within tolerance.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from flightid import aircraft as project_aircraft
from flightid.derivatives import is_derivative
from flightid.sim.jsbsim.model import as_model
from flightid.sim.jsbsim.trim import trim as do_trim
from flightid.sim.jsbsim.truth import derivatives


def truth_file(name: str) -> dict[str, Any]:
    """Read aircraft/<name>/truth.toml (or a .toml path) into {'condition', 'derivatives'}.

    Checks the agreed format: [condition] with altitude_m, speed_m_s, axes, flaps_rad and
    [derivatives.<canonical name>] tables with a numeric ``value`` (and a ``source``).

    Parameters
    ----------
    name : str
        Aircraft name, or a path ending in .toml.

    Returns
    -------
    dict
        The file's tables; ``axes`` defaults to "stability", ``flaps_rad`` to 0.

    Raises
    ------
    FileNotFoundError
        When there is no truth file.
    ValueError
        Naming the file and table that break the format.
    """
    if name.endswith(".toml"):
        path = Path(name)
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such truth file")
    else:
        path = project_aircraft.truth_path(name)
        if path is None:
            raise FileNotFoundError(
                f"aircraft {name!r} has no truth file (aircraft/{name}/truth.toml)")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: {exc}") from None
    cond = data.get("condition")
    if not isinstance(cond, dict):
        raise ValueError(f"{path}: missing [condition] table")
    for key in ("altitude_m", "speed_m_s"):
        if not isinstance(cond.get(key), int | float):
            raise ValueError(f"{path}: [condition] field {key!r} missing or not a number")
    axes = cond.setdefault("axes", "stability")
    if axes not in ("body", "stability"):
        raise ValueError(f"{path}: [condition] axes must be 'body' or 'stability', got {axes!r}")
    cond.setdefault("flaps_rad", 0.0)
    ders = data.get("derivatives", {})
    if not isinstance(ders, dict) or not ders:
        raise ValueError(f"{path}: no [derivatives.<name>] tables")
    for dname, entry in ders.items():
        if not is_derivative(dname):
            raise ValueError(f"{path}: [derivatives.{dname}] is not a canonical derivative name")
        if not isinstance(entry, dict) or not isinstance(entry.get("value"), int | float):
            raise ValueError(f"{path}: [derivatives.{dname}] field 'value' missing or not a number")
    return data


def compare_to_file(name: str, rel_tol: float = 0.02,
                    abs_tol: float = 1e-3) -> list[str]:
    """Trim at the truth file's condition and list every derivative outside tolerance.

    A derivative passes when |truth - file| <= max(rel_tol |file|, abs_tol).

    Parameters
    ----------
    name : str
        Aircraft name; it needs aircraft/<name>/truth.toml.
    rel_tol : float, optional
        Relative tolerance, 1. Default 0.02.
    abs_tol : float, optional
        Absolute tolerance, in the derivative's unit. Default 1e-3.

    Returns
    -------
    list of str
        One line per failing derivative; empty when the model reproduces its truth file.
    """
    data = truth_file(name)
    cond = data["condition"]
    model = as_model(name)
    t = do_trim(model, cond["altitude_m"], cond["speed_m_s"], flaps_rad=cond["flaps_rad"])
    truth = derivatives(model, t, axes=cond["axes"])
    problems = []
    for dname, entry in data["derivatives"].items():
        want = float(entry["value"])
        if dname in truth.flags:
            k = truth.flags[dname]
            problems.append(f"{dname}: kink at trim (slopes {k.minus:.4g}, {k.plus:.4g}), "
                            f"file {want:.4g}")
            continue
        if dname not in truth.values:
            problems.append(f"{dname}: not computed by truth (file {want:.4g})")
            continue
        got = truth.values[dname]
        if abs(got - want) > max(rel_tol * abs(want), abs_tol):
            problems.append(f"{dname}: truth {got:.5g}, file {want:.5g}")
    return problems
