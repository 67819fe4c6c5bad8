"""A derivative error's trend over flight conditions (``trend``), for the diagnosis across
the envelope (``envelope``): the deltas fitted at each condition (``Point``) with a
straight line in airspeed and in trim alpha by weighted least squares (``line``), and the
catalogue effect the trend names: a ``derivative_table`` when the slope is beyond
``TREND_SIGMAS`` of its bound, else one ``derivative_delta`` (the inverse-variance mean),
within the derivative's physical range at every condition (``candidates.ranges``). The
weights are the inverse variances of the points' Cramer-Rao bounds; the covariance is
scaled by the reduced chi-square where it exceeds one (the Birge ratio; Bevington &
Robinson 2003 sec. 6.5).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.identification.gap.candidates.ranges import derivative_outside

TREND_SIGMAS = 3.0  # a slope beyond this many of its bound is a trend
SCHEDULES = {"airspeed": ("m/s", 1.0), "alpha": ("deg", 180.0 / math.pi)}  # unit, scale


@dataclass
class Point:
    """One condition's fitted delta of a derivative (the model's axes at that condition)."""

    condition: str
    speed_m_s: float  # the condition's trim airspeed
    alpha: float  # the model's trim alpha there, rad
    model: float  # the model's derivative there
    delta: float
    std: float

    def to_json(self) -> dict[str, Any]:
        return {"condition": self.condition, "speed_m_s": self.speed_m_s,
                "alpha_deg": math.degrees(self.alpha), "model": self.model,
                "delta": self.delta, "std": self.std}


@dataclass
class Line:
    """delta = level + slope (x - center), fitted by weighted least squares."""

    schedule: str  # "airspeed" (x in m/s) or "alpha" (x in rad)
    center: float
    level: float
    level_std: float
    slope: float  # per m/s or per rad
    slope_std: float
    chi2: float  # weighted residual sum of squares of the points about the line
    scaled: float  # the factor the bounds were scaled by (1, or sqrt of the reduced chi2)

    def at(self, x: float) -> float:
        return self.level + self.slope * (x - self.center)


def line(x: np.ndarray, y: np.ndarray, std: np.ndarray, schedule: str) -> Line:
    """The weighted straight line through the points (module docstring, step 3).

    Parameters
    ----------
    x : ndarray
        The schedule's values (m/s, or rad for alpha).
    y, std : ndarray
        The deltas and their bounds (per rad, or per unit nondimensional rate).
    schedule : str
        "airspeed" or "alpha".

    Returns
    -------
    Line
        Level at the weighted mean x and slope (per m/s or per rad), with bounds scaled
        by the Birge ratio where the points scatter beyond theirs; with two points,
        exactly through them, its bounds from theirs.
    """
    w = 1.0 / std**2
    center = float(np.sum(w * x) / np.sum(w))
    X = np.column_stack([np.ones_like(x), x - center])
    cov = np.linalg.inv(X.T @ (w[:, None] * X))
    beta = cov @ X.T @ (w * y)
    chi2 = float(np.sum(w * (y - X @ beta) ** 2))
    dof = x.size - 2
    scale = math.sqrt(chi2 / dof) if dof > 0 and chi2 > dof else 1.0
    return Line(schedule, center, float(beta[0]), scale * math.sqrt(cov[0, 0]),
                float(beta[1]), scale * math.sqrt(cov[1, 1]), chi2, scale)


@dataclass
class Trend:
    """A derivative's delta across the conditions, and the catalogue effect it names."""

    axis: str
    derivative: str
    axes: str  # of the delta: the axis's model axes (body lateral, stability longitudinal)
    points: list[Point]
    lines: dict[str, Line] = field(default_factory=dict)  # per schedule
    schedule: str = ""  # the kept line's ("" with one point)
    # the named effect in the catalogue's units: {"name", "options", "parameters"}
    effect: dict[str, Any] = field(default_factory=dict)
    note: str = ""  # outside the physical range, or why no trend
    mean: float = math.nan  # the inverse-variance mean delta
    mean_std: float = math.nan

    @property
    def line(self) -> Line | None:
        return self.lines.get(self.schedule)

    @property
    def significant(self) -> bool:
        """The kept line's slope is beyond ``TREND_SIGMAS`` of its bound."""
        ln = self.line
        return ln is not None and abs(ln.slope) > TREND_SIGMAS * ln.slope_std

    def slope_text(self) -> str:
        """'-0.00118 +- 0.00004 per m/s' (alpha: per deg)."""
        ln = self.line
        if ln is None:
            return "one condition: no trend"
        unit, scale = SCHEDULES[ln.schedule]
        return f"{ln.slope / scale:+.3g} ± {ln.slope_std / scale:.2g} per {unit}"

    def label(self) -> str:
        e = self.effect
        opts = ",".join(str(v) for v in e.get("options", {}).values())
        return f"{e.get('name', '?')}({opts})"

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "axis": self.axis, "derivative": self.derivative, "axes": self.axes,
            "points": [p.to_json() for p in self.points], "schedule": self.schedule or None,
            "named": self.effect, "significant": self.significant, "note": self.note or None,
            "mean": {"value": self.mean, "std": self.mean_std}, "lines": {}}
        for s, ln in self.lines.items():
            unit, scale = SCHEDULES[s]
            out["lines"][s] = {"slope": ln.slope / scale, "slope_std": ln.slope_std / scale,
                               "unit": f"per {unit}", "level": ln.level,
                               "level_std": ln.level_std, "at": ln.center * scale,
                               "chi2": ln.chi2, "bounds_scaled_by": ln.scaled}
        return out


