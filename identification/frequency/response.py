"""Frequency responses from flight data: spectra, coherence, composite windows, conditioning.

Nonparametric frequency-response identification as in CIFER (Tischler & Remple 2012,
ch. 7-9; Catterall 2003 ch. 5): each channel is cut into overlapped windowed segments
(Hann or Hamming), each segment is Fourier transformed at the chosen frequencies (chirp
z-transform on a uniform grid, a direct transform otherwise), the auto and cross spectra
are averaged, and

* single input:  H = G_uy / G_uu,  gamma^2 = |G_uy|^2 / (G_uu G_yy);
* several correlated inputs (MISO, "conditioned" responses, Bendat & Piersol 2010
  ch. 7; Tischler & Remple ch. 9): H = G_xx^-1 G_xy at each frequency, with the partial
  coherence of each input read off the inverse of the full spectral matrix
  (|D_iy|^2 / (D_ii D_yy), Dahlhaus 2000) and the multiple coherence
  1 - 1 / (G_yy D_yy);
* normalised random error of |H| (Bendat & Piersol eq. 9.90, Tischler & Remple eq. 7.44):
  eps_r = sqrt(1 - gamma_m^2) / (|gamma_p| sqrt(2 (n_d - q + 1))), which for one input
  is sqrt(1 - gamma^2) / (|gamma| sqrt(2 n_d)); n_d is the effective number of
  independent averages of the overlapped windows (Welch 1967). The phase error is
  eps_r rad.

Composite responses (CIFER COMPOSITE) combine the estimates of several window lengths:
at each frequency the composite H minimises sum_i |H - H_i|^2 / eps_i^2 over the windows
that are valid there (a window is valid from 2 / T_window Hz up, two periods per
window, Tischler & Remple eq. 7.32), i.e. an inverse-variance weighted mean.

Units: frequencies in Hz (``omega`` in rad/s), responses in output unit per input unit
(SI, as in the record), phase in deg.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.signal.windows import tukey

from flightid.identification.engine import identifiability as ident
from flightid.identification.frequency.fourier import finite_fourier_transform
from flightid.identification.frequency.grids import default_windows, response_frequencies
from flightid.identification.frequency.spectra import (
    Spectra,
    cross_spectra,
)


@dataclass
class FrequencyResponse:
    """One input-output frequency response H(f) with its coherence and random error."""

    frequency: np.ndarray  # Hz
    response: np.ndarray  # complex, output unit per input unit
    coherence: np.ndarray  # gamma^2 (partial coherence when conditioned on other inputs)
    random_error: np.ndarray  # normalised random error of |H| (1 sigma, fraction)
    input: str = "u"
    output: str = "y"
    n_averages: np.ndarray | float = 1.0  # effective independent averages n_d
    window: float | tuple[float, ...] = 0.0  # window length(s), s
    multiple_coherence: np.ndarray | None = None
    conditioned_on: tuple[str, ...] = ()
    extra: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.frequency = np.asarray(self.frequency, dtype=float)
        self.response = np.asarray(self.response, dtype=complex)
        self.coherence = np.asarray(self.coherence, dtype=float)
        self.random_error = np.asarray(self.random_error, dtype=float)
        n = self.frequency.size
        for label in ("response", "coherence", "random_error"):
            if getattr(self, label).shape != (n,):
                raise ValueError(
                    f"{label} has shape {getattr(self, label).shape}; frequency has ({n},)"
                )

    @property
    def omega(self) -> np.ndarray:
        """Frequencies in rad/s."""
        return 2.0 * np.pi * self.frequency

    @property
    def magnitude_db(self) -> np.ndarray:
        """20 log10 |H| (dB of output unit per input unit)."""
        return 20.0 * np.log10(np.maximum(np.abs(self.response), 1e-300))

    @property
    def phase_deg(self) -> np.ndarray:
        """Phase of H, unwrapped along frequency (deg)."""
        return np.degrees(np.unwrap(np.angle(self.response)))

    def valid(self, coherence_min: float = 0.6) -> np.ndarray:
        """Mask of the frequencies where the coherence is at least ``coherence_min``."""
        return np.isfinite(self.response) & (np.nan_to_num(self.coherence) >= coherence_min)

    def select(self, mask: np.ndarray) -> FrequencyResponse:
        """The response at the frequencies where ``mask`` is true."""
        mask = np.asarray(mask, dtype=bool)
        nd = self.n_averages
        mc = self.multiple_coherence
        return replace(
            self,
            frequency=self.frequency[mask],
            response=self.response[mask],
            coherence=self.coherence[mask],
            random_error=self.random_error[mask],
            n_averages=nd[mask] if isinstance(nd, np.ndarray) else nd,
            multiple_coherence=None if mc is None else mc[mask],
        )

    def band(self, f_min: float, f_max: float) -> FrequencyResponse:
        """The response between f_min and f_max (Hz, inclusive)."""
        return self.select((self.frequency >= f_min) & (self.frequency <= f_max))


def _random_error(coh_mult: np.ndarray, coh_part: np.ndarray, n_d: float, q: int) -> np.ndarray:
    dof = max(n_d - q + 1, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        err = np.sqrt(np.clip(1.0 - coh_mult, 0.0, 1.0)) / (
            np.sqrt(np.clip(coh_part, 0.0, 1.0)) * np.sqrt(2.0 * dof))
    return np.where(np.isfinite(err), err, np.inf)


def responses_from_spectra(
    spectra: Spectra, inputs: Sequence[str], output: str
) -> dict[str, FrequencyResponse]:
    """Conditioned frequency responses of ``output`` to each input from a spectral matrix.

    Parameters
    ----------
    spectra : Spectra
        The averaged spectra; the matrix columns are the inputs in order, then the output.
    inputs : sequence of str
        The input names.
    output : str
        The output name.

    Returns
    -------
    dict of str to FrequencyResponse
        One response per input (output unit per input unit), with partial coherence and
        random error.

    Raises
    ------
    ValueError
        When the matrix does not have len(inputs) + 1 channels.
    """
    q = len(inputs)
    g = spectra.matrix
    if g.shape[1] != q + 1:
        raise ValueError(f"spectral matrix has {g.shape[1]} channels; expected {q} inputs + 1")
    gxx = g[:, :q, :q]
    gxy = g[:, :q, q]
    gyy = g[:, q, q].real
    h = np.full((g.shape[0], q), np.nan + 0j)
    partial = np.zeros((g.shape[0], q))
    multiple = np.zeros(g.shape[0])
    # with no more segments than inputs the spectral matrix has rank <= n_segments: the
    # coherence is 1 whatever the data, so nothing can be validated
    for k in range(g.shape[0] if spectra.n_segments > q else 0):
        if not np.all(np.isfinite(g[k])) or np.linalg.cond(gxx[k]) > 1e12 or gyy[k] <= 0:
            continue  # input spectra singular here (no excitation, or inputs fully correlated)
        h[k] = np.linalg.solve(gxx[k], gxy[k])
        if np.linalg.cond(g[k]) > 1e12:
            # output exactly linear in the inputs (e.g. a single segment): coherence 1
            multiple[k], partial[k] = 1.0, 1.0
            continue
        d = np.linalg.inv(g[k])
        multiple[k] = 1.0 - 1.0 / (gyy[k] * d[q, q].real)
        partial[k] = np.abs(d[:q, q]) ** 2 / (d.diagonal()[:q].real * d[q, q].real)
    multiple = np.clip(multiple, 0.0, 1.0)
    partial = np.clip(partial, 0.0, 1.0)
    out: dict[str, FrequencyResponse] = {}
    for i, name in enumerate(inputs):
        out[name] = FrequencyResponse(
            frequency=spectra.frequency,
            response=h[:, i],
            coherence=partial[:, i],
            random_error=_random_error(multiple, partial[:, i], spectra.n_averages, q),
            input=name,
            output=output,
            n_averages=spectra.n_averages,
            window=spectra.window,
            multiple_coherence=multiple if q > 1 else None,
            conditioned_on=tuple(n for n in inputs if n != name),
        )
    return out


def estimate_response(
    inputs: dict[str, np.ndarray],
    output: np.ndarray,
    dt: float,
    *,
    output_name: str = "y",
    window: float,
    frequencies: np.ndarray,
    overlap: float = 0.5,
    taper: str = "hann",
) -> dict[str, FrequencyResponse]:
    """Frequency responses of ``output`` to each of ``inputs`` from one window length;
    conditioned when several inputs.

    Below two periods per window the coherence is set to 0 and the random error to inf
    (Tischler & Remple eq. 7.32).

    Parameters
    ----------
    inputs : dict of str to numpy.ndarray
        The input signals on the output's time base, SI units; shape (N,) each.
    output : numpy.ndarray
        The output signal, SI units; shape (N,).
    dt : float
        Sample interval, s.
    output_name : str, optional
        The output's name. Default "y".
    window : float
        Segment length, s.
    frequencies : numpy.ndarray
        Frequencies, Hz.
    overlap : float, optional
        Fraction shared by neighbouring segments. Default 0.5.
    taper : str, optional
        "hann", "hamming" or "rectangular". Default "hann".

    Returns
    -------
    dict of str to FrequencyResponse
        One response per input.

    Raises
    ------
    ValueError
        When there is no input or an input's shape differs from the output's.
    """
    if not inputs:
        raise ValueError("give at least one input")
    names = list(inputs)
    y = np.asarray(output, dtype=float)
    cols = []
    for n in names:
        u = np.asarray(inputs[n], dtype=float)
        if u.shape != y.shape:
            raise ValueError(f"input {n!r} has shape {u.shape}, output has {y.shape}")
        cols.append(u)
    spectra = cross_spectra(np.column_stack(cols + [y]), dt, window, frequencies,
                            overlap=overlap, taper=taper)
    resp = responses_from_spectra(spectra, names, output_name)
    # below two periods per window the estimate is not valid (Tischler & Remple eq. 7.32)
    low = spectra.frequency < 2.0 / spectra.window
    for r in resp.values():
        r.coherence = np.where(low, 0.0, r.coherence)
        r.random_error = np.where(low, np.inf, r.random_error)
    return resp


def composite(responses: Sequence[FrequencyResponse]) -> FrequencyResponse:
    """Combine responses of several window lengths on one frequency grid (CIFER COMPOSITE).

    At each frequency H minimises sum_i |H - H_i|^2 / eps_i^2 (inverse-variance weighted
    mean), the coherence is the same weighted mean of gamma_i^2, and the random error is
    the same weighted mean of eps_i: the windows reuse the same data, so their errors are
    not independent and 1/sqrt(sum 1/eps_i^2) would overstate the accuracy.
    The averages counted are those of the window with the smallest random error there.

    Parameters
    ----------
    responses : sequence of FrequencyResponse
        Responses of one output/input pair on one frequency grid.

    Returns
    -------
    FrequencyResponse
        The composite response.

    Raises
    ------
    ValueError
        When there is no response or the grids differ.
    """
    if not responses:
        raise ValueError("no responses to combine")
    f = responses[0].frequency
    for r in responses[1:]:
        if r.frequency.shape != f.shape or not np.allclose(r.frequency, f):
            raise ValueError("responses to combine must share one frequency grid")
    h = np.array([r.response for r in responses])
    eps = np.array([r.random_error for r in responses])
    coh = np.array([r.coherence for r in responses])
    ok = np.isfinite(eps) & np.isfinite(h)
    wgt = np.where(ok, 1.0 / np.maximum(np.where(ok, eps, 1.0), 1e-9) ** 2, 0.0)
    total = wgt.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        hc = np.where(total > 0, (wgt * np.where(ok, h, 0)).sum(axis=0) / total, np.nan)
        cc = np.where(total > 0, (wgt * coh).sum(axis=0) / total, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        ec = np.where(total > 0, (wgt * np.where(ok, eps, 0.0)).sum(axis=0) / total, np.inf)
    best = np.where(ok, eps, np.inf).argmin(axis=0)
    nd = np.array([np.broadcast_to(r.n_averages, f.shape) for r in responses])
    mcs = [r.multiple_coherence for r in responses]
    mc = None
    if all(m is not None for m in mcs):
        mc = np.where(total > 0, (wgt * np.array(mcs)).sum(axis=0) / np.where(total > 0, total,
                                                                               1.0), 0.0)
    first = responses[0]
    return FrequencyResponse(
        frequency=f,
        response=hc,
        coherence=cc,
        random_error=ec,
        input=first.input,
        output=first.output,
        n_averages=np.take_along_axis(nd, best[None], axis=0)[0].astype(float),
        window=tuple(float(np.max(r.window)) for r in responses),
        multiple_coherence=mc,
        conditioned_on=first.conditioned_on,
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


