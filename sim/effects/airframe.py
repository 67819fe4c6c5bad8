"""Airframe and actuator effects: the parameters an augmented JSBSim aircraft is written from.

Each class is one entry of the effect catalogue (``flightid.sim.effects.catalogue``,
``acts on`` airframe or actuator); ``flightid.sim.augment.writer.augment`` writes them into
a copy of an aircraft's JSBSim XML. They are ``NamedEffect``s like the catalogue's other
effects (float parameters in SI units, string options, a ``source``). A card names them
in ``[[effect]]`` tables by ``name``.

Derivative deltas are nondimensional, per rad (angles, surfaces) or per unit of the
nondimensional rate (phat = p b/2V, qhat = q cbar/2V, rhat = r b/2V, alphadot cbar/2V),
in the axes of ``axes``: ``stability`` (CL, CD, CY; Cl, Cm, Cn about the stability axes
of the current alpha, stability-axis rates) or ``body`` (CX, CY, CZ; Cl, Cm, Cn, body rates).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

from flightid.channels import CONTROL_SURFACES
from flightid.sim.effects.base import NamedEffect

SURFACE_CHOICES = CONTROL_SURFACES
AXES_CHOICES = ("stability", "body")
# coefficient letters (flightid.derivatives) per axes and variables a delta can act on
COEFS = {"stability": ("L", "D", "Y", "l", "m", "n"), "body": ("X", "Y", "Z", "l", "m", "n")}
# a delta's dependence on its variable: linear, or even (on |variable|: the one-sided slopes
# differ by 2 delta, as a table written for |beta| has them)
FORM_CHOICES = ("linear", "even")
VARIABLES = ("0", "alpha", "beta", "p", "q", "r", "alphadot", "de", "da", "dr")
DERIVATIVES: tuple[str, ...] = tuple(dict.fromkeys(
    f"C{c}_{v}" for axes in AXES_CHOICES for c in COEFS[axes] for v in VARIABLES))


@dataclass(kw_only=True)
class AugmentEffect(NamedEffect):
    """Base: a named effect written into a JSBSim aircraft (float parameters in SI)."""

    key: ClassVar[str] = "name"  # the card-table key that names the effect ([[effect]])

    def options(self) -> dict[str, str]:
        """String options by name (e.g. the surface)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name != "source" and isinstance(getattr(self, f.name), str)}

    def neutral(self) -> bool:
        """True when the effect does nothing (written as a comment only)."""
        raise NotImplementedError

    def label(self) -> str:
        """One line for the XML comment and the record: name, options and magnitudes."""
        opts = " ".join(f"{k}={v}" for k, v in self.options().items())
        vals = " ".join(f"{k}={v:.6g}" for k, v in self.parameters().items())
        return f"{self.name} {opts} {vals}".replace("  ", " ").strip()

    def _choice(self, field: str, choices: tuple[str, ...]) -> None:
        if getattr(self, field) not in choices:
            raise ValueError(f"{self.name}: field {field!r} must be one of "
                             f"{', '.join(choices)}, got {getattr(self, field)!r}")

    def _require_finite(self, *fields: str) -> None:
        for f in fields:
            v = getattr(self, f)
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"{self.name}: field {f!r} must be finite, got {v!r}")


# -- airframe ------------------------------------------------------------------------------


@dataclass(kw_only=True)
class DerivativeDelta(AugmentEffect):
    """An additive delta to one derivative: an extra <function> term in the aero axes."""

    name: ClassVar[str] = "derivative_delta"
    delta: float = 0.02
    derivative: str = "Cn_beta"
    axes: str = "stability"
    form: str = "linear"  # "linear": delta x variable; "even": delta x |variable|

    def __post_init__(self) -> None:
        self._choice("axes", AXES_CHOICES)
        self._choice("form", FORM_CHOICES)
        self._require_finite("delta")
        ok = tuple(f"C{c}_{v}" for c in COEFS[self.axes] for v in VARIABLES)
        if self.derivative not in ok:
            raise ValueError(f"{self.name}: field 'derivative': {self.derivative!r} is not a "
                             f"derivative in {self.axes} axes; one of {', '.join(ok)}")

    def neutral(self) -> bool:
        return self.delta == 0.0


