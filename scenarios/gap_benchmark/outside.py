"""Effects the catalogue cannot express, applied to a measured record: the blind check's
test of "unexplained".

- ``structural_mode``: a lightly damped structural mode (3-6 Hz, damping 0.02-0.05)
  excited by the aileron and rudder, seen by the roll and yaw rate gyros and the lateral
  accelerometer near it: H(s) = g w s / (s^2 + 2 zeta w s + w^2) from (da + dr) in rad,
  added to p (rad/s), 0.3 of it to r and 2 m/s^2 per rad/s of it to ay. A step of the
  surfaces rings with an amplitude of about g times the step.
- ``vane_nonlinearity``: a sideslip vane whose calibration is quadratic,
  beta_m = beta + k beta |beta| (k per rad); a linear scale cannot express it.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from flightid.record import FlightRecord


def structural_mode(record: FlightRecord, frequency_hz: float, damping: float,
                    gain: float) -> FlightRecord:
    """``record`` with the mode's response added to p, r and ay."""
    w = 2 * math.pi * frequency_hz
    u = np.zeros(len(record.time))
    for s in ("da", "dr"):
        if s in record:
            u = u + (record[s] - record[s][0])
    _, y, _ = signal.lsim(([gain * w, 0.0], [1.0, 2 * damping * w, w * w]), u, record.time)
    changed = {"p": record["p"] + y, "r": record["r"] + 0.3 * y, "ay": record["ay"] + 2.0 * y}
    return record.with_channels(**{k: v for k, v in changed.items() if k in record})


def vane_nonlinearity(record: FlightRecord, k: float, channel: str = "beta") -> FlightRecord:
    """``record`` with ``channel`` (rad) read through beta + k beta |beta|."""
    b = record[channel]
    return record.with_channels(**{channel: b + k * b * np.abs(b)})


OUTSIDE = {"structural_mode": structural_mode, "vane_nonlinearity": vane_nonlinearity}
