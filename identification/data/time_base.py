"""Time bases as real data have them: a record whose steps carry rounding jitter (an
ASCII export's 0.09999 and 0.10001 s at 10 Hz) is re-gridded onto its uniform grid;
gaps and reversals are left for the methods to refuse.

Jitter is accepted when no step differs from the median step by more than
``JITTER_LIMIT`` (1 %) of it: the new grid is the uniform one nearest the times (a
least-squares line through sample index and time) with the same number of samples, and
every channel is interpolated linearly onto it, which moves a value by about the jitter
times one step's change. A larger difference is a gap or a changed
rate, not jitter.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from flightid.record import FlightRecord

JITTER_LIMIT = 0.01  # of the median step
# below this relative spread the record counts as uniform already (FlightRecord.uniform_step)
UNIFORM_RTOL = 1e-6


class RegriddedWarning(UserWarning):
    """A record's jittered time base was re-gridded."""


def jitter(record: FlightRecord) -> float:
    """The largest |step - median step| / median step of the record's time.

    Parameters
    ----------
    record : FlightRecord
        The flight.

    Returns
    -------
    float
        The relative jitter, 1; 0 when the record has fewer than three samples.
    """
    if len(record) < 3:
        return 0.0
    steps = np.diff(record.time)
    median = float(np.median(steps))
    return float(np.max(np.abs(steps - median)) / median) if median > 0 else 0.0


def regrid_jitter(record: FlightRecord) -> FlightRecord:
    """``record`` on a uniform time grid when its steps jitter by less than ``JITTER_LIMIT``
    of the median step (a ``RegriddedWarning`` says so).

    Channels are linearly interpolated onto the least-squares uniform grid.

    Parameters
    ----------
    record : FlightRecord
        The flight.

    Returns
    -------
    FlightRecord
        The re-gridded record; the record itself when it is uniform already or when its time
        has gaps (left to ``FlightRecord.uniform_step`` to refuse).
    """
    spread = jitter(record)
    if spread <= UNIFORM_RTOL or spread > JITTER_LIMIT:
        return record
    n = len(record)
    index = np.arange(n)
    step, start = np.polyfit(index, record.time, 1)  # the uniform grid nearest the times
    grid = start + step * index
    channels = {k: np.interp(grid, record.time, v) for k, v in record.channels.items()}
    warnings.warn(
        f"time steps jitter by up to {100 * spread:.3g} % of the {step:.4g} s step: "
        f"re-gridded to a uniform {step:.4g} s step ({n} samples, linear interpolation)",
        RegriddedWarning, stacklevel=2)
    extra = {**record.meta.extra, "regridded": {"max_jitter": spread, "step_s": step}}
    return FlightRecord(grid, channels, replace(record.meta, extra=extra))