SCHEDULE_CHOICES = ("airspeed", "alpha")


@dataclass(kw_only=True)
class DerivativeTable(AugmentEffect):
    """A delta to one derivative that depends on the condition: a JSBSim <table> in the
    true airspeed (m/s) or the angle of attack (rad), ``delta_low`` at ``low`` and below,
    ``delta_high`` at ``high`` and above, linear between (a table clamps at its ends)."""

    name: ClassVar[str] = "derivative_table"
    delta_low: float = 0.02
    delta_high: float = -0.02
    low: float = 50.0
    high: float = 75.0
    derivative: str = "Cn_beta"
    axes: str = "stability"
    schedule: str = "airspeed"

    def __post_init__(self) -> None:
        self._choice("axes", AXES_CHOICES)
        self._choice("schedule", SCHEDULE_CHOICES)
        self._require_finite("delta_low", "delta_high", "low", "high")
        ok = tuple(f"C{c}_{v}" for c in COEFS[self.axes] for v in VARIABLES)
        if self.derivative not in ok:
            raise ValueError(f"{self.name}: field 'derivative': {self.derivative!r} is not a "
                             f"derivative in {self.axes} axes; one of {', '.join(ok)}")
        if not self.high > self.low:
            raise ValueError(f"{self.name}: field 'high' ({self.high:g}) must be above "
                             f"'low' ({self.low:g})")
        if self.schedule == "alpha" and self.derivative.endswith(("_alpha", "_alphadot")):
            # the term delta(alpha) alpha would have the slope delta + alpha delta'(alpha)
            raise ValueError(f"{self.name}: field 'schedule': {self.derivative} cannot be "
                             "scheduled in alpha (its own variable); schedule it in airspeed")

    def neutral(self) -> bool:
        return self.delta_low == 0.0 and self.delta_high == 0.0

    def at(self, x: float) -> float:
        """The delta at ``x`` (m/s or rad, as ``schedule``): the table's value."""
        w = min(1.0, max(0.0, (x - self.low) / (self.high - self.low)))
        return self.delta_low + w * (self.delta_high - self.delta_low)


@dataclass(kw_only=True)
class ControlEffectiveness(AugmentEffect):
    """Every aerodynamic term that depends on a surface scaled by a factor."""

    name: ClassVar[str] = "control_effectiveness"
    factor: float = 0.8
    surface: str = "de"

    def __post_init__(self) -> None:
        self._choice("surface", SURFACE_CHOICES)
        self._require_finite("factor")

    def neutral(self) -> bool:
        return self.factor == 1.0


@dataclass(kw_only=True)
class CgOffset(AugmentEffect):
    """The CG moved (body axes: x forward, z down), every mass item with it."""

    name: ClassVar[str] = "cg_offset"
    x: float = 0.05
    z: float = 0.0

    def __post_init__(self) -> None:
        self._require_finite("x", "z")

    def neutral(self) -> bool:
        return self.x == 0.0 and self.z == 0.0


@dataclass(kw_only=True)
class MassScale(AugmentEffect):
    """Empty weight and point masses scaled (fuel unchanged)."""

    name: ClassVar[str] = "mass_scale"
    factor: float = 1.1

    def __post_init__(self) -> None:
        self._require_finite("factor")
        if not self.factor > 0:
            raise ValueError(f"{self.name}: field 'factor' must be > 0, got {self.factor}")

    def neutral(self) -> bool:
        return self.factor == 1.0


