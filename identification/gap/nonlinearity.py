"""Is there structure the linear test and the catalogue cannot express: a nonlinear or
sticky flow-angle vane, a kink of the pitching moment in alpha.

The window test of ``verdict`` regresses the model's residual on *linear* functions of the
inputs, so an effect that is a nonlinear function of the motion is either not seen or seen
through its linear part only (a quadratic sideslip vane read as a beta scale). Regressing
that residual on nonlinear functions of the simulated outputs was tried first and has no
power here: a vane's nonlinearity acts on the true flow angle, which in light turbulence
is as much gust as maneuver, so it is not a function of the inputs (seed 0: a quadratic
vane at k 5.7 per rad gave p ~ 0.1).

This test looks instead at relations between measured channels that the turbulence obeys
too (equation error: Morelli & Klein 2016 ch. 5; data compatibility, ch. 10): the side
force against the sideslip vane (``ay`` on beta, p, r, ...), the normal acceleration
against the alpha vane (``az`` on alpha, q, ...), the pitch acceleration (``qdot``, the
differentiated q) against alpha, q and the elevator. In each, the target is regressed on:

- the **known** set (``known_regressors``): the axis's measured channels and inputs and
  their rates (a sensor delay or lag, a lever arm: catalogue entries), the airspeed times
  the flow angle, and each surface through a play (the catalogue's ``backlash``) and a
  deadband of ``SURFACE_WIDTHS_RAD`` less the surface;
- a **structure** (``structures``), each saying what it would mean: ``vane_odd``,
  d |d| of the vane (beta; alpha less its median): a calibration beta + k beta |beta|;
  ``vane_play``: play(d, w) - d at the small widths ``PLAY_WIDTHS_RAD`` (the direction the
  vane last moved): a vane with play; ``alpha_kink``: max(alpha - alpha_k, 0) at the
  quantiles ``KNOT_QUANTILES`` of the measured alpha, in the pitch acceleration: a pitching
  moment whose slope changes at a kink.

The statistic is the partial Wald test of the structure's coefficients given the known
set (both regressed on the known set first: Frisch-Waugh-Lovell), with the colored-residual
covariance of ``verdict.channel_test`` (Morelli & Klein 2016 eq. 6.54, the leverage
correction of ``engine.bounds``), on the signals through the main test's high-pass
(``window.regressors.highpass``, which also takes off the biases). A structure is found when its
p-value and its share (the energy it explains beyond the known set, less chance, over what
the known set leaves of the target) pass its ``LEVELS``: the exact JSBSim aircraft is
itself nonlinear (its aerodynamic tables), so the levels are set above what null flights
give (docs/gap.md, "Nonlinear structure").
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.identification.gap.fit import WindowFit
from flightid.identification.gap.verdict import ChannelTest, channel_test
from flightid.identification.gap.window.regressors import highpass
from flightid.record import FlightRecord
from flightid.units import DEG

# per structure: (p-value below which, share at or above which it is found). The share is
# the energy the structure explains beyond the known set, less chance, over what the known
# set leaves of the target. Set on seed 0 of the blind check (docs/gap.md, "Nonlinear
# structure"; 100 null flights): the pitch kink at 1e-10 and 0.2 (null flights: p >= 1e-5,
# shares <= 0.11; breaks: p 1e-14 or less, shares 0.35-0.92); the vane play at 1e-7 and
# 0.03 (null flights reached 1e-6 on the alpha vane); the odd vane term at 1e-40 and 0.1,
# above the c172p's null flights (nothing injected, so its own side force is not linear in
# beta: p to 1e-28, shares to 0.30)
LEVELS = {"vane_odd": (1e-40, 0.1), "vane_play": (1e-7, 0.03), "alpha_kink": (1e-10, 0.2)}
# a linear effect named on a vane (``scale``, ``delay``, ``lag`` of beta or alpha, the
# ``vanes`` mounting) is checked for the same vane's structure at these looser levels
# (``named_sensor``): the named effect says the vane is wrong, and the question is only
# whether linearly (the same scale at small and large angles). Seed 0 (docs/gap_benchmark.md,
# "Naming changes for the seed-7 rules"): quadratic vanes named ``scale(beta)`` gave the odd
# term p 8.6e-5 to 3.1e-6 at shares 0.064-0.107
SENSOR_LEVELS = {"vane_odd": (1e-4, 0.05), "vane_play": (1e-4, 0.02)}
SENSOR_ENTRIES = ("scale", "delay", "lag", "vanes")
PLAY_WIDTHS_RAD = (0.2 * DEG, 0.5 * DEG)  # small plays: the direction the vane last moved
SURFACE_WIDTHS_RAD = (0.5 * DEG, 1.0 * DEG)  # the catalogue's surface backlash, deadband
KNOT_QUANTILES = (0.6, 0.75, 0.9)  # of the measured alpha: where a kink is tried
VANES = {"lateral": "beta", "longitudinal": "alpha"}


@dataclass
class Structure:
    """One structure tested in one relation (``channel``: the vane it is a function of;
    ``test.channel``: the target it is sought in)."""

    name: str  # vane_odd, vane_play, alpha_kink
    channel: str
    test: ChannelTest
    detail: str = ""  # what the structure says, in words (no catalogue entry)

    @property
    def found(self) -> bool:
        """Significant and material beyond the known regressors (``LEVELS``)."""
        return self.test.passes(*LEVELS[self.name])

    def to_json(self) -> dict:
        return {"structure": self.name, "channel": self.channel,
                "target": self.test.channel, "p_value": self.test.p_value,
                "share": self.test.share, "dof": self.test.dof, "found": self.found,
                "says": self.detail}


@dataclass
class NonlinearTest:
    """Every structure's test on the windows of one axis."""

    structures: list[Structure] = field(default_factory=list)
    # structures of a vane on which a linear effect is named (``named_sensor``)
    sensor: list[Structure] = field(default_factory=list)

    @property
    def found(self) -> list[Structure]:
        return [s for s in self.structures if s.found]

    @property
    def gap(self) -> bool:
        """Some structure explains a material part of a channel beyond the known set."""
        return bool(self.found)

    def text(self) -> str:
        """What the residual shows, in words ("" when nothing is found)."""
        said = [s.detail for s in self.found]
        said += [f"the named linear {s.channel} effect leaves {s.detail}: a nonlinear "
                 "sensor" for s in self.sensor]
        return "; ".join(dict.fromkeys(said))

    def to_json(self) -> dict:
        return {"gap": self.gap, "says": self.text() or None,
                "nonlinear_sensor": [s.to_json() for s in self.sensor],
                "structures": [s.to_json() for s in self.structures]}


