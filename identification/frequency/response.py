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
from matplotlib.figure import Figure
from scipy.signal import czt
from scipy.signal.windows import tukey

from flightid.identification.engine import identifiability as ident

TAPERS = ("hann", "hamming", "rectangular")


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


# ----------------------------------------------------------------------------- transforms
def _is_uniform(frequencies: np.ndarray) -> bool:
    if frequencies.size < 3:
        return False
    step = np.diff(frequencies)
    return bool(np.allclose(step, step[0], rtol=1e-9, atol=1e-12 * abs(frequencies[-1])))


def discrete_fourier(x: np.ndarray, dt: float, frequencies: np.ndarray) -> np.ndarray:
    """sum_k x_k exp(-j 2 pi f k dt) along axis 0 at any frequencies (Hz); no dt factor.

    A uniform grid goes through the chirp z-transform (scipy.signal.czt, Rabiner et al.
    1969), any other grid through a direct transform.
    """
    x = np.asarray(x)
    f = np.atleast_1d(np.asarray(frequencies, dtype=float))
    if _is_uniform(f):
        step = f[1] - f[0]
        w = np.exp(-2j * np.pi * step * dt)
        a = np.exp(2j * np.pi * f[0] * dt)
        return czt(x, m=f.size, w=w, a=a, axis=0)
    k = np.arange(x.shape[0])
    kernel = np.exp(-2j * np.pi * np.outer(f, k) * dt)
    return kernel @ x


