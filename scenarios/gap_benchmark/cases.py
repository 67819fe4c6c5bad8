"""What the blind check draws: an aircraft, an effect and a moderate magnitude per case.

Effects of the catalogue the diagnosis has candidates for (lateral axis): a
``derivative_delta`` of 30-50 % of the aircraft's own value (body axes, sign drawn; at
most half, so no sizeable derivative changes sign; of ``DELTA_SCALE`` where the value is
smaller, and then in the stabilising direction: a telemaster whose Cn_beta of -0.003 is
made -0.012 departs, not a case a flight test flies), a ``control_effectiveness`` factor
of 0.6-0.8 on the aileron or the rudder, a sensor ``scale`` of 1.15-1.30 on p, r or beta.
Outside the catalogue (about one case in five): a structural mode seen by the rate gyros and the
lateral accelerometer, or a nonlinear sideslip vane (``outside.py``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from flightid.identification.gap.candidates import OUTPUTS, SURFACES
from flightid.identification.gap.linearise import DERIVATIVES as MODELLED


@dataclass(frozen=True)
class Flight:
    """The lateral test flight of one aircraft: condition and inputs (``run.card``: each
    surface moved twice, so that an effect of one surface can be checked on a maneuver
    held out of its fit)."""

    altitude_m: float
    speed_m_s: float
    flaps_deg: float
    aileron_deg: float
    rudder_deg: float
    base_s: float  # pulse width of the doublet and the 2-1-1's unit


AIRCRAFT: dict[str, Flight] = {
    "navion": Flight(1500.0, 55.0, 0.0, 4.0, 4.0, 1.0),
    "twinotter": Flight(1890.0, 72.2, 0.0, 6.0, 2.8, 1.0),
    "telemaster": Flight(30.0, 15.0, 0.0, 2.0, 1.5, 0.5),
}
DERIVATIVES = ("Cn_beta", "Cl_beta", "Cn_r", "Cl_p", "Cl_r", "CY_beta", "Cl_da", "Cn_dr")
DELTA_FRACTION = (0.3, 0.5)
# the least |derivative| a delta is a fraction of (body axes, per rad): a derivative near
# zero (the telemaster's Cn_beta, -0.003) still gets a delta a flight test would notice
DELTA_SCALE = {"Cn_beta": 0.03, "Cl_beta": 0.03, "Cn_r": 0.05, "Cl_p": 0.1, "Cl_r": 0.03,
               "CY_beta": 0.1, "Cl_da": 0.05, "Cn_dr": 0.03}
# the stable sign of the derivatives a near-zero value may not be pushed away from
# (directional and dihedral stability, yaw and roll damping, side-force slope)
STABLE_SIGN = {"Cn_beta": 1.0, "Cl_beta": -1.0, "Cn_r": -1.0, "Cl_p": -1.0, "CY_beta": -1.0}
FACTOR = (0.6, 0.8)
SCALE = (1.15, 1.30)
SCALED = ("p", "r", "beta")
OUTSIDE_SHARE = 0.2
# in-catalogue kinds and their shares
KINDS = (("derivative_delta", 0.6), ("control_effectiveness", 0.2), ("scale", 0.2))


@dataclass(frozen=True)
class Case:
    """One blind case: what is injected (the diagnosis is not told)."""

    index: int
    seed: int  # the flight's noise seed
    aircraft: str
    entry: str  # catalogue entry, or the name of an effect outside it
    options: dict[str, str] = field(default_factory=dict)
    magnitude: dict[str, float] = field(default_factory=dict)  # catalogue units
    in_catalogue: bool = True

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @property
    def label(self) -> str:
        opts = ",".join(self.options.values())
        mag = ", ".join(f"{k} {v:.4g}" for k, v in self.magnitude.items())
        return f"{self.aircraft}: {self.entry}({opts}) {mag}"


def draw(n: int, seed: int, truths: dict[str, dict[str, float]]) -> list[Case]:
    """``n`` cases from ``seed``; ``truths``: each aircraft's body-axis derivatives at its
    condition (the magnitudes are fractions of them)."""
    rng = np.random.default_rng(seed)
    names = list(AIRCRAFT)
    # only what the diagnosis has candidates for (looked up, not assumed)
    derivs = [d for d in DERIVATIVES if d in MODELLED]
    surfaces = [s for s in ("da", "dr") if s in SURFACES]
    scaled = [c for c in SCALED if c in OUTPUTS]
    out = []
    for i in range(n):
        aircraft = names[int(rng.integers(len(names)))]
        flight_seed = int(rng.integers(2**31))
        if rng.random() < OUTSIDE_SHARE:
            out.append(_outside(i, flight_seed, aircraft, rng))
            continue
        kind = rng.choice([k for k, _ in KINDS], p=[w for _, w in KINDS])
        if kind == "derivative_delta":
            d = str(rng.choice(derivs))
            value = truths[aircraft][d]
            sign = float(rng.choice([-1, 1]))
            if abs(value) < DELTA_SCALE[d] and d in STABLE_SIGN:
                sign = STABLE_SIGN[d]  # (drawn all the same: the other cases stay as they were)
            delta = sign * rng.uniform(*DELTA_FRACTION) * max(abs(value), DELTA_SCALE[d])
            out.append(Case(i, flight_seed, aircraft, "derivative_delta",
                            {"derivative": d, "axes": "body"}, {"delta": float(delta)}))
        elif kind == "control_effectiveness":
            s = str(rng.choice(surfaces))
            out.append(Case(i, flight_seed, aircraft, "control_effectiveness", {"surface": s},
                            {"factor": float(rng.uniform(*FACTOR))}))
        else:
            ch = str(rng.choice(scaled))
            out.append(Case(i, flight_seed, aircraft, "scale", {"channel": ch},
                            {"factor": float(rng.uniform(*SCALE))}))
    return out


def _outside(i: int, seed: int, aircraft: str, rng: np.random.Generator) -> Case:
    if rng.random() < 0.5:
        return Case(i, seed, aircraft, "structural_mode", {},
                    {"frequency_hz": float(rng.uniform(3.0, 6.0)),
                     "damping": float(rng.uniform(0.02, 0.05)),
                     "gain": float(rng.uniform(0.5, 1.0))}, in_catalogue=False)
    return Case(i, seed, aircraft, "vane_nonlinearity", {"channel": "beta"},
                {"k": float(rng.uniform(4.0, 8.0))}, in_catalogue=False)
