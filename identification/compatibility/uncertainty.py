"""The parameter uncertainty of a flight path reconstruction.

``UNCERTAINTY`` names the kinds ``reconstruct`` offers; ``white_noise_std`` is the white
noise level of a sampled signal (third differences); ``_noise_covariance`` is the
parameter covariance from the output noise (sandwich) plus the input noise propagated
through the kinematic model by Monte Carlo (Morelli & Klein 2016 ch. 6 and 10).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from flightid.identification.compatibility.kinematics import (
    Problem,
    batch,
    corrected_inputs,
    integrate,
    model_outputs,
)
from flightid.identification.compatibility.parameters import INPUTS
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit

UNCERTAINTY = {
    "noise": "Cramer-Rao bound for the output noise plus the Monte Carlo scatter caused by "
             "the input noise (both noise levels from the data)",
    "colored": "Cramer-Rao bound corrected for colored residuals (M&K eq. 6.54)",
    "cramer-rao": "Cramer-Rao bound with the residual covariance (M&K eq. 6.50)",
}
MONTE_CARLO_RUNS = 200
OUTPUT_NOISE = "residual"


def white_noise_std(x: np.ndarray) -> float:
    """Standard deviation of the white noise on a sampled signal.

    From third differences, which remove a smooth signal: var(d3 x) = 20 sigma^2 for white
    noise; robust (median absolute deviation) against the few samples where the signal
    jerks, falling back to the rms for a coarsely quantised signal whose median is 0.

    Parameters
    ----------
    x : numpy.ndarray
        The signal, any unit; shape (n,).

    Returns
    -------
    float
        The noise standard deviation, unit of ``x``.
    """
    d = np.diff(np.asarray(x, dtype=float), 3)
    robust = 1.4826 * float(np.median(np.abs(d - np.median(d))))
    return (robust if robust > 0 else float(np.std(d))) / math.sqrt(20.0)


def _noise_covariance(problem: Problem, fit: MaximumLikelihoodFit, values: Mapping[str, float],
                      runs: int = MONTE_CARLO_RUNS, seed: int = 0) -> tuple[np.ndarray, dict]:
    """Parameter covariance from the output noise and the input noise, with their levels.

    Output noise (white, level from ``white_noise_std``): the sandwich M^-1 S^T W R_out W
    S M^-1 of the weighted least-squares step. Input noise is integrated by the model,
    so its effect is a random walk that no stationary correction captures (the colored
    correction understates it several fold); it is propagated instead: ``runs`` input
    noise histories of the measured level go through the model at the estimate, and the
    Gauss-Newton step each one causes, -M^-1 S^T W dy, gives the covariance by Monte
    Carlo (fixed ``seed``). The two sources are independent, so the covariances add.
    """
    names = fit.names
    weight = 1.0 / fit.noise
    info_inv = np.linalg.inv(fit.information)
    out_sigma = np.array([white_noise_std(problem.z[:, j]) for j in range(problem.z.shape[1])])
    # an output held between slow updates (or coarsely quantised) is far from white: its
    # error is then at least the residual (conservative), which gives M^-1 for it
    out_var = np.maximum(out_sigma**2, fit.noise) if OUTPUT_NOISE == "residual" else out_sigma**2
    ws = fit.sens * weight[None, :, None]
    middle = np.einsum("iak,a,ial->kl", ws, out_var, ws)
    cov_out = info_inv @ middle @ info_inv
    in_sigma = np.array([white_noise_std(problem.inputs[:, j]) for j in range(len(INPUTS))])
    rng = np.random.default_rng(seed)
    steps = []
    for start in range(0, runs, 50):
        k = min(50, runs - start)
        P = batch(values, k)
        a = corrected_inputs(problem, P)
        a = a + rng.standard_normal(a.shape) * in_sigma[None, :, None]
        dy = model_outputs(problem, P, integrate(problem, P, a), a) - fit.y[:, :, None]
        steps.append(-info_inv @ np.einsum("iak,a,iar->kr", fit.sens, weight, dy))
    delta = np.concatenate(steps, axis=1)
    cov_in = delta @ delta.T / delta.shape[1]
    levels = {"input_noise_std": dict(zip(INPUTS, in_sigma.tolist(), strict=True)),
              "output_noise_std": dict(zip(problem.outputs, out_sigma.tolist(), strict=True)),
              "monte_carlo_runs": runs,
              "std_output_noise": dict(zip(names, np.sqrt(np.diag(cov_out)).tolist(),
                                           strict=True)),
              "std_input_noise": dict(zip(names, np.sqrt(np.diag(cov_in)).tolist(),
                                          strict=True))}
    return cov_out + cov_in, levels