@dataclass(kw_only=True)
class InertiaScale(AugmentEffect):
    """Moments of inertia scaled (Ixz by sqrt(ixx izz))."""

    name: ClassVar[str] = "inertia_scale"
    ixx: float = 1.1
    iyy: float = 1.1
    izz: float = 1.1

    def __post_init__(self) -> None:
        self._require_finite("ixx", "iyy", "izz")
        for f in ("ixx", "iyy", "izz"):
            if not getattr(self, f) > 0:
                raise ValueError(f"{self.name}: field {f!r} must be > 0, got {getattr(self, f)}")

    def neutral(self) -> bool:
        return self.ixx == self.iyy == self.izz == 1.0


@dataclass(kw_only=True)
class ThrustMoment(AugmentEffect):
    """A pitching moment proportional to the thrust (thrust line off the CG, propwash)."""

    name: ClassVar[str] = "thrust_moment"
    arm: float = 0.1

    def __post_init__(self) -> None:
        self._require_finite("arm")

    def neutral(self) -> bool:
        return self.arm == 0.0


@dataclass(kw_only=True)
class TailIce(AugmentEffect):
    """Horizontal-tail ice: the pitching-moment terms scaled by what they read.

    ``elevator`` scales the pitching-moment terms that read the elevator (Cm_de),
    ``stability`` those that read alpha (Cm_alpha), ``damping`` those that read the pitch
    rate or alphadot (Cm_q, Cm_alphadot). The defaults are the project's iced Twin Otter
    (``twinotter-iced``: Cm_de x 0.85, Cm_alpha and Cm_q x 0.9, chosen from the text of
    Batterson & O'Mara, NASA TM-4099, 1989). Lift and drag terms are left as they are.
    """

    name: ClassVar[str] = "tail_ice"
    elevator: float = 0.85
    stability: float = 0.9
    damping: float = 0.9

    def __post_init__(self) -> None:
        self._require_finite("elevator", "stability", "damping")

    def neutral(self) -> bool:
        return self.elevator == self.stability == self.damping == 1.0


# -- actuator --------------------------------------------------------------------------------


@dataclass(kw_only=True)
class _Surface(AugmentEffect):
    surface: str = "de"

    def __post_init__(self) -> None:
        self._choice("surface", SURFACE_CHOICES)


@dataclass(kw_only=True)
class ActuatorLag(_Surface):
    """First-order lag 1/(tau s + 1) in series with the surface's actuator."""

    name: ClassVar[str] = "actuator_lag"
    tau: float = 0.05

    def neutral(self) -> bool:
        return self.tau == 0.0


@dataclass(kw_only=True)
class RateLimit(_Surface):
    """Surface rate limit in series with the surface's actuator."""

    name: ClassVar[str] = "rate_limit"
    rate: float = math.radians(20.0)

    def neutral(self) -> bool:
        return math.isinf(self.rate)


@dataclass(kw_only=True)
class Deadband(_Surface):
    """Deadband between the measured surface position and the surface the air sees."""

    name: ClassVar[str] = "deadband"
    width: float = math.radians(0.5)

    def neutral(self) -> bool:
        return self.width == 0.0


@dataclass(kw_only=True)
class Backlash(_Surface):
    """Backlash (hysteresis) between the measured surface position and the surface."""

    name: ClassVar[str] = "backlash"
    width: float = math.radians(0.5)

    def neutral(self) -> bool:
        return self.width == 0.0


@dataclass(kw_only=True)
class ActuatorBias(_Surface):
    """Rigging bias: the surface the air sees is offset from the measured position."""

    name: ClassVar[str] = "actuator_bias"
    bias: float = math.radians(0.5)

    def neutral(self) -> bool:
        return self.bias == 0.0


AIRFRAME_EFFECTS = (DerivativeDelta, DerivativeTable, ControlEffectiveness, CgOffset, MassScale,
                    InertiaScale, ThrustMoment, TailIce)
ACTUATOR_EFFECTS = (ActuatorLag, RateLimit, Deadband, Backlash, ActuatorBias)
# in series at the surface position (what the record's de/da/dr shows)
DYNAMIC = (ActuatorLag, RateLimit)
# between the measured position and the aerodynamics (the linkage)
LINKAGE = (Deadband, Backlash, ActuatorBias)
