"""Mounting effects (catalogue ``mounting``): where a sensor sits changes what it measures.

They act on several channels of the truth record at once, before the per-channel chains
of ``flightid.sim.sensors.suites.measure``: ``LeverArm`` (accelerometers away from the CG) and
``Vanes`` (alpha and beta vanes on a boom, with upwash and sidewash).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from flightid.sim.effects.base import NamedEffect


@dataclass(kw_only=True)
class MountingEffect(NamedEffect):
    """Base of the effects that act on several channels of the record at once."""

    requires: ClassVar[tuple[str, ...]] = ()

    def apply_record(
        self, t: np.ndarray, channels: dict[str, np.ndarray], rng: np.random.Generator
    ) -> dict[str, np.ndarray]:
        """The channels this effect changes, computed from ``channels`` on times ``t`` (s)."""
        raise NotImplementedError

    def check(self, channels: dict[str, np.ndarray]) -> None:
        """Raise naming the missing channels this effect needs."""
        missing = [c for c in self.requires if c not in channels]
        if missing:
            raise ValueError(
                f"{self.name} needs truth channels {', '.join(missing)}, which the record lacks"
            )


def _rate_derivative(t: np.ndarray, channels: dict[str, np.ndarray], name: str, of: str):
    if name in channels:
        return channels[name]
    return np.gradient(channels[of], t)  # numerical derivative when the truth lacks it


@dataclass(kw_only=True)
class LeverArm(MountingEffect):
    """Accelerometers at (x, y, z) m from the CG, body axes (x fwd, y right, z down).

    a_sensor = a_cg + omega_dot x r + omega x (omega x r) (Morelli & Klein 2016, eq.
    10.9; the CG transfer of Cooper, Drobik & Martin, ARL Flight Mechanics Report 187,
    1990). Needs p, q, r; pdot, qdot, rdot are differentiated from the rates if the truth
    lacks them. Gyros are unaffected.
    """

    name: ClassVar[str] = "lever_arm"
    requires: ClassVar[tuple[str, ...]] = ("ax", "ay", "az", "p", "q", "r")
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0

    def apply_record(self, t, channels, rng):
        self.check(channels)
        p, q, r = channels["p"], channels["q"], channels["r"]
        pd = _rate_derivative(t, channels, "pdot", "p")
        qd = _rate_derivative(t, channels, "qdot", "q")
        rd = _rate_derivative(t, channels, "rdot", "r")
        x, y, z = self.x, self.y, self.z
        c1, c2, c3 = q * z - r * y, r * x - p * z, p * y - q * x  # omega x r
        return {
            "ax": channels["ax"] + (qd * z - rd * y) + (q * c3 - r * c2),
            "ay": channels["ay"] + (rd * x - pd * z) + (r * c1 - p * c3),
            "az": channels["az"] + (pd * y - qd * x) + (p * c2 - q * c1),
        }


@dataclass(kw_only=True)
class Vanes(MountingEffect):
    """Alpha and beta vanes at body positions (m) with upwash and sidewash factors.

    The local air velocity at a vane is V_cg + omega x r_vane, so to first order
    alpha_v = alpha - x_a q / V + y_a p / V and beta_v = beta + x_b r / V - z_b p / V
    (Cooper, Drobik & Martin, ARL Flight Mechanics Report 187, 1990, App. I/J:
    alpha_m = K_a (alpha - x_a q / V), beta_m = K_b (beta - z_b p / V + x_b r / V);
    Morelli & Klein 2016, 10.2). Computed exactly from the local velocity, then scaled by
    (1 + upwash) and (1 + sidewash): the flow-amplification K of that report.
    """

    name: ClassVar[str] = "vanes"
    requires: ClassVar[tuple[str, ...]] = ("V", "alpha", "beta", "p", "q", "r")
    alpha_x: float = 0.0
    alpha_y: float = 0.0
    alpha_z: float = 0.0
    beta_x: float = 0.0
    beta_y: float = 0.0
    beta_z: float = 0.0
    upwash: float = 0.0
    sidewash: float = 0.0

    def apply_record(self, t, channels, rng):
        self.check(channels)
        V, a, b = channels["V"], channels["alpha"], channels["beta"]
        p, q, r = channels["p"], channels["q"], channels["r"]
        u, v, w = V * np.cos(a) * np.cos(b), V * np.sin(b), V * np.sin(a) * np.cos(b)

        def local(x: float, y: float, z: float) -> tuple[np.ndarray, ...]:
            return u + q * z - r * y, v + r * x - p * z, w + p * y - q * x

        ua, _, wa = local(self.alpha_x, self.alpha_y, self.alpha_z)
        ub, vb, wb = local(self.beta_x, self.beta_y, self.beta_z)
        alpha_v = np.arctan2(wa, ua)
        beta_v = np.arcsin(np.clip(vb / np.sqrt(ub**2 + vb**2 + wb**2), -1.0, 1.0))
        return {"alpha": (1 + self.upwash) * alpha_v, "beta": (1 + self.sidewash) * beta_v}


MISALIGNMENT_AXES = ("x", "y", "z")
# which triad components a rotation about each body axis mixes: (first, second) of the
# gyros and of the accelerometers (the third component is unchanged)
_MIXED = {"x": (("q", "r"), ("ay", "az")), "y": (("r", "p"), ("az", "ax")),
          "z": (("p", "q"), ("ax", "ay"))}


@dataclass(kw_only=True)
class Misalignment(MountingEffect):
    """The IMU triad (rate gyros and accelerometers, one rigid block) rotated by ``angle``
    (rad, right-handed) about the body ``axis``: each measured vector is the true one in
    the rotated axes, v_s = C v_b with C the direction cosine matrix of a single rotation
    (Stevens, Lewis & Johnson 2016, eq. 1.3-18; Etkin & Reid 1996 §4.4): about y,
    p_s = cos(a) p - sin(a) r, r_s = sin(a) p + cos(a) r, and ax, az alike. The flow
    angles, attitudes and air data are unchanged."""

    name: ClassVar[str] = "misalignment"
    requires: ClassVar[tuple[str, ...]] = ("p", "q", "r", "ax", "ay", "az")
    angle: float = 0.0
    axis: str = "y"

    def __post_init__(self) -> None:
        if self.axis not in MISALIGNMENT_AXES:
            raise ValueError(f"{self.name}: field 'axis' must be one of "
                             f"{', '.join(MISALIGNMENT_AXES)}, got {self.axis!r}")
        if not np.isfinite(self.angle):
            raise ValueError(f"{self.name}: field 'angle' must be finite, got {self.angle}")

    def apply_record(self, t, channels, rng):
        self.check(channels)
        c, s = np.cos(self.angle), np.sin(self.angle)
        out = {}
        # C about the axis, for the cyclic order (axis, first, second):
        # first_s = c first + s second, second_s = -s first + c second
        for first, second in _MIXED[self.axis]:
            a, b = channels[first], channels[second]
            out[first], out[second] = c * a + s * b, -s * a + c * b
        return out
