"""Multistep inputs recovered from noisy surface measurements (total-variation denoising).

Output error takes its inputs as exact. When the measured surface of a small multistep
input carries white noise (a hobby servo potentiometer: 0.2-0.3 deg with 0.25 deg
quantisation on a 2 deg pulse), the noise enters the model as an error in the variables
and shrinks the control and damping derivatives (Telemaster card: Cl_p, Cl_da -13 %;
+6 to +8 % after this reconstruction, the level of noise-free surfaces).
A multistep (doublet, 2-1-1, 3211, pulse) is piecewise constant between its steps, which
a linear smoother cannot exploit: any cut-off that removes the noise also rounds the
steps. Total-variation denoising (Rudin, Osher & Fatemi 1992) does,

    x = argmin 1/2 sum (x_k - y_k)^2 + lambda sum |x_{k+1} - x_k|,

and is solved exactly through its dual, a box-constrained least-squares problem
(x = y - D^T z, min ||y - D^T z|| with |z_k| <= lambda; D the first difference), with
the bound-constrained L-BFGS-B of ``scipy.optimize.minimize``. The jumps of x are where
the bound is active. TV shrinks each plateau towards its neighbours by about
2 lambda / (its length in samples); the result is therefore refitted ("debiased"):
steps that are not significant against the noise are removed
and each constant run is replaced by the mean of the measurements over it, which
keeps the real steps and removes the shrinkage.

Not for sweeps or multisines, which are not piecewise constant.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize

from flightid.identification.compatibility.reconstruction import white_noise_std
from flightid.record import FlightRecord

# lambda in units of the white-noise standard deviation of the measurement: on the
# Telemaster card (surfaces at 25 Hz, 0.2-0.3 deg noise) 1, 3, 10 and 30 gave rms errors
# against the true surface of 0.08, 0.03-0.04, 0.07 and 0.20 deg (raw 0.21 deg)
DEFAULT_WEIGHT = 3.0
# a candidate step is kept when its two sides differ by this many standard errors: TV with
# lambda = 3 sigma also cuts long quiet stretches (a flat run of L samples is cut where
# the running sum of its noise leaves +-lambda, i.e. for L of order (lambda/sigma)^2);
# 4 standard errors is a two-sided false-step probability of 6e-5 per candidate
STEP_SIGNIFICANCE = 4.0


def _dual(y: np.ndarray, lam: float) -> np.ndarray:
    """The dual variable z (n-1,) of the TV problem, |z_k| <= lam, x = y - D^T z."""

    def cost(z: np.ndarray) -> tuple[float, np.ndarray]:
        x = _primal(y, z)
        return 0.5 * float(x @ x), -np.diff(x)

    bounds = scipy.optimize.Bounds(-lam, lam)
    sol = scipy.optimize.minimize(cost, np.zeros(y.size - 1), jac=True, method="L-BFGS-B",
                                  bounds=bounds, options={"maxiter": 50 * y.size,
                                                          "ftol": 1e-15, "gtol": 1e-12,
                                                          "maxcor": 30})
    return sol.x


def _primal(y: np.ndarray, z: np.ndarray) -> np.ndarray:
    x = y.copy()  # y - D^T z: x_k = y_k + z_k - z_{k-1}
    x[:-1] += z
    x[1:] -= z
    return x


def _checked(y: np.ndarray, lam: float) -> np.ndarray:
    y = np.asarray(y, dtype=float)
    if y.ndim != 1:
        raise ValueError(f"total-variation denoising takes one signal (1-D), got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError("the signal contains NaN or inf values")
    if not (np.isfinite(lam) and lam >= 0):
        raise ValueError(f"lambda must be finite and >= 0, got {lam!r}")
    return y


def total_variation(y: np.ndarray, lam: float) -> np.ndarray:
    """The total-variation denoised signal.

    Parameters
    ----------
    y : numpy.ndarray
        The signal, any unit; shape (n,).
    lam : float
        The total-variation weight, unit of ``y``.

    Returns
    -------
    numpy.ndarray
        The denoised signal, unit of ``y``; shape (n,).
    """
    y = _checked(y, lam)
    if y.size < 3 or lam == 0:
        return y.copy()
    return _primal(y, _dual(y, lam))


def piecewise_constant(y: np.ndarray, sigma: float | None = None,
                       weight: float = DEFAULT_WEIGHT,
                       significance: float = STEP_SIGNIFICANCE) -> np.ndarray:
    """A noisy multistep measurement made piecewise constant, steps kept.

    lambda = weight * sigma. The candidate steps are where the TV dual bound is active; a step
    whose two sides differ by less than ``significance`` standard errors of the difference,
    sigma sqrt(1/n1 + 1/n2), is removed (least significant first), and each remaining run is
    the mean of ``y`` over it.

    Parameters
    ----------
    y : numpy.ndarray
        The measured input, its unit; shape (n,).
    sigma : float, optional
        White-noise standard deviation of ``y``, its unit. Default ``white_noise_std(y)``.
    weight : float, optional
        lambda / sigma. Default ``DEFAULT_WEIGHT``.
    significance : float, optional
        Standard errors a kept step must exceed. Default ``STEP_SIGNIFICANCE``.

    Returns
    -------
    numpy.ndarray
        The piecewise-constant input, unit of ``y``; shape (n,).
    """
    sigma = white_noise_std(np.asarray(y, dtype=float)) if sigma is None else float(sigma)
    parts = runs(y, sigma, weight, significance)
    return np.concatenate([np.full(r.size, r.mean()) for r in parts])


def runs(y: np.ndarray, sigma: float, weight: float = DEFAULT_WEIGHT,
         significance: float = STEP_SIGNIFICANCE) -> list[np.ndarray]:
    """The constant runs of ``piecewise_constant``.

    Parameters
    ----------
    y : numpy.ndarray
        The measured input, its unit; shape (n,).
    sigma : float
        White-noise standard deviation of ``y``, its unit.
    weight : float, optional
        lambda / sigma. Default ``DEFAULT_WEIGHT``.
    significance : float, optional
        Standard errors a kept step must exceed. Default ``STEP_SIGNIFICANCE``.

    Returns
    -------
    list of numpy.ndarray
        Consecutive pieces of ``y``, one per plateau (a single piece when there is no
        significant step).
    """
    lam = weight * sigma
    y = _checked(y, lam)
    if y.size < 3 or lam == 0:
        return [y.copy()]
    z = _dual(y, lam)
    steps = np.flatnonzero(np.abs(z) >= lam * (1 - 1e-12)) + 1
    return _merged(np.split(y, steps), sigma, significance)


def _merged(runs: list[np.ndarray], sigma: float, significance: float) -> list[np.ndarray]:
    """Adjacent runs joined while the least significant step is below ``significance``."""
    runs = list(runs)
    while len(runs) > 1:
        t = [abs(a.mean() - b.mean()) / (sigma * np.sqrt(1 / a.size + 1 / b.size))
             for a, b in zip(runs[:-1], runs[1:], strict=True)]
        k = int(np.argmin(t))
        if t[k] >= significance:
            break
        runs[k:k + 2] = [np.concatenate(runs[k:k + 2])]
    return runs


def denoise_channels(record: FlightRecord, channels: list[str] | tuple[str, ...]) -> FlightRecord:
    """``record`` with the named multistep input channels made piecewise constant.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    channels : list or tuple of str
        The multistep input channels.

    Returns
    -------
    FlightRecord
        A new record with those channels replaced.

    Raises
    ------
    ValueError
        When a channel is not in the record.
    """
    missing = [c for c in channels if c not in record]
    if missing:
        raise ValueError(f"multistep input(s) {', '.join(missing)} not in the record (it has "
                         f"{', '.join(record.channels)})")
    return record.with_channels(**{c: piecewise_constant(record[c]) for c in channels})
