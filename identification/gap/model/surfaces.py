"""What a record's surface channels hold (``surfaces_of``: positions, or the commands ahead
of the actuators, ``meta.extra["surfaces"]``; docs/record.md), and on a record of commands
the surfaces the aircraft's own actuators make of them (``actuated``: each
``<actuator>``'s lag and rate limit read from its XML and run as JSBSim runs them,
``run_actuators``, the commands held between updates at ``command_rate``), so that the
plain aircraft flown on its own commands is at the null level and an ``actuator_lag``
candidate is the lag the model lacks.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from flightid.record import FlightRecord
from flightid.sim.augment.actuators import Actuator, actuator_chains
from flightid.sim.flight.controls import substeps

SURFACE_KINDS = ("position", "command")
SURFACES_KEY = "surfaces"  # the key of FlightRecord.meta.extra
COMMAND_RATE_KEY = "command_rate_hz"  # meta.extra: the rate the commands were updated at


def surfaces_of(records: Sequence[FlightRecord], surfaces: str | None = None) -> str:
    """What the records' surface channels hold.

    Parameters
    ----------
    records : sequence of FlightRecord
        The records (their ``meta.extra["surfaces"]``; "position" when absent).
    surfaces : str or None
        "position" or "command" to override the metadata.

    Returns
    -------
    str
        "position" or "command". Raises ValueError naming the value when it is neither,
        or when the records disagree.
    """
    if surfaces is not None:
        found = {surfaces}
    else:
        found = {str(r.meta.extra.get(SURFACES_KEY, "position")) for r in records}
        found = found or {"position"}
    bad = sorted(found - set(SURFACE_KINDS))
    if bad:
        raise ValueError(f"surfaces must be one of {', '.join(SURFACE_KINDS)} "
                         f"(meta.extra[{SURFACES_KEY!r}] or the option), got {bad[0]!r}")
    if len(found) > 1:
        raise ValueError("the records disagree on what their surface channels hold "
                         f"(meta.extra[{SURFACES_KEY!r}]: {', '.join(sorted(found))}); "
                         "give surfaces= for all of them")
    return found.pop()


def run_actuators(time: np.ndarray, command: np.ndarray, chain: Sequence[Actuator],
                  rate_hz: float | None = None) -> np.ndarray:
    """The surface position that the actuators ``chain`` make of a recorded command.

    The command is updated at ``rate_hz`` (default: the record's rate; taken from the
    record between its samples, linearly) and held between updates. Each update is set
    before the last of the FCS steps that end at it (``substeps(rate_hz)`` steps per
    update, as ``sim.flight.simulation`` flies). Each actuator's ``<lag>`` runs by
    Tustin's rule, then its ``<rate_limit>`` acts on the lag's output (JSBSim reference
    manual, FGActuator: lag, then rate limit). Starts at rest at the first command.

    Parameters
    ----------
    time : ndarray
        The record's times, s.
    command : ndarray
        The recorded command, rad.
    chain : sequence of Actuator
        The actuators in series, command first (``sim.augment.actuators.actuator_chains``).
    rate_hz : float or None
        The rate the command was updated at, Hz (None: the record's).

    Returns
    -------
    ndarray
        The surface position at ``time``, rad.
    """
    rate = rate_hz or 1.0 / float(np.median(np.diff(time)))
    n = substeps(rate)
    h = 1.0 / (rate * n)
    updates = time[0] + np.arange(int(np.floor((time[-1] - time[0]) * rate + 1e-9)) + 2) / rate
    u = np.interp(updates, time, command)
    lags = []
    for a in chain:
        c = h / a.tau if a.tau > 0 else math.inf
        lags.append((c / (2.0 + c), (2.0 - c) / (2.0 + c)) if math.isfinite(c) else None)
    steps = [a.rate_limit * h for a in chain]
    u0 = float(u[0])
    lag_in = [u0] * len(chain)  # each lag's previous input and output
    lag_out = [u0] * len(chain)
    out_prev = [u0] * len(chain)  # each actuator's previous (rate-limited) output
    position = np.empty(len(u))
    position[0] = u0
    for k in range(1, len(u)):
        for j in range(n):
            x = float(u[k - 1] if j < n - 1 else u[k])
            for i in range(len(chain)):
                if lags[i] is not None:
                    ca, cb = lags[i]
                    y = ca * (x + lag_in[i]) + cb * lag_out[i]
                    lag_in[i], lag_out[i] = x, y
                    x = y
                x = min(max(x, out_prev[i] - steps[i]), out_prev[i] + steps[i])
                out_prev[i] = x
        position[k] = x
    return np.interp(time, updates, position)


def command_rate(record: FlightRecord) -> float | None:
    """The rate the record's commands were updated at.

    Parameters
    ----------
    record : FlightRecord
        A record of commands.

    Returns
    -------
    float or None
        ``meta.extra["command_rate_hz"]`` (Hz; docs/record.md), else the rate a simulated
        flight set its controls at (its card's ``rate``), else None (the record's own
        rate).
    """
    if COMMAND_RATE_KEY in record.meta.extra:
        return float(record.meta.extra[COMMAND_RATE_KEY])
    card = (record.meta.scenario or {}).get("card") or {}
    return float(card["rate"]) if "rate" in card else None


def actuated(records: Sequence[FlightRecord], aircraft: str,
             surfaces: str | None = None) -> list[FlightRecord]:
    """The records as the model's aerodynamics see them.

    Parameters
    ----------
    records : sequence of FlightRecord
        The records.
    aircraft : str
        The JSBSim aircraft whose actuators are read (name or XML path).
    surfaces : str or None
        What the surface channels hold ("position", "command"; None: ``surfaces_of``).

    Returns
    -------
    list of FlightRecord
        On records of commands each surface channel passed through the aircraft's own
        actuators (lag and rate limit, ``sim.augment.actuators.actuator_chains``;
        ``run_actuators``), so that an aircraft flown on its own commands is at the null
        level and an ``actuator_lag`` candidate is the lag it lacks; records of
        positions as they are.
    """
    if surfaces_of(records, surfaces) != "command":
        return list(records)
    chains = actuator_chains(aircraft)
    out = []
    for r in records:
        channels = dict(r.channels)
        for s, chain in chains.items():
            if s in r and chain:
                channels[s] = run_actuators(r.time, r[s], chain, command_rate(r))
        out.append(FlightRecord(r.time, channels, r.meta))
    return out
