"""The frequency responses of flight channels (arrays or a record) by the CIFER way.

``frequency_response_arrays`` estimates them over several overlapped window lengths and
composites them (``response.composite``), or takes one transform of the whole record
(``full_record_response``, Tukey-tapered ends) with the windows giving its coherence and
random error; ``frequency_response`` does it for a record's channels, checking that the
input is excited (Tischler & Remple 2012 ch. 7-9).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from scipy.signal.windows import tukey

from flightid.identification.engine import identifiability as ident
from flightid.identification.frequency.fourier import finite_fourier_transform
from flightid.identification.frequency.grids import default_windows, response_frequencies
from flightid.identification.frequency.response import (
    FrequencyResponse,
    composite,
    estimate_response,
)


def frequency_response_arrays(
    inputs: dict[str, np.ndarray],
    output: np.ndarray,
    dt: float,
    *,
    output_name: str = "y",
    windows: Sequence[float] | None = None,
    frequencies: np.ndarray | None = None,
    overlap: float = 0.5,
    taper: str = "hann",
    whole_record: bool = False,
) -> dict[str, FrequencyResponse]:
    """Composite (several windows) conditioned frequency responses from plain arrays.

    Parameters
    ----------
    inputs : dict of str to numpy.ndarray
        The input signals, SI units; shape (N,) each.
    output : numpy.ndarray
        The output signal, SI units; shape (N,).
    dt : float
        Sample interval, s.
    output_name : str, optional
        The output's name. Default "y".
    windows : sequence of float, optional
        Window lengths, s. Default half, quarter and eighth of the record.
    frequencies : numpy.ndarray, optional
        Frequencies, Hz. Default log-spaced, 100 points from 2/longest window to a fifth of
        the sample rate.
    overlap : float, optional
        Fraction shared by neighbouring segments. Default 0.5.
    taper : str, optional
        Segment taper. Default "hann".
    whole_record : bool, optional
        (Single input only) the response itself is the whole-record transform
        (``full_record_response``) and the windows give its coherence and random error.
        Default False.

    Returns
    -------
    dict of str to FrequencyResponse
        One response per input.
    """
    y = np.asarray(output, dtype=float)
    duration = y.size * dt
    wins = tuple(windows) if windows else default_windows(duration, dt)
    f = (np.asarray(frequencies, dtype=float) if frequencies is not None
         else response_frequencies(duration, dt, wins))
    per_window = [
        estimate_response(inputs, y, dt, output_name=output_name, window=w, frequencies=f,
                          overlap=overlap, taper=taper)
        for w in wins
    ]
    comp = {name: composite([pw[name] for pw in per_window]) for name in inputs}
    if whole_record:
        return full_record_response(inputs, y, dt, output_name=output_name, frequencies=f,
                                    windowed=comp)
    return comp


def _tukey(n: int, fraction: float) -> np.ndarray:
    """Tukey taper: flat, with raised-cosine ends over ``fraction`` of the n samples."""
    if not 0.0 <= fraction <= 1.0:
        raise ValueError(f"taper fraction must be in [0, 1], got {fraction}")
    return tukey(n, fraction)


def full_record_response(
    inputs: dict[str, np.ndarray],
    output: np.ndarray,
    dt: float,
    *,
    output_name: str = "y",
    frequencies: np.ndarray,
    windowed: dict[str, FrequencyResponse],
    end_taper: float = 0.1,
) -> dict[str, FrequencyResponse]:
    """Frequency response from one transform of the whole record (single input only).

    H = Y(f) / U(f), finite Fourier transforms (unit * s) of the mean-removed channels with
    a taper only at the ends (Tukey, raised cosine). The whole-record transform has the
    finest resolution 1/T_rec: segment windows (Hann) smear a lightly damped mode over their
    main lobe 4/T_win and, on a sweep, cut the mode's ringing at the segment edges (Tischler
    & Remple 2012 sec. 7.6-7.8; on the Navion yaw sweep 64/32/16 s Hann windows bias Cn_r by
    +9 %, this transform by < 1 %). One segment cannot estimate coherence (it is 1 whatever
    the data), so the coherence and random error come from ``windowed``.

    Parameters
    ----------
    inputs : dict of str to numpy.ndarray
        The one input signal, SI units; shape (N,).
    output : numpy.ndarray
        The output signal, SI units; shape (N,).
    dt : float
        Sample interval, s.
    output_name : str, optional
        The output's name. Default "y".
    frequencies : numpy.ndarray
        Frequencies, Hz.
    windowed : dict of str to FrequencyResponse
        The composite of overlapped windows on the same frequencies, by input (its "valid"
        mask decides where H is used).
    end_taper : float, optional
        Fraction of the record tapered at the ends. Default 0.1.

    Returns
    -------
    dict of str to FrequencyResponse
        The response of the one input.

    Raises
    ------
    ValueError
        For more than one input, a missing windowed response, mismatched shapes or grids.
    """
    if len(inputs) != 1:
        raise ValueError(
            f"the whole-record response needs a single input, got {len(inputs)} "
            f"({', '.join(inputs)}); correlated inputs need averaged spectra (windows)"
        )
    (name,) = inputs
    if name not in windowed:
        raise ValueError(f"no windowed response for input {name!r} to take the coherence from")
    y = np.asarray(output, dtype=float)
    u = np.asarray(inputs[name], dtype=float)
    if u.shape != y.shape:
        raise ValueError(f"input {name!r} has shape {u.shape}, output has {y.shape}")
    f = np.asarray(frequencies, dtype=float)
    ref = windowed[name]
    if ref.frequency.shape != f.shape or not np.allclose(ref.frequency, f):
        raise ValueError("windowed response and frequencies must share one grid")
    w = _tukey(y.size, end_taper)
    xf = finite_fourier_transform(np.column_stack([(u - u.mean()) * w, (y - y.mean()) * w]),
                                  dt, f)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.where(np.abs(xf[:, 0]) > 0, xf[:, 1] / xf[:, 0], np.nan)
    return {name: replace(ref, response=h, output=output_name, window=y.size * dt,
                          extra={**ref.extra, "whole_record": True, "end_taper": end_taper})}


def frequency_response(
    record,
    input: str,
    output: str,
    *,
    other_inputs: Sequence[str] = (),
    windows: Sequence[float] | None = None,
    frequencies: np.ndarray | None = None,
    overlap: float = 0.5,
    taper: str = "hann",
) -> FrequencyResponse:
    """Frequency response output/input of a FlightRecord (SI units per SI unit, Hz).

    Composite over ``windows``. An input that is constant or noise only
    (``identifiability.input_excitation``) is refused.

    Parameters
    ----------
    record : FlightRecord
        A uniformly sampled flight, SI channels.
    input : str
        The input channel.
    output : str
        The output channel.
    other_inputs : sequence of str, optional
        Inputs to condition on (their correlated contribution is removed, partial coherence
        reported).
    windows : sequence of float, optional
        Window lengths, s. Default as ``frequency_response_arrays``.
    frequencies : numpy.ndarray, optional
        Frequencies, Hz. Default as ``frequency_response_arrays``.
    overlap : float, optional
        Fraction shared by neighbouring segments. Default 0.5.
    taper : str, optional
        Segment taper. Default "hann".

    Returns
    -------
    FrequencyResponse
        The response of ``output`` to ``input``.

    Raises
    ------
    ValueError
        When the record is not uniformly sampled or the input is not excited.
    """
    dt = record.dt
    if len(record) > 2 and not np.allclose(np.diff(record.time), dt, rtol=1e-3):
        raise ValueError("record is not uniformly sampled; resample it first")
    names = [input, *[n for n in other_inputs if n != input]]
    inputs = {n: record[n] for n in names}
    quiet = ident.input_excitation(record, [input])
    if quiet:
        raise ValueError(f"input {input} is not excited: {quiet[input]}; a frequency "
                         "response needs a maneuver on it (a sweep or a multistep)")
    res = frequency_response_arrays(inputs, record[output], dt, output_name=output,
                                    windows=windows, frequencies=frequencies,
                                    overlap=overlap, taper=taper)
    return res[input]