def _filon_cubic(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Correction factor W and endpoint weights alpha_0..3 of the cubic-interpolation
    Fourier integral for the kernel exp(-j theta k) (Press et al. 1992, sec. 13.9,
    eqs. 13.9.13-14; Morelli & Klein 2016, sec. 7.2 high-accuracy Fourier transform)."""
    th = np.asarray(theta, dtype=float)
    w = np.empty(th.shape)
    alpha = np.empty(th.shape + (4,), dtype=complex)
    small = np.abs(th) < 0.1
    t = th[small]
    t2, t4, t6 = t * t, t**4, t**6
    w[small] = 1 - 11 / 720 * t4 + 23 / 15120 * t6
    alpha[small, 0] = (-2 / 3 + t2 / 45 + 103 / 15120 * t4 - 169 / 226800 * t6) + 1j * t * (
        2 / 45 + 2 / 105 * t2 - 8 / 2835 * t4 + 86 / 467775 * t6)
    alpha[small, 1] = (7 / 24 - 7 / 180 * t2 + 5 / 3456 * t4 - 7 / 259200 * t6) + 1j * t * (
        7 / 72 - t2 / 168 + 11 / 72576 * t4 - 13 / 5987520 * t6)
    alpha[small, 2] = (-1 / 6 + t2 / 45 - 5 / 6048 * t4 + t6 / 64800) + 1j * t * (
        -7 / 90 + t2 / 210 - 11 / 90720 * t4 + 13 / 7484400 * t6)
    alpha[small, 3] = (1 / 24 - t2 / 180 + 5 / 24192 * t4 - t6 / 259200) + 1j * t * (
        7 / 360 - t2 / 840 + 11 / 362880 * t4 - 13 / 29937600 * t6)
    t = th[~small]
    t2, t4 = t * t, t**4
    c, s, c2, s2 = np.cos(t), np.sin(t), np.cos(2 * t), np.sin(2 * t)
    sp = 6 + t2
    w[~small] = sp / (3 * t4) * (3 - 4 * c + c2)
    alpha[~small, 0] = ((-42 + 5 * t2) + sp * (8 * c - c2)) / (6 * t4) + 1j * (
        (-12 * t + 6 * t * t2) + sp * s2) / (6 * t4)
    alpha[~small, 1] = (14 * (3 - t2) - 7 * sp * c) / (6 * t4) + 1j * (30 * t - 5 * sp * s) / (
        6 * t4)
    alpha[~small, 2] = (-4 * (3 - t2) + 2 * sp * c) / (3 * t4) + 1j * (-12 * t + 2 * sp * s) / (
        3 * t4)
    alpha[~small, 3] = (2 * (3 - t2) - sp * c) / (6 * t4) + 1j * (6 * t - sp * s) / (6 * t4)
    # Press et al. write the kernel exp(+j theta k); ours is exp(-j theta k)
    return w, np.conj(alpha)


def finite_fourier_transform(
    x: np.ndarray, dt: float, frequencies: np.ndarray, *, correct: bool = True
) -> np.ndarray:
    """Finite Fourier integral int_0^T x(t) exp(-j 2 pi f t) dt of uniformly sampled data.

    ``x`` has time along axis 0 (shape (N,) or (N, k)), sampled every ``dt`` s from t = 0;
    ``frequencies`` in Hz (f dt <= 1/2). With ``correct`` the samples are interpolated by
    cubics and the integral is exact for them (multiplicative and endpoint corrections,
    Press et al. 1992 sec. 13.9; Morelli & Klein 2016 sec. 7.2, SIDPAC ``fint``); without,
    it is the plain Euler sum dt * sum x_k exp(-j w t_k). Returns shape (n_f,) or (n_f, k)
    in unit(x) * s.
    """
    x = np.asarray(x, dtype=float)
    f = np.atleast_1d(np.asarray(frequencies, dtype=float))
    if x.shape[0] < 8:
        raise ValueError(f"need at least 8 samples for the Fourier integral, got {x.shape[0]}")
    if dt <= 0:
        raise ValueError(f"sample interval must be positive, got {dt}")
    theta = 2 * np.pi * f * dt
    if np.any(np.abs(theta) > np.pi):
        raise ValueError(
            f"frequencies above the Nyquist frequency {0.5 / dt:g} Hz: max {f.max():g} Hz"
        )
    raw = discrete_fourier(x, dt, f)
    if not correct:
        return dt * raw
    w, alpha = _filon_cubic(theta)
    n = x.shape[0]
    t_end = (n - 1) * dt
    shape = (-1,) + (1,) * (x.ndim - 1)
    head = np.tensordot(alpha, x[:4], axes=([1], [0]))
    tail = np.tensordot(np.conj(alpha), x[::-1][:4], axes=([1], [0]))
    end = head + np.exp(-2j * np.pi * f * t_end).reshape(shape) * tail
    return dt * (w.reshape(shape) * raw + end)


# ----------------------------------------------------------------------------- spectra
@dataclass
class Spectra:
    """Averaged one-sided auto and cross spectra of several channels.

    ``matrix[f, i, j]`` = G_ij(f) = 2/(n U T_w) sum_segments conj(X_i) X_j (unit_i*unit_j/Hz).
    """

    frequency: np.ndarray
    matrix: np.ndarray
    n_segments: int
    n_averages: float  # effective number of independent averages (Welch 1967)
    window: float  # s


def _taper(name: str, n: int) -> np.ndarray:
    if name == "hann":
        return np.hanning(n + 2)[1:-1]  # nonzero end points: every sample contributes
    if name == "hamming":
        return np.hamming(n)
    if name == "rectangular":
        return np.ones(n)
    raise ValueError(f"unknown taper {name!r}; use one of {', '.join(TAPERS)}")


def effective_averages(taper: np.ndarray, n_segments: int, step: int) -> float:
    """Number of independent averages equivalent to overlapped tapered segments.

    Welch (1967) eq. 11 for the variance of an averaged periodogram of white data:
    1/n_eff = (1/K) [1 + 2 sum_{j=1}^{K-1} (1 - j/K) rho(j)^2],
    rho(j) = sum w(k) w(k + j S) / sum w(k)^2, with K segments offset by S samples.
    """
    k = n_segments
    if k <= 1:
        return float(k)
    energy = float(np.sum(taper**2))
    total = 1.0
    for j in range(1, k):
        lag = j * step
        if lag >= taper.size:
            break
        rho = float(np.sum(taper[: taper.size - lag] * taper[lag:])) / energy
        total += 2.0 * (1.0 - j / k) * rho**2
    return k / total


def cross_spectra(
    signals: np.ndarray,
    dt: float,
    window: float,
    frequencies: np.ndarray,
    *,
    overlap: float = 0.5,
    taper: str = "hann",
) -> Spectra:
    """Averaged auto and cross spectra of the columns of ``signals`` (time along axis 0).

    ``window`` is the segment length (s), ``overlap`` the fraction shared by neighbouring
    segments, ``taper`` hann, hamming or rectangular; each segment's mean is removed.
    """
    x = np.asarray(signals, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if not np.all(np.isfinite(x)):
        bad = np.argwhere(~np.isfinite(x))[0]
        raise ValueError(f"signal {bad[1]} is not finite at sample {bad[0]}")
    n_total = x.shape[0]
    n_win = int(round(window / dt))
    if n_win < 8:
        raise ValueError(f"window of {window} s is only {n_win} samples; need at least 8")
    if n_win > n_total:
        raise ValueError(
            f"window of {window} s ({n_win} samples) is longer than the record "
            f"({n_total} samples, {n_total * dt:g} s)"
        )
    if not 0.0 <= overlap < 1.0:
        raise ValueError(f"overlap must be in [0, 1), got {overlap}")
    step = max(1, int(round(n_win * (1.0 - overlap))))
    starts = list(range(0, n_total - n_win + 1, step))
    w = _taper(taper, n_win)
    f = np.atleast_1d(np.asarray(frequencies, dtype=float))
    g = np.zeros((f.size, x.shape[1], x.shape[1]), dtype=complex)
    for s in starts:
        seg = x[s : s + n_win]
        seg = (seg - seg.mean(axis=0)) * w[:, None]
        xf = dt * discrete_fourier(seg, dt, f)  # (n_f, k)
        g += np.conj(xf)[:, :, None] * xf[:, None, :]
    scale = 2.0 / (len(starts) * np.mean(w**2) * n_win * dt)
    return Spectra(
        frequency=f,
        matrix=g * scale,
        n_segments=len(starts),
        n_averages=effective_averages(w, len(starts), step),
        window=n_win * dt,
    )


# ----------------------------------------------------------------------------- responses
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

    The spectral matrix columns are the inputs in order, then the output.
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


def default_frequencies(
    duration: float, dt: float, windows: Sequence[float], n: int = 100,
    f_max: float | None = None,
) -> np.ndarray:
    """Log-spaced grid from 2 / (longest window) to f_max (default a fifth of the sample
    rate), in Hz: two periods in the longest window (Tischler & Remple eq. 7.32)."""
    f_lo = 2.0 / max(windows)
    f_hi = f_max if f_max is not None else 0.2 / dt
    if f_hi <= f_lo:
        raise ValueError(
            f"no frequencies: the lowest resolvable ({f_lo:g} Hz for a {max(windows):g} s "
            f"window) is above f_max = {f_hi:g} Hz"
        )
    return np.geomspace(f_lo, f_hi, n)


def default_windows(duration: float, dt: float) -> tuple[float, ...]:
    """Window lengths (s) for a composite: half, a quarter and an eighth of the record,
    none shorter than 40 samples (Tischler & Remple sec. 7.8 use about 5 windows from
    T_rec/2 down)."""
    wins = [duration / 2, duration / 4, duration / 8]
    return tuple(w for w in wins if w >= 40 * dt) or (duration / 2,)


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
    """Frequency responses of ``output`` to each of ``inputs`` (arrays on one time base)
    from one window length (s) at ``frequencies`` (Hz); conditioned when several inputs."""
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
    that of the best window there: the windows reuse the same data, so their errors are
    not independent and 1/sqrt(sum 1/eps_i^2) would overstate the accuracy.
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

    ``windows`` in s (default half, quarter and eighth of the record); ``frequencies`` in
    Hz (default log-spaced, 100 points from 2/longest window to a fifth of the sample
    rate). With ``whole_record`` (single input only) the response itself is the
    whole-record transform (``full_record_response``) and the windows give its coherence
    and random error. Returns one response per input.
    """
    y = np.asarray(output, dtype=float)
    duration = y.size * dt
    wins = tuple(windows) if windows else default_windows(duration, dt)
    f = (np.asarray(frequencies, dtype=float) if frequencies is not None
         else default_frequencies(duration, dt, wins))
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
    a taper only at the ends (Tukey, ``end_taper`` of the record, raised cosine). The
    whole-record transform has the finest resolution 1/T_rec: segment windows (Hann)
    smear a lightly damped mode over their main lobe 4/T_win and, on a sweep, cut the
    mode's ringing at the segment edges (Tischler & Remple 2012 sec. 7.6-7.8; on the
    Navion yaw sweep 64/32/16 s Hann windows bias Cn_r by +9 %, this transform by < 1 %).
    One segment cannot estimate coherence (it is 1 whatever the data), so the coherence
    and random error come from ``windowed``, the composite of overlapped windows on the
    same frequencies (the "valid" mask of the composite decides where H is used).
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

    ``other_inputs`` are inputs to condition on (their correlated contribution is
    removed, partial coherence reported). Composite over ``windows`` (s). An input that
    is constant or noise only (``identifiability.input_excitation``) is refused.
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


