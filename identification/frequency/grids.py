"""The default frequency grids and window lengths of the frequency-domain methods."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flightid.record import FlightRecord


def default_windows(duration: float, dt: float, n_inputs: int = 2) -> tuple[float, ...]:
    """Window lengths for a composite frequency response (Tischler & Remple 2012 sec. 7.8
    use about five windows from T_rec/2 down).

    The longest window still gives ``n_inputs + 1`` half-overlapped segments, the others
    are half and a quarter of it, none shorter than 40 samples: for two inputs (or one
    output of a single-input response) a half, a quarter and an eighth of the record, for
    one input 2/3 of it and its half and quarter. Long windows matter: the Hann window
    widens a lightly damped resonance, and the short windows alone would overstate the
    Dutch-roll damping (Cn_r 20 % too large on the Navion yaw sweep with 40/20/10 s
    windows, 8 % with 64/32/16 s).

    Parameters
    ----------
    duration : float
        The record's length, s.
    dt : float
        The sample interval, s.
    n_inputs : int
        The number of inputs the responses are conditioned on (2: the plain halving).

    Returns
    -------
    tuple of float
        The window lengths, s, longest first.
    """
    longest = 2.0 * duration / (n_inputs + 2)
    wins = [longest, longest / 2, longest / 4]
    return tuple(w for w in wins if w >= 40 * dt) or (longest,)


def response_frequencies(duration: float, dt: float, windows: Sequence[float], n: int = 100,
                         f_max: float | None = None) -> np.ndarray:
    """The log-spaced grid of a frequency response: two periods in the longest window
    (Tischler & Remple 2012 eq. 7.32) up to ``f_max``.

    Parameters
    ----------
    duration : float
        The record's length, s (not used by the grid; kept with the windows' arguments).
    dt : float
        The sample interval, s.
    windows : sequence of float
        The window lengths, s.
    n : int
        The number of frequencies.
    f_max : float, optional
        The highest frequency, Hz (default: a fifth of the sample rate).

    Returns
    -------
    numpy.ndarray
        ``n`` frequencies, Hz, from 2 / (longest window) to ``f_max``.
    """
    f_lo = 2.0 / max(windows)
    f_hi = f_max if f_max is not None else 0.2 / dt
    if f_hi <= f_lo:
        raise ValueError(
            f"no frequencies: the lowest resolvable ({f_lo:g} Hz for a {max(windows):g} s "
            f"window) is above f_max = {f_hi:g} Hz"
        )
    return np.geomspace(f_lo, f_hi, n)


def fourier_frequencies(record: FlightRecord, f_min: float = 0.1, f_max: float = 1.5
                        ) -> np.ndarray:
    """The linear grid of the frequency-domain regressions: f_min to f_max spaced 1/T,
    T the record's length (Morelli & Klein 2016 sec. 7.1, the band of rigid-body dynamics).

    Parameters
    ----------
    record : FlightRecord
        The record whose length sets the spacing.
    f_min, f_max : float
        The band, Hz.

    Returns
    -------
    numpy.ndarray
        The frequencies, Hz.
    """
    duration = record.time[-1] - record.time[0]
    step = 1.0 / duration
    return np.arange(f_min, f_max + 0.5 * step, step)