def named_sensor(test: NonlinearTest, named: Sequence[Any]) -> list[Structure]:
    """The structures of ``test`` on a vane on which one of the ``named`` effects (or a
    part of a named group) is a linear sensor effect (``SENSOR_ENTRIES``), significant and
    material at ``SENSOR_LEVELS``: the vane reads the flow angle nonlinearly, which its named
    scale, delay or lag expresses only in part.

    Parameters
    ----------
    test : NonlinearTest
        The nonlinear-structure test of the model as is.
    named : sequence of Ranked
        The named effects (``ranked.Ranked``).

    Returns
    -------
    list of Structure
        The structures found at the looser levels ([] when none).
    """
    vanes: set[str] = set()
    for r in named:
        for c in r.candidate.parts or (r.candidate,):
            if c.entry == "vanes":
                vanes.update(VANES.values())
            elif c.entry in SENSOR_ENTRIES and c.options.get("channel") in VANES.values():
                vanes.add(c.options["channel"])
    out = []
    for s in test.structures:
        if s.channel in vanes and s.name in SENSOR_LEVELS and not s.found:
            if s.test.passes(*SENSOR_LEVELS[s.name]):
                out.append(s)
    return out


def play(x: np.ndarray, width: float) -> np.ndarray:
    """``x`` through a play (backlash) operator of full ``width``: the output follows the
    input only once it has moved half the width past it (Krasnosel'skii & Pokrovskii 1989).

    Parameters
    ----------
    x : ndarray
        Input time history (any unit).
    width : float
        Full width of the play (the unit of ``x``).

    Returns
    -------
    ndarray
        The output, starting at ``x[0]``.
    """
    half = 0.5 * width
    y = np.empty_like(np.asarray(x, float))
    y[0] = x[0]
    for i in range(1, len(x)):
        y[i] = min(max(y[i - 1], x[i] - half), x[i] + half)
    return y