COHERENCE_PLOT_MIN = 0.6  # below it a response point is drawn faint (Tischler & Remple)


def bode_figure(responses: Sequence[FrequencyResponse], title: str = "") -> Figure:
    """Matplotlib figure: magnitude (dB), phase (deg) and coherence against frequency (Hz);
    points with coherence below 0.6 are drawn faint."""
    fig = Figure(figsize=(7.5, 8))
    axes = fig.subplots(3, 1, sharex=True,
                        gridspec_kw={"height_ratios": [2, 2, 1]})
    for r in responses:
        label = f"{r.output}/{r.input}"
        ok = np.isfinite(r.response)
        f, mag = r.frequency[ok], r.magnitude_db[ok]
        phase = np.degrees(np.unwrap(np.angle(r.response[ok])))
        # the whole curve faint, the points with coherence >= 0.6 (usable, CIFER) solid
        good = np.where(r.coherence[ok] >= COHERENCE_PLOT_MIN, 1.0, np.nan)
        (line,) = axes[0].semilogx(f, mag, alpha=0.25)
        axes[0].semilogx(f, mag * good, color=line.get_color(), label=label)
        axes[1].semilogx(f, phase, color=line.get_color(), alpha=0.25)
        axes[1].semilogx(f, phase * good, color=line.get_color())
        axes[2].semilogx(r.frequency, r.coherence, color=line.get_color())
    axes[0].set_ylabel("magnitude (dB)")
    axes[1].set_ylabel("phase (deg)")
    axes[2].set_ylabel("coherence")
    axes[2].axhline(0.6, color="0.5", ls="--", lw=0.8)
    axes[2].set_ylim(0, 1.05)
    axes[2].set_xlabel("frequency (Hz)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend()
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return fig


def bode_overlay_figure(measured: Sequence[FrequencyResponse], model: Sequence[np.ndarray],
                        coherence_min: float = 0.6, title: str = ""):
    """Matplotlib figure: measured responses (points where coherence >= coherence_min)
    with the identified model's responses (lines, complex arrays on the same frequencies)
    overlaid: magnitude (dB), phase (deg), coherence against frequency (Hz)."""
    if len(measured) != len(model):
        raise ValueError(f"{len(measured)} measured responses but {len(model)} model ones")
    fig = Figure(figsize=(8, 9))
    axes = fig.subplots(3, 1, sharex=True,
                        gridspec_kw={"height_ratios": [2, 2, 1]})
    for k, (r, h) in enumerate(zip(measured, model, strict=True)):
        colour = f"C{k % 10}"
        ok = r.valid(coherence_min)
        h = np.asarray(h, dtype=complex)
        phase_model = np.degrees(np.unwrap(np.angle(h)))
        phase_meas = np.degrees(np.angle(r.response))
        # measured phase put on the model's branch, so the two overlay
        phase_meas = phase_model + ((phase_meas - phase_model + 180.0) % 360.0 - 180.0)
        axes[0].semilogx(r.frequency[ok], r.magnitude_db[ok], "o", ms=3, color=colour,
                         label=f"{r.output}/{r.input}")
        axes[0].semilogx(r.frequency, 20 * np.log10(np.abs(h)), "-", color=colour)
        axes[1].semilogx(r.frequency[ok], phase_meas[ok], "o", ms=3, color=colour)
        axes[1].semilogx(r.frequency, phase_model, "-", color=colour)
        axes[2].semilogx(r.frequency, r.coherence, "-", color=colour)
    axes[0].set_ylabel("magnitude (dB)")
    axes[1].set_ylabel("phase (deg)")
    axes[2].set_ylabel("coherence")
    axes[2].axhline(coherence_min, color="0.5", ls="--", lw=0.8)
    axes[2].set_ylim(0, 1.05)
    axes[2].set_xlabel("frequency (Hz)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2, title="points: measured, lines: model",
                   title_fontsize=7)
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return fig
