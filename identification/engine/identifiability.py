"""Which parameters a flight can determine: unexcited inputs, zero sensitivity, collinearity.

Works on the Fisher information matrix M = sum_i S_i^T R^-1 S_i of an output-error fit
(Morelli & Klein 2016, sec. 6.3; Jategaonkar 2015, sec. 4.17) and on the inputs of the
record. Each test returns ``{parameter: reason}`` for the parameters it finds cannot be
separated, so the caller can fix them at their a priori values and estimate the rest.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flightid.record import FlightRecord

# An input that moves less than this (rad) carries no excitation: it is below the
# resolution of control-position sensors (about 0.1 deg) and far below any test input.
MIN_INPUT_RANGE = 1e-3
# Smallest eigenvalue of the normalised information matrix (unit diagonal) below which it
# is treated as singular: a combination of parameters whose estimate would have a
# variance 1e8 times that of an uncorrelated one (pairwise correlation 1 - 5e-9).
SINGULAR_EIGENVALUE = 1e-8
# A parameter whose whitened sensitivity is this small relative to the largest one has
# no effect on the outputs.
ZERO_SENSITIVITY = 1e-9


def unexcited_inputs(
    inputs: Sequence[str], data: np.ndarray, min_range: float = MIN_INPUT_RANGE
) -> dict[str, float]:
    """Inputs whose peak-to-peak range is below ``min_range``.

    Parameters
    ----------
    inputs : sequence of str
        The input names, one per column of ``data``.
    data : numpy.ndarray
        The input samples, SI units; shape (N, len(inputs)).
    min_range : float, optional
        The smallest peak-to-peak range, in the inputs' SI unit. Default ``MIN_INPUT_RANGE``.

    Returns
    -------
    dict of str to float
        {name: range} of the unexcited inputs.
    """
    ranges = np.ptp(np.asarray(data, dtype=float), axis=0)
    return {n: float(r) for n, r in zip(inputs, ranges, strict=True) if r < min_range}


def input_only_parameters(
    names: Sequence[str], dA: np.ndarray, dB: np.ndarray, dC: np.ndarray, dD: np.ndarray
) -> dict[str, int]:
    """Parameters that enter the model only through one input column of B and D.

    Such a parameter (a control derivative) is multiplied by that input alone, so it can
    only be estimated when the input moves.

    Parameters
    ----------
    names : sequence of str
        The parameters, one per leading index of the derivative arrays.
    dA : numpy.ndarray
        dA/dtheta; shape (np, nx, nx).
    dB : numpy.ndarray
        dB/dtheta; shape (np, nx, nu).
    dC : numpy.ndarray
        dC/dtheta; shape (np, ny, nx).
    dD : numpy.ndarray
        dD/dtheta; shape (np, ny, nu).

    Returns
    -------
    dict of str to int
        {name: input column}.
    """
    found: dict[str, int] = {}
    for k, name in enumerate(names):
        if np.any(dA[k]) or np.any(dC[k]):
            continue
        cols = np.flatnonzero(np.any(dB[k] != 0, axis=0) | np.any(dD[k] != 0, axis=0))
        if cols.size == 1:
            found[name] = int(cols[0])
    return found


def normalized_information(information: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(D^-1 M D^-1, D) with D = sqrt(diag M): the information matrix on a unit diagonal.

    Parameters
    ----------
    information : numpy.ndarray
        The information matrix M; shape (np, np).

    Returns
    -------
    tuple of numpy.ndarray
        The normalised matrix, shape (np, np), 1; and D, shape (np,), 1 / parameter unit
        (a zero diagonal entry leaves its row unscaled).
    """
    scale = np.sqrt(np.clip(np.diag(information), 0.0, None))
    safe = np.where(scale > 0, scale, 1.0)
    return information / np.outer(safe, safe), scale


