"""The model curve relocated to the flight points: per derivative, the flight estimates
across a campaign against the model's values at the same conditions.

The F-111C approach (Cooper, Drobik & Martin, DSTO Flight Mechanics Report 187, 1990,
section 4.7): "relocate the model data curve to best fit the flight derivatives": the
model supplies the trend, flight the level. With flight estimates y_i (standard errors
s_i) and the model's values m_i at the points' conditions x_i, the forms tried are

- ``shift``:        y = m + a
- ``scale``:        y = b m
- ``shift+slope``:  y = m + a + c (x - x0)   (x0 the points' mean x; needs 3 points)

each by weighted least squares (weights 1/s_i^2; Morelli & Klein 2016 eq. 5.30). A
derivative is corrected only when the model itself is rejected (chi^2 of y - m above
its ``LEVEL`` quantile with n degrees of freedom: the flights disagree with the tables
beyond their bounds), and only by a form that explains the disagreement: its residual
chi^2 below its ``LEVEL`` quantile with n - k degrees of freedom, or below ``EXPLAINED``
of the model's chi^2 (the form takes away at least 95 % of the disagreement; what is left
is a structure error of the point's linear model that its Cramer-Rao bounds do not
cover, e.g. Cn_beta read at the mean airspeed of the lateral maneuver, not at the trim's);
among those, the smallest AIC = chi^2 + 2k (Akaike 1974). A derivative whose points no
form explains (a structure error at one point, a kink) is left as the model has it, with
the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

LEVEL = 0.999  # chi^2 quantile: a model rejected, a form accepted
EXPLAINED = 0.05  # a form leaving at most this share of the model's chi^2 is accepted
FORMS = ("shift", "scale", "shift+slope")


@dataclass(frozen=True)
class Correction:
    """The relocation of one derivative's model curve: y = b m + a + c (x - x0).

    form: 'none' (the model is kept) or one of ``FORMS``; chi2_model: chi^2 of the flight
    points about the model; chi2: about the corrected curve; n: the points; reason: why
    the model was kept, empty otherwise.
    """

    name: str
    form: str
    shift: float = 0.0
    scale: float = 1.0
    slope: float = 0.0
    x0: float = 0.0
    chi2_model: float = 0.0
    chi2: float = 0.0
    n: int = 0
    reason: str = ""

    def value(self, x: float | np.ndarray, model: float | np.ndarray) -> np.ndarray:
        """The corrected derivative at condition x where the model has ``model``."""
        return self.scale * np.asarray(model) + self.shift + self.slope * (np.asarray(x)
                                                                          - self.x0)

    def delta(self, x: float | np.ndarray, model: float | np.ndarray) -> np.ndarray:
        """Corrected minus model at x."""
        return self.value(x, model) - np.asarray(model)


def _wls(columns: list[np.ndarray], target: np.ndarray, w: np.ndarray
         ) -> tuple[np.ndarray, float]:
    X = np.column_stack(columns) * w[:, None]
    theta, *_ = np.linalg.lstsq(X, target * w, rcond=None)
    resid = target * w - X @ theta
    return theta, float(resid @ resid)


def fit_correction(name: str, x: np.ndarray, estimate: np.ndarray, std: np.ndarray,
                   model: np.ndarray, trend: bool = True, level: float = LEVEL
                   ) -> Correction:
    """The relocation of derivative ``name``'s model curve to its flight points.

    Parameters
    ----------
    name : str
        The derivative.
    x : numpy.ndarray
        The points' condition (the campaign's x: m/s, rad, ...); shape (n,).
    estimate : numpy.ndarray
        The flight estimates, the derivative's unit; shape (n,).
    std : numpy.ndarray
        Their standard errors, same unit; shape (n,).
    model : numpy.ndarray
        The model's values at the same conditions; shape (n,).
    trend : bool, optional
        Allow the ``shift+slope`` form (False where x cannot carry a table). Default True.
    level : float, optional
        The chi^2 quantile for rejecting the model and accepting a form. Default ``LEVEL``.

    Returns
    -------
    Correction
        The accepted form with the least AIC, or form "none" with the reason the model is
        kept.
    """
    x, y, s, m = (np.asarray(a, dtype=float) for a in (x, estimate, std, model))
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(s) & (s > 0) & np.isfinite(m)
    x, y, s, m = x[ok], y[ok], s[ok], m[ok]
    n = int(x.size)
    if n == 0:
        return Correction(name, "none", reason="no flight point")
    w = 1.0 / s
    chi2_model = float(np.sum(((y - m) * w) ** 2))
    if chi2_model <= stats.chi2.ppf(level, n):
        return Correction(name, "none", chi2_model=chi2_model, chi2=chi2_model, n=n,
                          reason=f"the flights agree with the model (chi2 {chi2_model:.1f} "
                                 f"for {n} points)")
    x0 = float(np.mean(x))
    fits: list[Correction] = []
    (a,), chi2 = _wls([np.ones(n)], y - m, w)
    fits.append(Correction(name, "shift", shift=float(a), x0=x0, chi2_model=chi2_model,
                           chi2=chi2, n=n))
    if np.any(np.abs(m) > 0):
        (b,), chi2 = _wls([m], y, w)
        fits.append(Correction(name, "scale", scale=float(b), x0=x0, chi2_model=chi2_model,
                               chi2=chi2, n=n))
    if trend and n >= 3 and np.ptp(x) > 0:
        (a, c), chi2 = _wls([np.ones(n), x - x0], y - m, w)
        fits.append(Correction(name, "shift+slope", shift=float(a), slope=float(c), x0=x0,
                               chi2_model=chi2_model, chi2=chi2, n=n))
    k = {"shift": 1, "scale": 1, "shift+slope": 2}
    accepted = [f for f in fits if n - k[f.form] == 0 or f.chi2 <= EXPLAINED * chi2_model
                or (n - k[f.form] > 0 and f.chi2 <= stats.chi2.ppf(level, n - k[f.form]))]
    if not accepted:
        best = min(fits, key=lambda f: f.chi2)
        return Correction(name, "none", chi2_model=chi2_model, chi2=chi2_model, n=n,
                          reason=f"no form fits the points within their bounds (best "
                                 f"{best.form}: chi2 {best.chi2:.1f} for {n} points)")
    return min(accepted, key=lambda f: f.chi2 + 2 * k[f.form])


def aic(correction: Correction) -> float:
    """chi^2 + 2k of a correction (k its parameters; 0 for the model kept).

    Parameters
    ----------
    correction : Correction
        A fitted correction.

    Returns
    -------
    float
        Akaike's criterion, 1; inf when its chi^2 is not finite.
    """
    k = {"none": 0, "shift": 1, "scale": 1, "shift+slope": 2}[correction.form]
    return correction.chi2 + 2 * k if math.isfinite(correction.chi2) else math.inf