def _x(point: Point, schedule: str) -> float:
    return point.speed_m_s if schedule == "airspeed" else point.alpha


def trend(axis: str, derivative: str, axes: str, points: list[Point]) -> Trend:
    """The trend of ``derivative``'s delta over ``points`` and the effect it names
    (module docstring, step 3).

    Parameters
    ----------
    axis : str
        "lateral" or "longitudinal": the axis whose model the deltas are fitted on.
    derivative : str
        The derivative, e.g. "Cn_beta".
    axes : str
        Axes of the deltas: "body" (lateral) or "stability" (longitudinal).
    points : list of Point
        One per condition.

    Returns
    -------
    Trend
        The lines in airspeed and alpha, the schedule kept, and the catalogue effect
        named (``derivative_table`` when the slope is beyond ``TREND_SIGMAS`` bounds,
        else ``derivative_delta``), with a note when outside the physical range.
    """
    out = Trend(axis, derivative, axes, points)
    d = np.array([p.delta for p in points])
    s = np.array([p.std for p in points])
    w = 1.0 / s**2
    out.mean, out.mean_std = float(np.sum(w * d) / np.sum(w)), float(1.0 / math.sqrt(np.sum(w)))
    options = {"derivative": derivative, "axes": axes}
    if len(points) >= 2:
        for schedule in SCHEDULES:
            x = np.array([_x(p, schedule) for p in points])
            if np.ptp(x) > 0:
                out.lines[schedule] = line(x, d, s, schedule)
    if out.lines:  # the schedule whose line fits the points better (airspeed on a tie)
        out.schedule = min(out.lines, key=lambda k: (out.lines[k].chi2, k != "airspeed"))
    if out.significant:
        ln = out.line
        xs = [_x(p, out.schedule) for p in points]
        lo, hi = min(xs), max(xs)
        out.effect = {"name": "derivative_table",
                      "options": {**options, "schedule": out.schedule},
                      "parameters": {"delta_low": ln.at(lo), "delta_high": ln.at(hi),
                                     "low": lo, "high": hi}}
        deltas = [(p, ln.at(_x(p, out.schedule))) for p in points]
    else:
        out.effect = {"name": "derivative_delta", "options": options,
                      "parameters": {"delta": {"value": out.mean, "std": out.mean_std}}}
        out.note = ("one condition: the trend is not identifiable; records at other "
                    "airspeeds or alphas make it so" if len(points) < 2 else
                    f"no trend: slope {out.slope_text()}, within {TREND_SIGMAS:g} bounds")
        deltas = [(p, out.mean) for p in points]
    ranges = [_outside(derivative, p, v) for p, v in deltas]
    if found := [r for r in ranges if r]:
        out.note = "outside its physical range: " + "; ".join(found)
    return out


def _outside(derivative: str, point: Point, delta: float) -> str | None:
    found = derivative_outside(derivative, point.model + delta)
    return f"at {point.condition}: {found}" if found else None
