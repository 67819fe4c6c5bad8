"""The window test's regressors and signal tools (``verdict.null_test``): the input-driven
regressors, the high band's, the other outputs' residuals as nuisance, the high-pass and
the band energy.

- each input u of the axis (its change from the window's first sample) and ``LAGUERRE``
  orthonormal Laguerre filters of it (time constant ``LAGUERRE_TAU_S``; Wahlberg 1991;
  Heuberger, Van den Hof & Wahlberg 2005): the low-frequency response of an error in the
  model's dynamics;
- every output of the model as simulated from the measured inputs: the directions a
  derivative or scale error moves the response in. (Their rates of change were tried too:
  they made the roll rate of two of nine flights in moderate turbulence a false alarm, p ~
  1e-7 to 1e-11, and added no detection.)

All of them are functions of the measured inputs only, so under the null (open-loop inputs)
they are uncorrelated with the turbulence response and the noise.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from scipy import linalg, signal

from flightid.identification.gap.fit import WindowFit
from flightid.record import FlightRecord

LAGUERRE = 4  # Laguerre filters per input
LAGUERRE_TAU_S = 0.7  # their time constant (s): the band of the short period and Dutch roll
# the high band's regressors (a structural mode, a fast sensor or actuator effect): fast
# Laguerre filters of the inputs
FAST_LAGUERRE, FAST_TAU_S = 4, 0.08
# the main test's nuisance regressors (``other_outputs``): each other output's high-passed
# residual and this many Laguerre filters of it (time constant LAGUERRE_TAU_S). Turbulence
# drives every output of an axis at once; under the null the other outputs' residuals are
# independent of the inputs as this one's is, so fitting them beside the input regressors
# keeps the test's null and takes most of the turbulence response out of its noise: on the
# blind check's development flights the chance term of the share fell from 0.02-0.2 to
# 0.001-0.01 (docs/gap_benchmark.md, the rules for the seed-7 run)
PARTIAL_LAGUERRE = 2
# the main test's band: residual and regressors through the same 2nd-order Butterworth
# high-pass at this corner (rad/s) before the Wald test, per window. A linear filter applied
# to both keeps the null's uncorrelatedness (inputs against turbulence and noise) and takes
# off the few-cycle phugoid and slow turbulence response (V, theta over a 10 s window) that
# correlates by chance with the slow regressors; the maneuvers' 0.6-3 rad/s are kept
# (docs/gap_benchmark.md, the rules for the seed-3 run)
HIGHPASS_RAD_S = 0.6


def laguerre(u: np.ndarray, dt: float, n: int = LAGUERRE,
             tau: float = LAGUERRE_TAU_S) -> list[np.ndarray]:
    """``u`` through the first ``n`` discrete Laguerre filters with pole exp(-dt/tau).

    L_1 = sqrt(1 - a^2) / (1 - a q^-1), L_(k+1) = L_k (q^-1 - a) / (1 - a q^-1)
    (Wahlberg 1991).

    Parameters
    ----------
    u : numpy.ndarray
        The signal, any unit; shape (N,).
    dt : float
        Sample interval, s.
    n : int, optional
        Number of filters. Default ``LAGUERRE``.
    tau : float, optional
        The filters' time constant, s. Default ``LAGUERRE_TAU_S``.

    Returns
    -------
    list of numpy.ndarray
        The n filtered signals, unit of ``u``; shape (N,) each.
    """
    a = math.exp(-dt / tau)
    x = signal.lfilter([math.sqrt(1.0 - a * a)], [1.0, -a], u)
    out = [x]
    for _ in range(n - 1):
        x = signal.lfilter([-a, 1.0], [1.0, -a], x)
        out.append(x)
    return out


def regressors(fit: WindowFit, record: FlightRecord, inputs: Sequence[str],
               n: int = LAGUERRE) -> np.ndarray:
    """The input-driven regressors of one window (module docstring).

    Each input's change from the window's first sample and ``n`` Laguerre filters of it, then
    every output of the model as simulated.

    Parameters
    ----------
    fit : WindowFit
        The model's fit on the window.
    record : FlightRecord
        The window's record, for the inputs (interpolated to the fit's times).
    inputs : sequence of str
        The axis's inputs (those the record lacks are skipped).
    n : int, optional
        Laguerre filters per input. Default ``LAGUERRE``.

    Returns
    -------
    numpy.ndarray
        The regressors, means removed, SI units; shape (N, k).
    """
    t = fit.time
    dt = float(np.median(np.diff(t)))
    cols: list[np.ndarray] = []
    for s in inputs:
        if s not in record:
            continue
        u = np.interp(t, record.time, record[s])
        u = u - u[0]
        cols += [u, *laguerre(u, dt, n)]
    for m in fit.model.values():
        cols.append(m - np.mean(m))
    x = np.column_stack(cols)
    return x - x.mean(axis=0)


def unit_columns(x: np.ndarray) -> np.ndarray:
    """The columns of ``x`` scaled to unit norm, those that are (numerically) zero dropped.

    Parameters
    ----------
    x : numpy.ndarray
        (N, k) columns.

    Returns
    -------
    numpy.ndarray
        (N, k') the non-zero columns, each of unit norm.
    """
    scale = np.sqrt(np.sum(x * x, axis=0))
    keep = scale > 1e-12 * max(float(scale.max(initial=0.0)), 1e-300)
    return x[:, keep] / scale[keep]


def independent_columns(x: np.ndarray, first: int = 0) -> np.ndarray:
    """The columns of ``x`` that are linearly independent (rank-revealing QR), in order.

    Parameters
    ----------
    x : numpy.ndarray
        (N, k) columns.
    first : int, optional
        The first columns, independent themselves, always kept (those of the tested
        regressors ahead of nuisance columns). Default 0.

    Returns
    -------
    numpy.ndarray
        (N, k') the independent columns, the ``first`` ones first.
    """
    if first:
        q, _ = np.linalg.qr(x[:, :first])
        tail = x[:, first:]
        rest = tail - q @ (q.T @ tail)  # what the first columns do not span
        live = np.sqrt(np.sum(rest**2, axis=0)) > 1e-6 * np.sqrt(np.sum(tail**2, axis=0))
        tail, rest = tail[:, live], rest[:, live]
        return np.hstack([x[:, :first], tail[:, independent_index(rest)]]) if rest.size \
            else x[:, :first]
    return x[:, independent_index(x)]


def independent_index(x: np.ndarray) -> np.ndarray:
    """Indices of the linearly independent columns of ``x`` (rank-revealing QR).

    Parameters
    ----------
    x : numpy.ndarray
        (N, k) columns.

    Returns
    -------
    numpy.ndarray
        The indices of a largest independent set, sorted.
    """
    _, r, piv = linalg.qr(x, mode="economic", pivoting=True)
    d = np.abs(np.diag(r))
    rank = int(np.sum(d > 1e-8 * d[0])) if d.size else 0
    return np.sort(piv[:rank])


def highpass(x: np.ndarray, dt: float, corner: float = HIGHPASS_RAD_S) -> np.ndarray:
    """``x``, means removed, through a causal 2nd-order Butterworth high-pass.

    Parameters
    ----------
    x : numpy.ndarray
        The signal(s), time along the first axis; shape (N,) or (N, k).
    dt : float
        Sample interval, s.
    corner : float, optional
        The corner, rad/s. Default ``HIGHPASS_RAD_S``.

    Returns
    -------
    numpy.ndarray
        The filtered signal(s), unit of ``x``; shape of ``x``.
    """
    b, a = signal.butter(2, corner * dt / math.pi, "high")
    return signal.lfilter(b, a, x - np.mean(x, axis=0), axis=0)


def band_energy(x: np.ndarray, dt: float, low_hz: float) -> float:
    """Energy of ``x`` (mean removed) above ``low_hz``, by Parseval.

    Parameters
    ----------
    x : numpy.ndarray
        The signal, any unit; shape (N,).
    dt : float
        Sample interval, s.
    low_hz : float
        The band's lower edge, Hz.

    Returns
    -------
    float
        The energy, unit of ``x`` squared (summed over samples).
    """
    f = np.fft.rfftfreq(x.size, dt)
    e = np.abs(np.fft.rfft(x - np.mean(x))) ** 2
    w = np.full(f.size, 2.0)
    w[0] = 1.0
    if x.size % 2 == 0:
        w[-1] = 1.0
    return float(np.sum((w * e)[f >= low_hz]) / x.size)


def fast_regressors(fit: WindowFit, record: FlightRecord, inputs: Sequence[str]) -> np.ndarray:
    """The high band's regressors of one window.

    ``FAST_LAGUERRE`` Laguerre filters of each input with time constant ``FAST_TAU_S`` (a few
    tenths of a second of memory).

    Parameters
    ----------
    fit : WindowFit
        The model's fit on the window (its times).
    record : FlightRecord
        The window's record, for the inputs.
    inputs : sequence of str
        The axis's inputs (those the record lacks are skipped).

    Returns
    -------
    numpy.ndarray
        The regressors, means removed, SI units; shape (N, k).
    """
    t = fit.time
    dt = float(np.median(np.diff(t)))
    cols: list[np.ndarray] = []
    for s in inputs:
        if s in record:
            u = np.interp(t, record.time, record[s])
            cols += laguerre(u - u[0], dt, FAST_LAGUERRE, FAST_TAU_S)
    x = np.column_stack(cols)
    return x - x.mean(axis=0)


def nuisance_blocks(high_passed: Mapping[str, Sequence[np.ndarray]],
                    dts: Sequence[float]) -> dict[str, list[np.ndarray]]:
    """Each output's nuisance columns for the other outputs' tests, window by window.

    Each output's high-passed residual and ``PARTIAL_LAGUERRE`` Laguerre filters of it; a
    channel non-finite on any window is left out (each column then holds one channel
    throughout).

    Parameters
    ----------
    high_passed : mapping of str to sequence of numpy.ndarray
        {channel: one high-passed residual per window}, SI units.
    dts : sequence of float
        The windows' sample intervals, s.

    Returns
    -------
    dict of str to list of numpy.ndarray
        {channel: one (n_j, 1 + ``PARTIAL_LAGUERRE``) block per window}.
    """
    return {c: [np.column_stack([v, *laguerre(v, dt, PARTIAL_LAGUERRE)])
                for v, dt in zip(vs, dts, strict=True)]
            for c, vs in high_passed.items() if all(np.all(np.isfinite(v)) for v in vs)}


def other_outputs(high_passed: Mapping[str, Sequence[np.ndarray]], channel: str,
                  dts: Sequence[float],
                  blocks: Mapping[str, Sequence[np.ndarray]] | None = None
                  ) -> np.ndarray | None:
    """The main test's nuisance regressors of ``channel``.

    Every other output's high-passed residual and ``PARTIAL_LAGUERRE`` Laguerre filters of it,
    window by window, stacked.

    Parameters
    ----------
    high_passed : mapping of str to sequence of numpy.ndarray
        {channel: one high-passed residual per window}, SI units.
    channel : str
        The channel tested (left out).
    dts : sequence of float
        The windows' sample intervals, s.
    blocks : mapping of str to sequence of numpy.ndarray, optional
        Those of ``nuisance_blocks``, computed once for every channel. Default: computed here.

    Returns
    -------
    numpy.ndarray or None
        The regressors, means removed per window; shape (N, m). None when
        ``PARTIAL_LAGUERRE`` is negative (no nuisance) or no other output is finite.
    """
    if PARTIAL_LAGUERRE < 0:
        return None
    if blocks is None:
        blocks = nuisance_blocks(high_passed, dts)
    others = [c for c in blocks if c != channel]
    if not others:
        return None
    out = []
    for j in range(len(dts)):
        z = np.column_stack([blocks[c][j] for c in others])
        out.append(z - z.mean(axis=0))
    return np.vstack(out)
