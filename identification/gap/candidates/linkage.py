"""The nonlinear actuator entries (``rate_limit``, ``backlash``, ``deadband``) as candidates,
on records whose surface channels hold the commands.

A linear model cannot carry them, so they are not in the linear screening
(``candidates.actuator``); without them a rate-limited elevator was named as the nearest
linear effect, ``actuator_lag(de)`` (four of the five seen rate limits of the blind
check's seeds 0 and 5 named wrong; docs/gap_benchmark.md). Here each is scored the way it
acts: the record's surface (already through the aircraft's own actuators,
``model.surfaces.actuated``) is passed through the entry at a trial value, in series as
JSBSim runs it (``run_actuators`` for the rate limit; the play and deadband operators of
``nonlinearity``), and the model as is is fitted on that record (only the nuisance
parameters: ``fit.fit``). The value is found on a grid (``GRIDS``, geometric, 0.25 to 6
times the catalogue default: a worn linkage's 1.5 deg play lies inside it) with a parabola
through the best point and its neighbours in log-value; a minimum at the grid's edge is
no estimate (a rate limit that never acts, a play wider than the maneuvers). The evidence
is the linear candidates': delta BIC on the fitted windows and the cost and gap on each
held-out window with the value chosen on the other windows (``rank.Ranker.judge``), so
they are ranked with them. A surface nonlinearity is not a state of the linear model, so
the sequence of ``sequence.following`` stops at it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from flightid.identification.gap.fit import WindowFit, fit
from flightid.identification.gap.model.edits import Candidate, identity
from flightid.identification.gap.model.surfaces import run_actuators
from flightid.identification.gap.nonlinearity import deadband, play
from flightid.record import FlightRecord
from flightid.sim.augment.actuators import Actuator
from flightid.units import DEG

# per entry: (catalogue parameter, catalogue default, trial values). Geometric grids of 11
# values over 0.25-6 x the default (rate limit 20 deg/s; widths 0.5 deg). The top is twice
# the widest play or deadband the blind check draws (1.5 deg): with the grid's top at
# 3 x the default (1.5 deg), 0 of 8 seen single plays of 1.2-1.5 deg were named, their
# minimum at the edge (docs/gap_benchmark.md, "The rules for the seed-14 run")
ENTRIES = ("rate_limit", "backlash", "deadband")
DEFAULTS = {"rate_limit": ("rate", 20.0 * DEG), "backlash": ("width", 0.5 * DEG),
            "deadband": ("width", 0.5 * DEG)}
GRID_FACTORS = tuple(float(f) for f in np.geomspace(0.25, 6.0, 11))
GRIDS = {e: tuple(d * f for f in GRID_FACTORS) for e, (_, d) in DEFAULTS.items()}


def through(entry: str, time: np.ndarray, surface: np.ndarray, value: float) -> np.ndarray:
    """A surface position (rad) passed through ``entry`` at ``value`` (rate rad/s, width rad).

    Parameters
    ----------
    entry : str
        "rate_limit", "backlash" or "deadband".
    time : ndarray
        The record's times, s.
    surface : ndarray
        The surface position ahead of the entry, rad.
    value : float
        The entry's parameter: a rate limit in rad/s, a full width in rad.

    Returns
    -------
    ndarray
        The surface position behind the entry, rad.
    """
    if entry == "rate_limit":
        return run_actuators(time, surface, [Actuator(rate_limit=value)])
    if entry == "backlash":
        return play(surface, value)
    if entry == "deadband":
        return deadband(surface, value)
    raise ValueError(f"linkage: unknown entry {entry!r}; one of {', '.join(ENTRIES)}")


def transformed(record: FlightRecord, entry: str, surface: str, value: float) -> FlightRecord:
    """``record`` with its ``surface`` channel passed through ``entry`` at ``value``.

    Parameters
    ----------
    record : FlightRecord
        One window (surface channels in rad).
    entry : str
        "rate_limit", "backlash" or "deadband".
    surface : str
        "da", "dr" or "de".
    value : float
        The entry's parameter (rad/s or rad).

    Returns
    -------
    FlightRecord
    """
    return record.with_channels(**{surface: through(entry, record.time, record[surface],
                                                    value)})


def linkage(entry: str, surface: str) -> Candidate:
    """The candidate of ``entry`` on ``surface`` (no linear-model edit: ``identity``; its one
    free name is the catalogue parameter's, scored by ``scan``).

    Parameters
    ----------
    entry : str
        "rate_limit", "backlash" or "deadband".
    surface : str
        "da", "dr" or "de".

    Returns
    -------
    Candidate
    """
    name, _ = DEFAULTS[entry]
    return Candidate(entry, {"surface": surface}, (f"{entry}_{surface}",), identity,
                     catalogue=(name,))


def is_linkage(c: Candidate) -> bool:
    """Whether ``c`` is one of this module's candidates (scored by ``scan``, not a model
    edit).

    Parameters
    ----------
    c : Candidate

    Returns
    -------
    bool
    """
    return c.entry in ENTRIES and not c.parts and c.wrap is identity


def linkage_candidates(inputs: tuple[str, ...] | list[str], surfaces: str) -> list[Candidate]:
    """The nonlinear actuator entries on the surface inputs: ``backlash`` and ``deadband``
    on any record (the catalogue puts them in the linkage, between the measured surface
    position and the surface the air sees; no deadband on the elevator, which is trimmed
    away from zero, where a deadband is a constant offset: the trim-level class's), and
    ``rate_limit`` on records of commands (on positions it has acted on what was
    recorded).

    Parameters
    ----------
    inputs : sequence of str
        The model's inputs.
    surfaces : str
        "position" or "command".

    Returns
    -------
    list of Candidate
        One per entry and surface that can carry it.
    """
    entries = ENTRIES if surfaces == "command" else ("backlash", "deadband")
    return [linkage(e, s) for s in inputs if s in ("da", "dr", "de") for e in entries
            if not (e == "deadband" and s == "de")]


def refined_minimum(grid: tuple[float, ...], cost: list[float]) -> tuple[float, float] | None:
    """The minimum of ``cost`` over ``grid`` refined by a parabola in log-value through the
    best point and its neighbours, and the standard deviation from its curvature (the
    cost is a negative log-likelihood: var = 1 / (d2J/dv2)); None at the grid's edge or
    without curvature.

    Parameters
    ----------
    grid : tuple of float
        Trial values, increasing.
    cost : list of float
        The cost at each.

    Returns
    -------
    tuple of float or None
        (value, std).
    """
    k = int(np.argmin(cost))
    if k == 0 or k == len(grid) - 1 or not all(map(math.isfinite, cost[k - 1:k + 2])):
        return None
    x = np.log(np.array(grid[k - 1:k + 2]))
    a, b, _ = np.polyfit(x, np.array(cost[k - 1:k + 2]), 2)
    if a <= 0:
        return None
    xm = float(np.clip(-b / (2 * a), x[0], x[2]))
    value = math.exp(xm)
    # d2J/dv2 = d2J/dx2 / v^2 at the minimum (x = ln v)
    return value, value / math.sqrt(2 * a)


def scan(model, records: dict[str, FlightRecord], cand: Candidate,
         fitter: Callable[..., WindowFit] = fit) -> dict[str, list[WindowFit | None]]:
    """Each window's fit of the model as is on its record passed through ``cand`` at each
    value of its grid (None where the fit fails).

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.
    records : dict of str to FlightRecord
        The windows by label.
    cand : Candidate
        A ``linkage`` candidate.
    fitter : callable
        The fit (``fit.fit``).

    Returns
    -------
    dict of str to list
        Per window, one fit per grid value.
    """
    surface = cand.options["surface"]
    out: dict[str, list[WindowFit | None]] = {}
    for label, rec in records.items():
        row: list[WindowFit | None] = []
        for v in GRIDS[cand.entry]:
            try:
                row.append(fitter(model, transformed(rec, cand.entry, surface, v)))
            except (ValueError, np.linalg.LinAlgError):
                row.append(None)
        out[label] = row
    return out
