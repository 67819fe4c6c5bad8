"""Engine and propeller vibration (catalogue ``vibration``) on the IMU, driven by the rpm.

Narrowband components at the engine rotation frequency rpm / 60 (Hz), its harmonics
(amplitude ``harmonic_decay`` ** (n - 1)) and the blade-passing frequency ``blades`` x
``gear_ratio`` x rpm / 60 (relative amplitude ``blade_amplitude``). The frequency varies
with the rpm, so the phase is the time integral of 2 pi f. Amplitudes are per axis:
accelerometers ``ax``, ``ay``, ``az`` (m/s^2) and gyros ``p``, ``q``, ``r`` (rad/s, usually
weaker), at ``rpm_ref``; with ``exponent`` > 0 they scale as (rpm / rpm_ref) ** exponent
(2 for a rotating unbalance). Each axis and component has a random phase from the rng.

Telemaster (Sofyan, RMIT thesis, c. 1997, ch. 7, Figs 7-1, 7-2): engine vibration "buried
the rate-gyro signals unless the throttle was at idle". Boomerang 60 (Monash paper, c. 2008):
a 16,000 rpm glow engine (267 Hz) and a 100 Hz IMU, so the vibration aliases (our inference;
the paper does not discuss vibration).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy.integrate import cumulative_trapezoid

from flightid.sim.effects.base import Effect

AXES: tuple[str, ...] = ("ax", "ay", "az", "p", "q", "r")


@dataclass(kw_only=True)
class EngineVibration(Effect):
    """Narrowband engine/propeller vibration on the IMU channels (m/s^2, rad/s amplitudes)."""

    name: ClassVar[str] = "engine_vibration"
    ax: float = 0.0
    ay: float = 0.0
    az: float = 0.0
    p: float = 0.0
    q: float = 0.0
    r: float = 0.0
    harmonics: float = 1.0
    harmonic_decay: float = 0.5
    blades: float = 0.0
    blade_amplitude: float = 0.5
    gear_ratio: float = 1.0
    rpm_ref: float = 0.0
    exponent: float = 0.0

    def __post_init__(self) -> None:
        if self.harmonics < 1 or self.harmonics != int(self.harmonics):
            raise ValueError(f"{self.name}: field 'harmonics' must be a whole number >= 1")
        if self.blades < 0 or self.blades != int(self.blades):
            raise ValueError(f"{self.name}: field 'blades' must be a whole number >= 0")
        if self.exponent != 0 and self.rpm_ref <= 0:
            raise ValueError(f"{self.name}: field 'rpm_ref' must be > 0 when exponent != 0")
        if self.gear_ratio <= 0:
            raise ValueError(f"{self.name}: field 'gear_ratio' must be > 0")

    def components(self) -> tuple[np.ndarray, np.ndarray]:
        """(frequency multiples of the engine rotation, relative amplitudes) of the lines."""
        n = np.arange(1, int(self.harmonics) + 1, dtype=float)
        orders, amps = list(n), list(self.harmonic_decay ** (n - 1))
        if self.blades:
            orders.append(self.blades * self.gear_ratio)
            amps.append(self.blade_amplitude)
        return np.asarray(orders), np.asarray(amps)

    def max_frequency(self, rpm: np.ndarray) -> float:
        """Highest line frequency (Hz) over the record."""
        orders, _ = self.components()
        return float(np.max(np.abs(rpm)) / 60.0 * orders.max())

    def phases(self, rng: np.random.Generator) -> np.ndarray:
        """Random phases (rad), one per axis (``AXES`` order) and component."""
        orders, _ = self.components()
        return rng.uniform(0.0, 2 * np.pi, size=(len(AXES), orders.size))

    def signal(self, t: np.ndarray, rpm: np.ndarray, axis: str, phases: np.ndarray) -> np.ndarray:
        """Vibration on ``axis`` at times ``t`` (s) for engine speed ``rpm`` (1/min) there."""
        if axis not in AXES:
            raise ValueError(f"{self.name}: no vibration axis {axis!r}; axes are {AXES}")
        amp = getattr(self, axis)
        t = np.asarray(t, float)
        if amp == 0:
            return np.zeros_like(t)
        rpm = np.asarray(rpm, float)
        turns = cumulative_trapezoid(rpm / 60.0, t, initial=0.0)  # engine revolutions
        scale = amp * ((np.abs(rpm) / self.rpm_ref) ** self.exponent if self.exponent else 1.0)
        orders, rel = self.components()
        ph = phases[AXES.index(axis)]
        out = np.zeros_like(t)
        for k, (order, a) in enumerate(zip(orders, rel, strict=True)):
            out += a * np.sin(2 * np.pi * order * turns + ph[k])
        return scale * out

    def apply(self, t, x, rng, *, rpm: np.ndarray | None = None, axis: str = "az"):
        """``x`` plus the vibration on ``axis``; ``rpm`` (1/min) on the same times is required."""
        if rpm is None:
            raise ValueError(f"{self.name}: needs the rpm channel (engine speed, 1/min)")
        return x + self.signal(t, rpm, axis, self.phases(rng))
