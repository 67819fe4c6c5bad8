"""The information an episode gathers about its target derivatives: one regularised
least-squares regression per coefficient, updated sample by sample (D-optimality;
Morelli & Klein 2016, ch. 9)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flightid.scenarios.gym.kernels import rank_one
from flightid.scenarios.gym.options import SIGMA


def regression_designs(spec: Sequence[tuple[str, tuple[str, ...]]]
             ) -> tuple[list[int], list[tuple[tuple[str, ...], float]]]:
    """(each coefficient's design, the designs): a design is (variables, residual std);
    coefficients with the same one share an information matrix.

    Parameters
    ----------
    spec : Sequence[tuple[str, tuple[str, ...]]]
        Per coefficient, (coefficient name, its regressor variables).

    Returns
    -------
    tuple[list[int], list[tuple[tuple[str, ...], float]]]
        (design index per coefficient, the distinct designs).
    """
    keys = [(v, SIGMA[c]) for c, v in spec]
    unique = list(dict.fromkeys(keys))
    return [unique.index(k) for k in keys], unique


class Information:
    """Information, inverse and estimate of every coefficient's regression.

    Coefficients with the same regressors and residual std (Cl and Cn of the lateral
    preset) share one information matrix: ``design[g]`` is coefficient g's, and a shared
    matrix counts once per coefficient in log det. Designs with fewer variables are padded
    with regressors that stay zero: with the prior I their entries stay decoupled
    (information 1, no contribution to log det). Each sample is a rank-one update of
    P = M^-1 (Sherman-Morrison) and of the estimate (recursive least squares, Ljung &
    Soderstrom 1983, which with P_0 = I and theta_0 = 0 is exactly M^-1 X^T W y), compiled
    (``kernels.rank_one``).
    """

    def __init__(self, spec: Sequence[tuple[str, tuple[str, ...]]]) -> None:
        design, unique = regression_designs(spec)
        k = 1 + max(len(v) for _, v in spec)
        nd, ng = len(unique), len(spec)
        self.design = np.array(design, dtype=np.int64)
        self.w = np.array([1.0 / s**2 for _, s in unique])  # per design
        self.count = np.array([design.count(d) for d in range(nd)], dtype=float)
        self.w_coef = np.array([1.0 / SIGMA[c] ** 2 for c, _ in spec])
        # one flat array (the compiled step's ``state``) and its views: inv (D, k, k),
        # theta (G, k), acc = [sum over coefficients of log det M (prior I), the samples'
        # summed weights]
        self.state = np.zeros(nd * k * k + ng * k + 2)
        self.inv = self.state[:nd * k * k].reshape(nd, k, k)
        self.inv[:] = np.eye(k)
        self.theta = self.state[nd * k * k:nd * k * k + ng * k].reshape(ng, k)
        self.acc = self.state[nd * k * k + ng * k:]

    @property
    def logdet_m(self) -> float:
        """Sum over the coefficients of log det M."""
        return float(self.acc[0])

    @property
    def logdet(self) -> float:
        """Sum of log det of the targets' information (Schur complements of the biases)."""
        return float(self.acc[0] - np.sum(np.log1p(self.acc[1] * self.w_coef)))

    def add(self, x: Sequence[Sequence[float]], y: Sequence[float], weight: float = 1.0
            ) -> None:
        """One sample: regressors x (per design, bias first), dependent variables y (per
        coefficient), with ``weight`` in [0, 1] on its information (weighted least squares:
        the residual's variance sigma^2 / weight)."""
        rank_one(self.inv, self.theta, self.design, self.w, self.count,
                 np.asarray(x, dtype=float), np.asarray(y, dtype=float), float(weight), self.acc)