def zero_sensitivity(
    names: Sequence[str], information: np.ndarray, values: np.ndarray,
    tolerance: float = ZERO_SENSITIVITY,
) -> dict[str, str]:
    """Parameters that hardly change the outputs at all, with the reason.

    Each parameter's whitened sensitivity sqrt(M_kk) times its scale (|value|, at least
    1e-2) is compared with the strongest.

    Parameters
    ----------
    names : sequence of str
        The parameters.
    information : numpy.ndarray
        The information matrix M; shape (np, np).
    values : numpy.ndarray
        The parameter values at the fit, parameter units; shape (np,).
    tolerance : float, optional
        The fraction of the strongest sensitivity below which a parameter counts as zero.
        Default ``ZERO_SENSITIVITY``.

    Returns
    -------
    dict of str to str
        {name: reason}.
    """
    # sensitivity norm times a parameter scale (|value|, at least 1e-2) makes it unit-free
    scale = np.maximum(np.abs(values), 1e-2)
    strength = np.sqrt(np.clip(np.diag(information), 0.0, None)) * scale
    top = strength.max() if strength.size else 0.0
    out: dict[str, str] = {}
    for name, s in zip(names, strength, strict=True):
        if top == 0.0 or s <= tolerance * top:
            out[name] = (
                f"zero sensitivity: the outputs do not depend on {name} in this flight "
                f"(whitened sensitivity {s:.3g} vs {top:.3g} for the strongest parameter)"
            )
    return out


def collinear(
    names: Sequence[str], information: np.ndarray, prefer_keep: Sequence[str] = (),
    tolerance: float = SINGULAR_EIGENVALUE,
) -> dict[str, str]:
    """Parameters to fix, one per (near-)null direction of the normalised information matrix.

    Repeatedly takes the eigenvector of the smallest eigenvalue of D^-1 M D^-1; while it is
    below ``tolerance`` the parameters with large components in it cannot be separated.
    The one fixed is the largest component, preferring parameters not in ``prefer_keep``.

    Parameters
    ----------
    names : sequence of str
        The parameters.
    information : numpy.ndarray
        The information matrix M; shape (np, np).
    prefer_keep : sequence of str, optional
        Parameters fixed only when nothing else can be (biases, which absorb trim terms).
    tolerance : float, optional
        The smallest eigenvalue of the normalised matrix accepted, 1. Default
        ``SINGULAR_EIGENVALUE``.

    Returns
    -------
    dict of str to str
        {name: reason naming the combination}.
    """
    names = list(names)
    keep = list(range(len(names)))
    out: dict[str, str] = {}
    while len(keep) > 1:
        sub = information[np.ix_(keep, keep)]
        normalized, _ = normalized_information(sub)
        eigval, eigvec = np.linalg.eigh(normalized)
        if eigval[0] >= tolerance:
            break
        vec = eigvec[:, 0]
        order = np.argsort(-np.abs(vec))
        members = [i for i in order if abs(vec[i]) >= 0.1 * abs(vec[order[0]])]
        candidates = [i for i in members if names[keep[i]] not in prefer_keep] or members
        drop = max(candidates, key=lambda i: abs(vec[i]))
        combo = " ".join(f"{vec[i]:+.3f} {names[keep[i]]}" for i in members)
        partners = [names[keep[i]] for i in members if i != drop]
        out[names[keep[drop]]] = (
            "cannot be separated from " + (", ".join(partners) or "the other parameters")
            + f": the normalised information matrix is singular along [{combo}] "
            f"(eigenvalue {eigval[0]:.2g} < {tolerance:g})"
        )
        del keep[drop]
    return out


