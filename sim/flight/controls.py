"""Controls of a flight: the FCS's own map from surface increment to pilot command
(measured at reset, cached per aircraft and trim), the internal steps per record
interval, where a held control acts, the control schedules sampled at the record times,
and the per-sample writes of the values that change.
"""

from __future__ import annotations

import itertools
import math
from bisect import bisect_right
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np

from flightid.channels import CONTROL_SURFACES
from flightid.sim.jsbsim.model import (
    COMMANDS,
    SURFACES,
    Model,
)
from flightid.sim.jsbsim.trim import Trim

MIN_INTERNAL_HZ = 400.0

Control = np.ndarray | Callable[[float], float] | float


COMMAND_MAPS: dict[tuple, dict[str, tuple[np.ndarray, np.ndarray]]] = {}


def command_maps(model: Model, trim: Trim) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """FCS maps of de, da, dr at a trim, cached per aircraft file and trim setting.

    Parameters
    ----------
    model : Model
        The loaded JSBSim model.
    trim : Trim
        The trim; its JSBSim settings key the cache.

    Returns
    -------
    dict of str to tuple of numpy.ndarray
        By surface, (positions in rad, pilot commands) as :func:`command_map` gives them;
        surfaces without a map are left out.
    """
    key = (str(model.xml_path), tuple(sorted(trim.jsbsim.items())))
    if key not in COMMAND_MAPS:
        if len(COMMAND_MAPS) > 64:
            COMMAND_MAPS.clear()
        COMMAND_MAPS[key] = {c: m for c in CONTROL_SURFACES
                      if (m := command_map(model, c)) is not None}
    return COMMAND_MAPS[key]


def command_map(model: Model, control: str) -> tuple[np.ndarray, np.ndarray] | None:
    """The FCS map pilot command -> surface position (project sign), or None.

    Parameters
    ----------
    model : Model
        The loaded JSBSim model, at its trim.
    control : str
        "de", "da" or "dr".

    Returns
    -------
    tuple of numpy.ndarray or None
        (positions in rad, increasing; pilot commands), saturated plateaus dropped; None when
        the model lacks the properties or the map has fewer than two points.
    """
    cmd, _ = COMMANDS[control]
    prop, sign = SURFACES[control]
    if not (model.has(cmd) and model.has(prop)):
        return None
    fdm = model.fdm
    saved = fdm[cmd]
    # the grid holds the usual kinks exactly: command + trim command = 0 and = +-1
    trim_cmd = fdm[COMMANDS[control][1]] if model.has(COMMANDS[control][1]) else 0.0
    grid = np.unique(np.concatenate([np.linspace(-2.0, 2.0, 81),
                                     [-trim_cmd, -1.0 - trim_cmd, 1.0 - trim_cmd]]))
    pos = np.empty_like(grid)
    fdm.set_trim_status(True)  # actuators and kinematics follow their input at once
    try:
        for i, c in enumerate(grid):
            fdm[cmd] = c
            fdm.run_ic()
            pos[i] = sign * fdm[prop]
    finally:
        fdm.set_trim_status(False)
        fdm[cmd] = saved
    order = np.argsort(pos, kind="stable")
    pos, cmds = pos[order], grid[order]
    keep = np.concatenate(([True], np.diff(pos) > 1e-12))  # drop saturated plateaus
    if keep.sum() < 2:
        return None
    return pos[keep], cmds[keep]


def hold_center(rate_hz: float) -> float:
    """Where a control given for sample k acts, relative to t_k.

    JSBSim computes the forces of a run after its FCS, so the control set before the run
    that ends at t_k makes the forces at t_k and at every substep up to the next setting,
    t_k + (substeps - 1) h: their middle is (substeps - 1) h / 2, h the internal step. An
    input sampled from a continuous signal is best taken there.

    Parameters
    ----------
    rate_hz : float
        Record rate, Hz.

    Returns
    -------
    float
        The offset from t_k, s.
    """
    n = substeps(rate_hz)
    return (n - 1) / (2.0 * n * rate_hz)


def substeps(rate_hz: float) -> int:
    """JSBSim runs per record interval at ``rate_hz``: at least ``MIN_INTERNAL_HZ``.

    Parameters
    ----------
    rate_hz : float
        Record rate, Hz.

    Returns
    -------
    int
        Runs per record interval, >= 1.
    """
    return max(1, math.ceil(MIN_INTERNAL_HZ / rate_hz - 1e-9))


def interp_point(x: float, xp: Sequence[float], fp: Sequence[float]) -> float:
    """``np.interp`` of one point with numpy's arithmetic (same result, no array overhead).

    Parameters
    ----------
    x : float
        The point.
    xp : sequence of float
        Increasing abscissae.
    fp : sequence of float
        Ordinates; same length as ``xp``.

    Returns
    -------
    float
        The interpolated value, ends held.
    """
    if x <= xp[0]:
        return fp[0]
    if x >= xp[-1]:
        return fp[-1]
    j = bisect_right(xp, x) - 1  # xp[j] <= x < xp[j + 1]
    if xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    y = slope * (x - xp[j]) + fp[j]
    if y != y:  # nan from an infinite slope: numpy retries from the right end
        y = slope * (x - xp[j + 1]) + fp[j + 1]
        if y != y and fp[j] == fp[j + 1]:
            y = fp[j]
    return y


