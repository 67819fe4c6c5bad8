"""Scaling and comparing input designs at equal energy (Morelli & Klein 2016, ch. 9):
``scale_amplitude``, the input ``energy``, its ``spectrum`` and ``scale_to_energy``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from flightid.scenarios.input_design import InputDesign, check_time
from flightid.scenarios.inputs import Maneuvers


def scale_amplitude(design: InputDesign, c: float) -> InputDesign:
    """A copy of ``design`` with its amplitude(s) times ``c`` (every part of a Maneuvers);
    ValueError naming the design when it has no amplitude to scale.

    Parameters
    ----------
    design : InputDesign
        The design to scale.
    c : float
        Scale factor, 1.

    Returns
    -------
    InputDesign
        The scaled copy.
    """
    if isinstance(design, Maneuvers):
        return dataclasses.replace(design, parts=tuple(scale_amplitude(d, c)
                                                        for d in design.parts))
    changes: dict[str, Any] = {}
    for f in dataclasses.fields(design):
        if f.name == "amplitude" or f.name == "amplitudes":
            v = getattr(design, f.name)
            changes[f.name] = tuple(c * a for a in v) if isinstance(v, tuple) else c * v
    if not changes:
        raise ValueError(f"{design.kind!r} has no amplitude to scale")
    return dataclasses.replace(design, **changes)


# -- comparing designs -------------------------------------------------------------


def _uniform_dt(t: np.ndarray) -> float:
    t = check_time(t)
    if t.size < 2:
        raise ValueError("need at least two samples")
    dt = np.diff(t)
    if np.ptp(dt) > 1e-6 * dt.mean():
        raise ValueError("spectrum needs uniformly sampled time")
    return float(dt.mean())


def energy(t: np.ndarray, u: np.ndarray) -> float:
    """Input energy: the integral of u^2 dt (rad^2 s), trapezoidal rule.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s; shape (n,).
    u : numpy.ndarray
        Signal, rad (or its unit); shape (n,).

    Returns
    -------
    float
        Energy, rad^2 s (unit^2 s).
    """
    t = check_time(t)
    u = np.asarray(u, float)
    if u.shape != t.shape:
        raise ValueError(f"u has shape {u.shape}, t has {t.shape}")
    return float(np.trapezoid(u**2, t))


def spectrum(t: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One-sided energy spectral density of ``u``: (frequency in Hz, power in unit^2 s/Hz).

    Scaled so that ``sum(power) * df`` equals the sum of u^2 dt (Parseval), i.e. the
    energy of a signal that starts and ends at zero.

    Parameters
    ----------
    t : numpy.ndarray
        Uniformly spaced sample times, s; shape (n,).
    u : numpy.ndarray
        Signal; shape (n,).

    Returns
    -------
    tuple[numpy.ndarray, numpy.ndarray]
        Frequencies, Hz, and energy spectral density, unit^2 s/Hz; each of shape (n // 2 + 1,).
    """
    dt = _uniform_dt(t)
    u = np.asarray(u, float)
    n = u.size
    U = np.fft.rfft(u) * dt
    power = np.abs(U) ** 2
    power[1:] *= 2.0
    if n % 2 == 0:
        power[-1] /= 2.0  # the Nyquist bin has no mirror
    return np.fft.rfftfreq(n, dt), power


def scale_to_energy(design: InputDesign, t: np.ndarray, target: float) -> InputDesign:
    """A copy of ``design`` with amplitude(s) scaled so its total energy is ``target``.

    The energy is summed over the surfaces the design moves (rad^2 s). With rate
    limiting the energy is not quadratic in amplitude, so the scale is refined by a few
    secant steps until the energy is within 1e-6 of the target.

    Parameters
    ----------
    design : InputDesign
        The design to scale.
    t : numpy.ndarray
        Sample times, s; shape (n,).
    target : float
        Total energy wanted, rad^2 s; > 0.

    Returns
    -------
    InputDesign
        The scaled copy.
    """
    if target <= 0:
        raise ValueError(f"target energy must be > 0, got {target}")

    def scaled(c: float) -> InputDesign:
        return scale_amplitude(design, c)

    def total(d: InputDesign) -> float:
        return sum(energy(t, u) for u in d.signals(t).values())

    e0 = total(design)
    if e0 <= 0:
        raise ValueError(f"{design.kind!r} has zero energy on this time vector")
    c = np.sqrt(target / e0)
    for _ in range(50):
        e = total(scaled(c))
        if abs(e - target) <= 1e-6 * target:
            return scaled(c)
        c *= np.sqrt(target / e)
    raise ValueError(
        f"{design.kind!r} cannot reach energy {target:.6g} on this time vector (it gets "
        f"{e:.6g}): the rate limit or the time span caps it"
    )
