"""Model validation: fit and prediction metrics, residual whiteness, prediction on new data.

* TIC, J_rms and R^2 from ``engine.metrics`` (a TIC below about 0.25-0.3 is taken as a
  good match);
* Residual whiteness: the fraction of the normalised residual autocorrelation at lags
  1..L inside the 95 % band +/- 1.96 / sqrt(N) (about 95 % for white residuals), and the
  Ljung-Box portmanteau statistic Q = N (N + 2) sum_k r_k^2 / (N - k), chi-square with L
  degrees of freedom for white residuals (Ljung & Box 1978).
* Prediction: an equation-error model applied to a maneuver not used for fitting
  (the "prediction cases" of Morelli & Klein 2016).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.stats import chi2

from flightid.identification.data.coefficients import channel_values
from flightid.identification.engine.metrics import j_rms, paired, r_squared, theil_inequality
from flightid.identification.estimate import Estimate
from flightid.identification.methods.equation_error import predict as ee_predict
from flightid.record import FlightRecord


@dataclass
class Whiteness:
    """Residual whiteness: autocorrelation band fraction and Ljung-Box test."""

    lags: int
    bound: float  # 1.96 / sqrt(N)
    fraction_inside: float  # share of lags 1..lags whose autocorrelation is inside the bound
    ljung_box_q: float
    p_value: float  # probability of a Q this large for white residuals
    white: bool  # p_value > 0.05


def autocorrelation(residual: np.ndarray, max_lag: int) -> np.ndarray:
    """Normalised autocorrelation r_k (k = 0..max_lag) of a residual, biased estimate.

    Parameters
    ----------
    residual : numpy.ndarray
        The residual sequence; shape (N,).
    max_lag : int
        The largest lag, samples.

    Returns
    -------
    numpy.ndarray
        r_0 .. r_max_lag, 1 (r_0 = 1; zeros for a constant residual); shape (max_lag + 1,).
    """
    v = np.asarray(residual, dtype=float) - np.mean(residual)
    n = v.size
    full = np.correlate(v, v, mode="full")[n - 1: n + max_lag]
    return full / full[0] if full[0] > 0 else np.zeros(max_lag + 1)


def residual_whiteness(residual: np.ndarray, max_lag: int | None = None) -> Whiteness:
    """Whiteness of a residual sequence: lags inside the 95 % band and the Ljung-Box test.

    Parameters
    ----------
    residual : numpy.ndarray
        The residual sequence, at least 10 samples; shape (N,).
    max_lag : int, optional
        The largest lag, samples. Default min(20, N/5) (Ljung & Box).

    Returns
    -------
    Whiteness
        The lags, the band 1.96/sqrt(N), the fraction of lags inside it, Q, its p-value and
        whether p > 0.05.

    Raises
    ------
    ValueError
        For fewer than 10 residuals.
    """
    v = np.asarray(residual, dtype=float)
    n = v.size
    if n < 10:
        raise ValueError(f"whiteness needs at least 10 residuals, got {n}")
    lags = max_lag if max_lag is not None else int(min(20, n // 5))
    r = autocorrelation(v, lags)[1:]
    bound = 1.96 / np.sqrt(n)
    k = np.arange(1, lags + 1)
    q = float(n * (n + 2) * np.sum(r**2 / (n - k)))
    p = float(chi2.sf(q, lags))
    return Whiteness(lags, float(bound), float(np.mean(np.abs(r) <= bound)), q, p, p > 0.05)


def metrics(y: np.ndarray, yhat: np.ndarray) -> dict[str, float]:
    """TIC, J_rms, R2 and residual whiteness of a model output against measured data.

    Parameters
    ----------
    y : numpy.ndarray
        Measured output.
    yhat : numpy.ndarray
        Model output, same shape and unit.

    Returns
    -------
    dict of str to float
        TIC, J_rms, R2, whiteness_fraction, ljung_box_q, ljung_box_p.
    """
    y, yhat = paired(y, yhat)
    white = residual_whiteness(y - yhat)
    return {
        "TIC": theil_inequality(y, yhat),
        "J_rms": j_rms(y, yhat),
        "R2": r_squared(y, yhat),
        "whiteness_fraction": white.fraction_inside,
        "ljung_box_q": white.ljung_box_q,
        "ljung_box_p": white.p_value,
    }


@dataclass
class Prediction:
    """An equation-error model's prediction of one coefficient on a record."""

    coefficient: str
    time: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    bias_shift: float  # added to the prediction when the bias was re-estimated
    metrics: dict[str, float]

    def as_dict(self) -> dict:
        """JSON form without the time histories."""
        d = asdict(self)
        for key in ("time", "measured", "predicted"):
            d.pop(key)
        return d


def predict_record(est: Estimate, record: FlightRecord, refit_bias: bool = True) -> Prediction:
    """Predict the fitted coefficient on another maneuver and score the prediction.

    The derivatives are fixed at the fitted values. With ``refit_bias`` the constant term is
    re-estimated on the new maneuver (the mean prediction error is removed), as in SIDPAC
    prediction cases: a new maneuver starts from its own trim, which a perturbation model's
    bias does not know.

    Parameters
    ----------
    est : Estimate
        An equation-error estimate of one coefficient.
    record : FlightRecord
        The other maneuver, SI channels.
    refit_bias : bool, optional
        Re-estimate the constant term. Default True.

    Returns
    -------
    Prediction
        The coefficient, time (s), measured and predicted values (dimensionless), the shift
        and the ``metrics``.
    """
    coefficient = est.fit["coefficient"]
    measured = channel_values(record, coefficient)
    predicted = ee_predict(est, record)
    shift = float(np.mean(measured - predicted)) if refit_bias else 0.0
    predicted = predicted + shift
    return Prediction(coefficient, record.time.copy(), measured, predicted, shift,
                      metrics(measured, predicted))