def schedule_writes(schedules: Iterable[tuple[Callable[[float], None], np.ndarray]], n: int
             ) -> list[tuple[tuple[Callable[[float], None], float], ...]]:
    """Per sample k, the (setter, value) pairs to write before it.

    Those whose value differs from sample k - 1, or every sample for a schedule that changes
    at more than a quarter of them.

    Parameters
    ----------
    schedules : iterable of tuple
        (setter, values per sample) pairs.
    n : int
        Number of samples.

    Returns
    -------
    list of tuple
        Per sample, the tuple of (setter, value) pairs.
    """
    dense = []
    sparse: dict[int, list[tuple[Callable[[float], None], float]]] = {}
    for setter, values in schedules:
        values = np.asarray(values, dtype=float)
        changed = np.flatnonzero(values[1:] != values[:-1]) + 1
        if len(changed) > n // 4:
            dense.append(zip(itertools.repeat(setter), values.tolist(), strict=False))
        else:
            for k in changed.tolist():
                sparse.setdefault(k, []).append((setter, float(values[k])))
    out: list[tuple[tuple[Callable[[float], None], float], ...]]
    out = list(zip(*dense, strict=True)) if dense else [()] * n
    for k, pairs in sparse.items():
        out[k] = out[k] + tuple(pairs)
    return out


def sampled_controls(controls: Mapping[str, Control], n: int, rate_hz: float
                     ) -> dict[str, np.ndarray]:
    """Control increments sampled at the record times (arrays checked, callables evaluated).

    Parameters
    ----------
    controls : Mapping of str to Control
        de, da, dr (rad) and throttle (fraction): arrays of at least n samples, callables of
        time (s) or constants.
    n : int
        Number of samples.
    rate_hz : float
        Record rate, Hz.

    Returns
    -------
    dict of str to numpy.ndarray
        Increment per sample, shape (n,), by control.

    Raises
    ------
    ValueError
        For an unknown control, too few samples or non-finite values.
    """
    out: dict[str, np.ndarray] = {}
    t = np.arange(n) / rate_hz
    for name, c in controls.items():
        if name not in ("de", "da", "dr", "throttle"):
            raise ValueError(f"unknown control {name!r}; use de, da, dr, throttle")
        if callable(c):
            arr = np.array([float(c(ti)) for ti in t])
        elif np.isscalar(c):
            arr = np.full(n, float(c))
        else:
            arr = np.asarray(c, dtype=float)
            if arr.ndim != 1 or arr.size < n:
                raise ValueError(
                    f"control {name!r} has {arr.size} samples; {n} needed for the flight "
                    f"({(n - 1) / rate_hz:g} s at {rate_hz:g} Hz, both ends included)"
                )
            arr = arr[:n]
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"control {name!r} has non-finite values")
        out[name] = arr
    return out


def command_schedule(setters: Mapping[str, Callable[[float], None]],
                     maps: Mapping[str, tuple[Sequence[float], Sequence[float]]],
                     trim_cmd: Mapping[str, float], trim_pos: Mapping[str, float],
                     trim_throttle: float, throttle_setters: Sequence[Callable[[float], None]],
                     inputs: Mapping[str, np.ndarray], n: int
                     ) -> list[tuple[Callable[[float], None], np.ndarray]]:
    """(setter, command per sample) of every pilot command node for a whole flight.

    The same mapping as a single step's (a zero increment keeps the trim command exactly),
    one vectorised call per control; the throttle is clipped to 0..1.

    Parameters
    ----------
    setters : Mapping of str to callable
        Control -> the setter of its pilot command node.
    maps : Mapping of str to tuple
        Control -> (surface positions in rad, pilot commands), the FCS map of
        :func:`command_maps`.
    trim_cmd : Mapping of str to float
        The trim's pilot command per control.
    trim_pos : Mapping of str to float
        The trim's surface position per control, rad.
    trim_throttle : float
        The trim's throttle, fraction.
    throttle_setters : sequence of callable
        Setters of the throttle command of each engine.
    inputs : Mapping of str to numpy.ndarray
        Control -> increment per sample (rad; throttle as a fraction).
    n : int
        Number of samples.

    Returns
    -------
    list of tuple
        (setter, command per sample, shape (n,)) pairs.
    """
    out = []
    for c, set_cmd in setters.items():
        inc = inputs.get(c)
        if inc is None or c not in maps:
            cmd = np.full(n, trim_cmd[c])
        else:
            pos, cmds = maps[c]
            cmd = np.where(inc != 0.0, np.interp(trim_pos[c] + inc, pos, cmds), trim_cmd[c])
        out.append((set_cmd, cmd))
    thr = np.clip(trim_throttle + inputs.get("throttle", np.zeros(n)), 0.0, 1.0)
    out.extend((set_thr, thr) for set_thr in throttle_setters)
    return out