def unidentifiable(
    names: Sequence[str], information: np.ndarray, values: np.ndarray,
    prefer_keep: Sequence[str] = (), tolerance: float = SINGULAR_EIGENVALUE,
) -> dict[str, str]:
    """Parameters a fit's information matrix cannot determine: {name: reason}.

    The zero-sensitivity test first; when no parameter fails it, the collinearity test on the
    normalised information matrix. Used by every maximum-likelihood method to decide what to
    fix before refitting.

    Parameters
    ----------
    names : sequence of str
        The parameters.
    information : numpy.ndarray
        The information matrix M; shape (np, np).
    values : numpy.ndarray
        The values at the fit, parameter units; shape (np,).
    prefer_keep : sequence of str, optional
        Passed to ``collinear``.
    tolerance : float, optional
        Passed to ``collinear``. Default ``SINGULAR_EIGENVALUE``.

    Returns
    -------
    dict of str to str
        {name: reason}.
    """
    found = zero_sensitivity(names, information, values)
    if found:
        return found
    return collinear(names, information, prefer_keep=prefer_keep, tolerance=tolerance)


def correlation(covariance: np.ndarray) -> np.ndarray:
    """Correlation matrix of a parameter covariance.

    Parameters
    ----------
    covariance : numpy.ndarray
        Parameter covariance, parameter units squared; shape (np, np).

    Returns
    -------
    numpy.ndarray
        The correlations, 1; shape (np, np).
    """
    s = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    s = np.where(s > 0, s, 1.0)
    return covariance / np.outer(s, s)


def high_correlations(
    names: Sequence[str], covariance: np.ndarray, threshold: float = 0.9
) -> list[tuple[str, str, float]]:
    """Pairs of parameters whose estimates correlate more than ``threshold`` in magnitude.

    Parameters
    ----------
    names : sequence of str
        The parameters.
    covariance : numpy.ndarray
        Parameter covariance, parameter units squared; shape (np, np).
    threshold : float, optional
        The magnitude of correlation above which a pair is listed, 1. Default 0.9.

    Returns
    -------
    list of tuple of (str, str, float)
        (name, name, correlation), the strongest first.
    """
    corr = correlation(covariance)
    pairs = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if abs(corr[i, j]) > threshold:
                pairs.append((names[i], names[j], float(corr[i, j])))
    return sorted(pairs, key=lambda p: -abs(p[2]))


# an input counts as excited when the peak-to-peak range of its 0.2 s moving average
# exceeds this many times the noise of that average (white noise reaches about 7 on a
# minute of data at 50 Hz; a doublet of 10 noise standard deviations reaches 60)
MIN_SIGNAL_TO_NOISE = 15.0
EXCITATION_AVERAGE_S = 0.2


def input_excitation(record: FlightRecord, inputs: Sequence[str]) -> dict[str, str]:
    """{input: why it is not excited} for the record's ``inputs`` that are constant or noise only.

    Constant: peak to peak below MIN_INPUT_RANGE in their SI unit. Noise only: the range of
    the input averaged over EXCITATION_AVERAGE_S below MIN_SIGNAL_TO_NOISE times the noise of
    that average (noise from the median absolute sample-to-sample difference, which steps do
    not inflate).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    inputs : sequence of str
        The input channels checked.

    Returns
    -------
    dict of str to str
        {input: reason} of the unexcited inputs.
    """
    out = {}
    for name in inputs:
        x = np.asarray(record[name], dtype=float)
        spread = float(np.ptp(x)) if x.size else 0.0
        if spread < MIN_INPUT_RANGE:
            out[name] = f"{name} is constant (peak to peak {spread:.2g} {record.unit(name)})"
            continue
        k = max(3, int(round(EXCITATION_AVERAGE_S / record.dt))) if record.dt > 0 else 3
        k = min(k, x.size)
        d = np.diff(x)
        noise = 1.4826 * float(np.median(np.abs(d - np.median(d)))) / np.sqrt(2.0)
        averaged = np.convolve(x, np.ones(k) / k, mode="valid")
        ratio = float(np.ptp(averaged)) / (noise / np.sqrt(k)) if noise > 0 else np.inf
        if ratio < MIN_SIGNAL_TO_NOISE:
            out[name] = (f"{name} is noise only (its {EXCITATION_AVERAGE_S:g} s average spans "
                         f"{ratio:.1f} times its noise; a maneuver spans "
                         f"{MIN_SIGNAL_TO_NOISE:g} and more)")
    return out