def deadband(x: np.ndarray, width: float) -> np.ndarray:
    """``x`` through a deadband of full ``width`` around zero.

    Parameters
    ----------
    x : numpy.ndarray
        The signal, any unit.
    width : float
        The deadband's full width, unit of ``x``.

    Returns
    -------
    numpy.ndarray
        The output, unit of ``x``; shape of ``x``.
    """
    half = 0.5 * width
    return np.sign(x) * np.maximum(np.abs(x) - half, 0.0)


# (target channel, vane, structures) per axis: the relation each structure is sought in
EQUATIONS = {"lateral": (("ay", "beta", ("vane_odd", "vane_play")),),
             "longitudinal": (("az", "alpha", ("vane_odd", "vane_play")),
                              ("qdot", "alpha", ("alpha_kink",)))}
DERIVED = {"qdot": "q"}  # a target that is a measured channel's rate
LINEAR = {"lateral": ("beta", "p", "r", "phi", "V"),
          "longitudinal": ("alpha", "q", "theta", "V", "thrust")}


def signals(fit: WindowFit, record: FlightRecord, axis: str,
            inputs: Sequence[str]) -> dict[str, np.ndarray]:
    """The window's measured channels on the fit's time (outputs, inputs, airspeed,
    thrust) and the pitch acceleration ``qdot`` (rad/s^2, differentiated q).

    Parameters
    ----------
    fit : WindowFit
        The model's fit of the window (its time, s, and measured outputs).
    record : FlightRecord
        The window's record (inputs, airspeed, thrust).
    axis : str
        "lateral" or "longitudinal".
    inputs : sequence of str
        The axis's surfaces.

    Returns
    -------
    dict of str to numpy.ndarray
        Channel -> its samples on the fit's time, SI.
    """
    t = fit.time
    out = {c: np.asarray(v, float) for c, v in fit.measured.items()}
    for c in (*LINEAR[axis], *inputs):
        if c not in out and c in record:
            out[c] = np.interp(t, record.time, record[c])
    if "q" in out:
        out["qdot"] = np.gradient(out["q"], t)
    return out


def known_regressors(sig: Mapping[str, np.ndarray], dt: float, axis: str, target: str,
                     inputs: Sequence[str]) -> np.ndarray:
    """What a linear relation and the catalogue's candidates explain of ``target`` (module note).

    The axis's measured channels and inputs, their rates, the airspeed's product with the flow
    angle, each surface through a play and a deadband less itself.

    Parameters
    ----------
    sig : mapping of str to numpy.ndarray
        One window's signals, SI; shape (N,) each.
    dt : float
        Sample interval, s.
    axis : str
        "lateral" or "longitudinal".
    target : str
        The channel explained (left out of its own regressors).
    inputs : sequence of str
        The axis's surfaces.

    Returns
    -------
    numpy.ndarray
        The regressors, means removed; shape (N, k).
    """
    cols: list[np.ndarray] = []
    names = [c for c in (*LINEAR[axis], *inputs) if c in sig and c != target]
    for c in names:
        cols.append(sig[c])
        if DERIVED.get(target) != c:  # the target itself when it is this channel's rate
            cols.append(np.gradient(sig[c], dt))
    vane = VANES[axis]
    if "V" in sig and vane in sig:
        cols.append(sig[vane] * (sig["V"] - np.mean(sig["V"])))
    for s in inputs:
        if s in sig:
            for w in SURFACE_WIDTHS_RAD:
                cols += [play(sig[s], w) - sig[s], deadband(sig[s], w) - sig[s]]
    x = np.column_stack(cols)
    return x - x.mean(axis=0)


def structures(sig: Mapping[str, np.ndarray], center: Mapping[str, Any]
               ) -> dict[str, np.ndarray]:
    """The regressors of each nonlinear structure on one window (module note).

    Parameters
    ----------
    sig : mapping of str to numpy.ndarray
        One window's signals, SI; shape (N,) each.
    center : mapping of str to Any
        The vane channel (``vane``), its reference (``ref``, rad) and the kink knots
        (``knots``, rad), the same on every window.

    Returns
    -------
    dict of str to numpy.ndarray
        {structure name: regressors, means removed, shape (N, k)}; empty when the window lacks
        the vane.
    """
    out: dict[str, np.ndarray] = {}
    vane = center["vane"]
    if vane in sig:
        d = sig[vane] - center["ref"]
        out["vane_odd"] = (d * np.abs(d))[:, None]
        out["vane_play"] = np.column_stack([play(d, w) - d for w in PLAY_WIDTHS_RAD])
        if center.get("knots"):
            out["alpha_kink"] = np.column_stack([np.maximum(sig[vane] - k, 0.0)
                                                 for k in center["knots"]])
    return {k: x - x.mean(axis=0) for k, x in out.items()}


def _residualised(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``y`` less its least-squares projection on the columns of ``x``."""
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    return y - x @ coef


def nonlinear_test(fits: Mapping[str, WindowFit], records: Mapping[str, FlightRecord],
                   inputs: Sequence[str], axis: str) -> NonlinearTest:
    """Each structure's partial Wald test over the windows ``fits`` (their time and
    measured outputs; ``records``: the windows' records, for the inputs, airspeed and
    thrust) of ``axis`` ("lateral" or "longitudinal").

    Parameters
    ----------
    fits : mapping of str to WindowFit
        The model as is on each window (only the nuisance parameters fitted).
    records : mapping of str to FlightRecord
        The windows' records.
    inputs : sequence of str
        The axis's surface channels.
    axis : str
        "lateral" or "longitudinal".

    Returns
    -------
    NonlinearTest
        Every structure tested in its relation; ``found`` the significant, material ones.
    """
    labels = [k for k in fits if k in records]
    out = NonlinearTest()
    if not labels or axis not in EQUATIONS:
        return out
    dts = {k: float(np.median(np.diff(fits[k].time))) for k in labels}
    sigs = {k: signals(fits[k], records[k], axis, inputs) for k in labels}
    for target, vane, names in EQUATIONS[axis]:
        if not all(target in s and vane in s for s in sigs.values()):
            continue
        pooled = np.concatenate([sigs[k][vane] for k in labels])
        center = {"vane": vane, "ref": 0.0 if vane == "beta" else float(np.median(pooled))}
        if "alpha_kink" in names:
            center["knots"] = tuple(float(np.quantile(pooled, q)) for q in KNOT_QUANTILES)
        known = np.vstack([highpass(known_regressors(sigs[k], dts[k], axis, target, inputs),
                                    dts[k]) for k in labels])
        known = known[:, np.sqrt(np.sum(known * known, axis=0)) > 0]
        y = np.concatenate([highpass(sigs[k][target], dts[k]) for k in labels])
        if not np.all(np.isfinite(y)) or not np.all(np.isfinite(known)):
            continue
        y_perp = _residualised(y, known)
        spread = float(np.sum(y_perp * y_perp))  # what the known set leaves
        per = {k: structures(sigs[k], center) for k in labels}
        for name in names:
            if name not in per[labels[0]]:
                continue
            x = np.vstack([highpass(per[k][name], dts[k]) for k in labels])
            x_perp = _residualised(x, known)
            test = channel_test(y_perp, x_perp, spread, target)
            out.structures.append(Structure(name, vane, test,
                                            _says(name, vane, target, center)))
    return out


def _says(name: str, vane: str, target: str, center: Mapping[str, Any]) -> str:
    """The structure in words (never a catalogue entry)."""
    if name == "vane_odd":
        return (f"an odd nonlinear function of {vane}: the {vane} vane against {target} "
                f"(as {vane} + k {vane} |{vane}|)")
    if name == "vane_play":
        return f"a hysteresis (play) on the {vane} vane, seen against {target}"
    if name == "alpha_kink":
        knots = center.get("knots", ())
        lo, hi = (min(knots) / DEG, max(knots) / DEG) if knots else (math.nan, math.nan)
        return (f"a kink in the pitching moment against alpha, between {lo:.1f} and "
                f"{hi:.1f} deg (its slope changes there)")
    return name
