"""Equation error: ordinary least squares of a measured coefficient on named regressors.

Model (Morelli & Klein 2016, ch. 5): for a coefficient such as Cl,

    Cl(i) = Cl_0 + sum_j theta_j x_j(i) + v(i)

where each regressor x_j is a term of record channels taken as a perturbation from a
reference value (the record mean by default, or the initial value, as SIDPAC does), and
Cl_0 is the bias (the coefficient at the reference condition). A term is a channel
("beta", "phat", "de"), a derivative variable ("p" means phat), or a product or power
of them ("alpha^2", "alpha*de"); linear terms give canonical derivative names (Cl_p,
Cn_dr), others ``C<coef>_<term>`` (Cm_alpha^2).

Standard errors: the Cramer-Rao bounds s^2 (X'X)^-1 and, by default, the
bounds corrected for colored residuals (Morelli & Klein 2016, ch. 5, least squares
with colored residuals):

    Cov = (X'X)^-1 [sum_i sum_j X(i) R_vv(i - j) X(j)'] (X'X)^-1,
    R_vv(k) = (1/N) sum_i v(i) v(i + k),

evaluated here by FFT convolution, so the cost is O(p N log N), not O(N^2).
Regressors that the data cannot separate (constant, or collinear with others) are not
estimated: they go to ``Estimate.unidentifiable`` with the reason.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import fftconvolve

from flightid.identification.data.coefficients import (
    HINGE,
    channel_values,
    differentiated,
    smoothed,
)
from flightid.identification.engine.metrics import determination
from flightid.identification.estimate import Estimate, merge
from flightid.identification.methods.protocol import Method, RegressionOptions, option
from flightid.identification.models import a_priori
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

ID = "ee"
# coefficient channel -> letter of its derivative names (flightid.derivatives)
COEF_LETTER = {"CX": "X", "CY": "Y", "CZ": "Z", "CL": "L", "CD": "D", "Cl": "l", "Cm": "m",
               "Cn": "n"}
# term factor -> record channel; derivative variables map to their nondimensional channel
FACTOR_CHANNEL = {"p": "phat", "q": "qhat", "r": "rhat", "dt": "throttle", "alphadot":
                  "alphadot_hat"}
# channel -> derivative variable of flightid.derivatives
CHANNEL_VARIABLE = {"phat": "p", "qhat": "q", "rhat": "r", "throttle": "dt",
                    "alphadot_hat": "alphadot"}
DERIVED_CHANNELS = ("phat", "qhat", "rhat", "alphadot_hat")
DERIVED_BY_DIFFERENTIATION = ("alphadot_hat",)
COLLINEAR_R = 0.99  # pairwise |correlation| above which two regressors are inseparable
# VIF above which a regressor is (nearly) a linear combination of the others; the same
# threshold as the pairwise one: R_j^2 > 0.99^2
VIF_LIMIT = 1.0 / (1.0 - COLLINEAR_R**2)
REFERENCES = ("mean", "initial", "none")
# A control that moves less than this (peak to peak, SI unit) carries no excitation: below
# the resolution of control-position sensors (about 0.1 deg = 1.7e-3 rad) and far below
# any test input; the same limit as identification/engine/identifiability.py MIN_INPUT_RANGE.
MIN_CONTROL_RANGE = {"de": 1e-3, "da": 1e-3, "dr": 1e-3, "df": 1e-3, "throttle": 1e-3}
CONTROL_CHANNELS = tuple(MIN_CONTROL_RANGE)
# a term: a channel or a spline factor (``HINGE``, its anchors stripped), to a power
_TERM = re.compile(rf"^([A-Za-z_][A-Za-z0-9_]*|{HINGE.pattern[1:-1]})(\^[1-9])?$")


@dataclass(frozen=True)
class Term:
    """A regressor: a product of channels raised to powers, e.g. alpha^2 or alpha*de."""

    text: str
    factors: tuple[tuple[str, int], ...]  # (channel, power)

    @property
    def is_linear(self) -> bool:
        return len(self.factors) == 1 and self.factors[0][1] == 1


def parse_term(text: str) -> Term:
    """A Term from text such as 'beta', 'p', 'alpha^2', 'alpha*de'.

    Parameters
    ----------
    text : str
        Channels joined by '*', each with an optional power '^k' (k 1-9), or a spline
        factor such as '(alpha-8deg)+'; 'p', 'q', 'r', 'dt', 'alphadot' name their
        nondimensional channels (``FACTOR_CHANNEL``).

    Returns
    -------
    Term
        The term, its factors as (channel, power).

    Raises
    ------
    ValueError
        The text is empty or a factor is malformed.
    """
    text = text.strip()
    if not text:
        raise ValueError("empty regressor name")
    factors = []
    for part in text.split("*"):
        part = part.strip()
        if not _TERM.match(part):
            raise ValueError(
                f"regressor {text!r}: cannot read factor {part!r}; write channels joined by "
                "'*' with optional powers, e.g. 'alpha', 'alpha^2', 'alpha*de', "
                "'(alpha-8deg)+^2' (a spline: max(alpha - 8 deg, 0)^2)"
            )
        name, _, power = part.partition("^")
        factors.append((FACTOR_CHANNEL.get(name, name), int(power) if power else 1))
    return Term(text, tuple(factors))


def derivative_name(coefficient: str, term: Term) -> str:
    """Name of the parameter of ``term`` in the model of ``coefficient`` (Cl, beta -> Cl_beta).

    Parameters
    ----------
    coefficient : str
        Coefficient channel, a key of ``COEF_LETTER`` (e.g. 'Cl').
    term : Term
        The regressor.

    Returns
    -------
    str
        Canonical derivative name for a linear term (Cl_p), else ``C<letter>_<term>``
        (Cm_alpha^2).

    Raises
    ------
    ValueError
        ``coefficient`` is unknown.
    """
    letter = _letter(coefficient)
    if term.is_linear:
        channel = term.factors[0][0]
        return f"C{letter}_{CHANNEL_VARIABLE.get(channel, channel)}"
    parts = []
    for channel, power in term.factors:
        var = CHANNEL_VARIABLE.get(channel, channel)
        parts.append(var if power == 1 else f"{var}^{power}")
    return f"C{letter}_{'*'.join(parts)}"


def bias_name(coefficient: str) -> str:
    """Name of the bias parameter of a coefficient model (Cl -> Cl_0).

    Parameters
    ----------
    coefficient : str
        Coefficient channel, a key of ``COEF_LETTER``.

    Returns
    -------
    str
        ``C<letter>_0``.

    Raises
    ------
    ValueError
        ``coefficient`` is unknown.
    """
    return f"C{_letter(coefficient)}_0"


def reference_values(
    record: FlightRecord, terms: Sequence[Term], reference: str = "mean"
) -> dict[str, float]:
    """Reference value of each factor channel of the terms, for perturbations.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    terms : sequence of Term
        The regressors.
    reference : str, optional
        'mean' (default: the record mean), 'initial' (the first sample) or 'none' (0).
        A spline factor's reference is always 0 (its origin is its knot).

    Returns
    -------
    dict of str to float
        {channel: reference value}, in the channel's SI unit.

    Raises
    ------
    ValueError
        ``reference`` is not in ``REFERENCES``.
    """
    if reference not in REFERENCES:
        raise ValueError(f"reference must be one of {REFERENCES}, got {reference!r}")
    out: dict[str, float] = {}
    for term in terms:
        for channel, _ in term.factors:
            if channel in out:
                continue
            x = channel_values(record, channel)  # a spline factor's origin is its knot
            out[channel] = (
                0.0 if HINGE.match(channel) or reference == "none"
                else float(np.mean(x)) if reference == "mean" else float(x[0]))
    return out


def regressor_matrix(
    record: FlightRecord, terms: Sequence[Term], references: dict[str, float]
) -> np.ndarray:
    """Each term evaluated on the perturbations channel - reference.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    terms : sequence of Term
        The regressors.
    references : dict of str to float
        {channel: reference value} (``reference_values``); a missing channel takes 0.

    Returns
    -------
    numpy.ndarray
        Regressor matrix, shape (N, len(terms)), in the terms' units.

    Raises
    ------
    ValueError
        A regressor is not finite; the message names the sample and time.
    """
    columns = []
    cache: dict[str, np.ndarray] = {}
    for term in terms:
        col = np.ones(len(record))
        for channel, power in term.factors:
            if channel not in cache:
                cache[channel] = channel_values(record, channel) - references.get(channel, 0.0)
            col = col * cache[channel] ** power
        if not np.all(np.isfinite(col)):
            i = int(np.argmax(~np.isfinite(col)))
            raise ValueError(f"regressor {term.text!r} is not finite at sample {i} "
                             f"(t = {record.time[i]} s)")
        columns.append(col)
    return np.column_stack(columns) if columns else np.empty((len(record), 0))


def colored_residual_covariance(x: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Parameter covariance corrected for colored residuals (Morelli & Klein 2016, ch. 5).

    The residual autocorrelation is the biased estimate over all lags.

    Parameters
    ----------
    x : numpy.ndarray
        Regressor matrix, shape (N, p).
    residual : numpy.ndarray
        Equation-error residuals, shape (N,).

    Returns
    -------
    numpy.ndarray
        Covariance, shape (p, p), in the parameters' units squared; symmetric.
    """
    n = residual.size
    rvv = np.correlate(residual, residual, mode="full")[n - 1:] / n if n < 4096 else (
        fftconvolve(residual, residual[::-1], mode="full")[n - 1:] / n
    )
    kernel = np.concatenate([rvv[:0:-1], rvv])  # R(|k|), k = -(n-1) .. n-1
    # (T x)(i) = sum_j R(|i - j|) x(j): a convolution with the symmetric kernel
    tx = fftconvolve(kernel[:, None], x, mode="full", axes=0)[n - 1: 2 * n - 1]
    xtx_inv = np.linalg.inv(x.T @ x)
    middle = x.T @ tx
    cov = xtx_inv @ middle @ xtx_inv
    return 0.5 * (cov + cov.T)


def identifiability(
    x: np.ndarray, names: Sequence[str], terms: Sequence[Term], record: FlightRecord
) -> dict[str, str]:
    """Parameters the regressors cannot determine, with the reason.

    A regressor is unidentifiable when it has no excitation (constant, or a control that
    moves less than MIN_CONTROL_RANGE), when it is collinear with another (|r| > 0.99),
    or when it is nearly a linear combination of the others (variance inflation factor
    above 1/(1 - 0.99^2)).

    Parameters
    ----------
    x : numpy.ndarray
        Regressor matrix, shape (N, p).
    names : sequence of str
        Parameter name of each column.
    terms : sequence of Term
        The term of each column.
    record : FlightRecord
        The flight, for the units named in the reasons.

    Returns
    -------
    dict of str to str
        {parameter: reason}; empty when all are identifiable.
    """
    bad: dict[str, str] = {}
    keep = []
    for j, term in enumerate(terms):
        col = x[:, j]
        spread = float(np.std(col))
        scale = max(float(np.max(np.abs(col))), 1.0)
        control = term.is_linear and term.factors[0][0] in CONTROL_CHANNELS
        if spread <= 1e-12 * scale:
            unit = _term_unit(record, term)
            bad[names[j]] = (f"{term.text} is constant (std {spread:.1f} {unit}) in this record")
        elif control and np.ptp(col) < MIN_CONTROL_RANGE[term.factors[0][0]]:
            unit = _term_unit(record, term)
            bad[names[j]] = (
                f"{term.text} is not excited (peak-to-peak {np.ptp(col):.2g} {unit}, below "
                f"{MIN_CONTROL_RANGE[term.factors[0][0]]:g} {unit}) in this record"
            )
        else:
            keep.append(j)
    if len(keep) < 2:
        return bad
    centred = x[:, keep] - x[:, keep].mean(axis=0)
    centred /= np.linalg.norm(centred, axis=0)
    corr = centred.T @ centred
    collinear: set[int] = set()
    for a in range(len(keep)):
        for b in range(a + 1, len(keep)):
            if abs(corr[a, b]) > COLLINEAR_R:
                collinear.update((a, b))
                reason = (f"{names[keep[a]]} and {names[keep[b]]} are collinear "
                          f"(r = {corr[a, b]:.3f})")
                for k in (a, b):
                    bad.setdefault(names[keep[k]], reason)
    rest = [k for k in range(len(keep)) if k not in collinear]
    while len(rest) >= 2:
        sub = corr[np.ix_(rest, rest)]
        try:
            vif = np.diag(np.linalg.inv(sub))
        except np.linalg.LinAlgError:
            vif = np.full(len(rest), np.inf)
        worst = int(np.argmax(vif))
        if not vif[worst] > VIF_LIMIT:
            break
        # name the regressors that carry the dependence (auxiliary regression weights)
        others_idx = [k for i, k in enumerate(rest) if i != worst]
        w, *_ = np.linalg.lstsq(centred[:, others_idx], centred[:, rest[worst]], rcond=None)
        others = [names[keep[k]] for k, wk in zip(others_idx, w, strict=True)
                  if abs(wk) >= 0.1 * np.max(np.abs(w))]
        r2 = 1.0 - 1.0 / vif[worst] if np.isfinite(vif[worst]) else 1.0
        bad[names[keep[rest[worst]]]] = (
            f"{names[keep[rest[worst]]]} is nearly a linear combination of "
            f"{', '.join(others)} (R^2 = {r2:.4f}, VIF {vif[worst]:.0f})"
        )
        rest.pop(worst)
    return bad


def estimate(
    record: FlightRecord,
    coefficient: str,
    regressors: Iterable[str],
    *,
    bias: bool = True,
    reference: str = "mean",
    colored: bool = True,
    consistent_smoothing: bool = False,
    a_priori: Mapping[str, float] | None = None,
) -> Estimate:
    """OLS estimate of ``coefficient``'s derivatives on ``regressors`` (per rad, dimensionless).

    The coefficient is the record's channel of that name, or is computed from the record
    (flightid.identification.data.coefficients).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    coefficient : str
        Coefficient to model, a key of ``COEF_LETTER`` (e.g. 'Cl').
    regressors : iterable of str
        Regressor terms (``parse_term``), e.g. 'beta', 'p', 'alpha^2'.
    bias : bool, optional
        Estimate the constant C<letter>_0. Default True.
    reference : str, optional
        Perturbation reference: 'mean' (default), 'initial' or 'none'.
    colored : bool, optional
        Standard errors corrected for colored residuals (fit['std_kind'] 'corrected';
        default) or the plain OLS ones ('OLS').
    consistent_smoothing : bool, optional
        Where the coefficient comes from smoothed derivatives of the rates (a moment
        coefficient without measured angular accelerations), pass the regressors through
        the same smoothing filter, so that both sides of the regression see the same
        filter (Morelli & Klein 2016 sec. 11.2: a filter applied to the dependent variable
        alone biases the estimates; a sharp surface input loses up to 20 % of its moment
        derivative to the 0.2 s fit otherwise). Default False.
    a_priori : mapping of str to float or None, optional
        Derivatives of this coefficient held at known values ({"Cm_alphadot": -4.4}):
        their terms move to the measured side, y - sum value x (Morelli & Klein 2016
        sec. 5.5, a priori information), and they leave the regressors.

    Returns
    -------
    Estimate
        Derivatives and bias with standard errors, fit statistics (``least_squares``), the
        unidentifiable regressors with reasons, and the measured and modelled coefficient.

    Raises
    ------
    ValueError
        An unknown coefficient, repeated or malformed regressors, or no regressor that can
        be estimated.
    """
    _letter(coefficient)
    terms = [parse_term(t) for t in regressors]
    if len({t.text for t in terms}) != len(terms):
        raise ValueError(f"regressors repeat: {[t.text for t in terms]}")
    held = {derivative_name(coefficient, parse_term(v)): (parse_term(v), float(value))
            for v, value in _held_terms(coefficient, a_priori or {}).items()}
    terms = [t for t in terms if derivative_name(coefficient, t) not in held]
    y = channel_values(record, coefficient)
    refs = reference_values(record, terms + [t for t, _ in held.values()], reference)
    x_all = regressor_matrix(record, terms, refs)
    x_held = regressor_matrix(record, [t for t, _ in held.values()], refs)
    smoothed_x = consistent_smoothing and differentiated(record, coefficient)
    if smoothed_x:
        x_all = smooth_columns(x_all, terms, record.dt)
        x_held = smooth_columns(x_held, [t for t, _ in held.values()], record.dt)
    if held:
        y = y - x_held @ np.array([value for _, value in held.values()])
    names_all = [derivative_name(coefficient, t) for t in terms]
    unident = identifiability(x_all, names_all, terms, record)
    keep = [j for j, n in enumerate(names_all) if n not in unident]
    names = [names_all[j] for j in keep]
    kept_terms = [terms[j] for j in keep]
    x = x_all[:, keep]
    if bias:
        x = np.column_stack([x, np.ones(len(record))])
        names.append(bias_name(coefficient))
    if x.shape[1] == 0:
        raise ValueError(f"no regressor of {coefficient} can be estimated: {unident}")
    result = least_squares(x, y, colored=colored)
    fit = {
        "coefficient": coefficient,
        "regressors": [t.text for t in kept_terms],
        "reference": reference,
        "reference_values": refs,
        "bias": bias,
        "consistent_smoothing": smoothed_x,
        "fixed": {name: value for name, (_, value) in held.items()},
        **result.statistics,
    }
    return Estimate(
        method=ID,
        names=names,
        values=result.theta,
        std=result.std,
        covariance=result.covariance,
        fit=fit,
        unidentifiable=unident,
        outputs={coefficient: {"measured": y, "model": result.model,
                               "residual": y - result.model}},
        time=record.time.copy(),
    )


@dataclass
class LeastSquares:
    """Result of one least-squares fit: parameters, covariance and statistics."""

    theta: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    model: np.ndarray
    statistics: dict


def smooth_columns(x: np.ndarray, terms: Sequence[Term], dt: float) -> np.ndarray:
    """Regressor columns through ``coefficients.smoothed``.

    A column that is itself a smoothed derivative (alphadot_hat) already carries the
    filter and is left as is.

    Parameters
    ----------
    x : numpy.ndarray
        Regressor matrix, shape (N, p).
    terms : sequence of Term
        The term of each column.
    dt : float
        Sample interval, s.

    Returns
    -------
    numpy.ndarray
        Smoothed regressor matrix, shape (N, p).
    """
    cols = [col if any(c in DERIVED_BY_DIFFERENTIATION for c, _ in term.factors)
            else smoothed(col, dt) for col, term in zip(x.T, terms, strict=True)]
    return np.column_stack(cols) if cols else x


def _held_terms(coefficient: str, a_priori: Mapping[str, float]) -> dict[str, float]:
    """{regressor channel: value} of the a priori derivatives of ``coefficient``."""
    letter = _letter(coefficient)
    out = {}
    for name, value in a_priori.items():
        coef, _, variable = name.partition("_")
        if coef == f"C{letter}" and variable:
            out[FACTOR_CHANNEL.get(variable, variable)] = value
    return out


def least_squares(x: np.ndarray, y: np.ndarray, colored: bool = True) -> LeastSquares:
    """OLS of y on the columns of x with Cramer-Rao bounds, optionally colored-corrected.

    Parameters
    ----------
    x : numpy.ndarray
        Regressor matrix, shape (N, p).
    y : numpy.ndarray
        Dependent variable, shape (N,).
    colored : bool, optional
        Covariance corrected for colored residuals (default) or plain OLS s^2 (X'X)^-1.

    Returns
    -------
    LeastSquares
        theta (p,), std (p,), covariance (p, p), model (N,) and statistics: R2 (about the
        mean), s2 = SSE/(N - p), F, PSE (Morelli & Klein 5.4), N, n_parameters,
        condition_number, std_kind, std_ols.

    Raises
    ------
    ValueError
        N <= p.
    """
    n, p = x.shape
    if n <= p:
        raise ValueError(f"{n} samples cannot determine {p} parameters")
    theta, *_ = np.linalg.lstsq(x, y, rcond=None)
    model = x @ theta
    v = y - model
    sse = float(v @ v)
    s2 = sse / (n - p)
    xtx_inv = np.linalg.inv(x.T @ x)
    cov_ols = s2 * xtx_inv
    std_ols = np.sqrt(np.diag(cov_ols))
    if colored:
        cov = colored_residual_covariance(x, v)
        kind = "corrected"
    else:
        cov = cov_ols
        kind = "OLS"
    sst = float(np.sum((y - y.mean()) ** 2))
    r2 = determination(sse, sst)
    sigma_max2 = sst / n
    # count the regressors other than a constant column for the F statistic
    has_const = np.any(np.all(np.isclose(x, x[:1]), axis=0))
    k = p - 1 if has_const else p
    f_stat = ((sst - sse) / k) / s2 if k > 0 and s2 > 0 else math.nan
    col_norm = np.linalg.norm(x, axis=0)
    col_norm[col_norm == 0] = 1.0
    cond = float(np.linalg.cond(x / col_norm))
    return LeastSquares(
        theta=theta,
        std=np.sqrt(np.diag(cov)),
        covariance=cov,
        model=model,
        statistics={
            "R2": r2,
            "s2": s2,
            "F": f_stat,
            "PSE": sse / n + sigma_max2 * p / n,
            "N": n,
            "n_parameters": p,
            "condition_number": cond,
            "std_kind": kind,
            "std_ols": std_ols,
        },
    )


def estimate_model(
    record: FlightRecord, model: dict[str, Sequence[str]], **options
) -> list[Estimate]:
    """Equation error for each coefficient of ``model``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : dict of str to sequence of str
        {coefficient: regressors}.
    **options
        Keywords of ``estimate``.

    Returns
    -------
    list of Estimate
        One per coefficient, in ``model`` order.
    """
    return [estimate(record, coef, regs, **options) for coef, regs in model.items()]


def predict(est: Estimate, record: FlightRecord) -> np.ndarray:
    """The coefficient time history an equation-error estimate predicts for another record.

    The regressors are formed from ``record`` with the reference values of the fit, so
    the prediction is the fitted absolute model, not refitted to the new record's mean;
    a fit with consistent smoothing passes them through the same filter as the
    coefficient it is compared with.

    Parameters
    ----------
    est : Estimate
        An estimate of ``estimate`` (one coefficient).
    record : FlightRecord
        The flight to predict, SI channels.

    Returns
    -------
    numpy.ndarray
        Predicted coefficient, shape (N,), dimensionless.
    """
    coefficient = est.fit["coefficient"]
    terms = [parse_term(t) for t in est.fit["regressors"]]
    x = regressor_matrix(record, terms, est.fit["reference_values"])
    if est.fit.get("consistent_smoothing") and differentiated(record, coefficient):
        x = smooth_columns(x, terms, record.dt)
    values = [est[derivative_name(coefficient, t)] for t in terms]
    y = x @ np.asarray(values, dtype=float) if terms else np.zeros(len(record))
    if est.fit.get("bias", True):
        y = y + est[bias_name(coefficient)]
    return y


def _letter(coefficient: str) -> str:
    try:
        return COEF_LETTER[coefficient]
    except KeyError:
        raise ValueError(
            f"unknown coefficient {coefficient!r}; expected one of {', '.join(COEF_LETTER)}"
        ) from None


def _term_unit(record: FlightRecord, term: Term) -> str:
    if term.is_linear:
        channel = term.factors[0][0]
        try:
            return record.unit(channel)
        except KeyError:
            return "-"
    return "(product)"


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(RegressionOptions):
    """Options of ``--method ee``."""

    bias: bool = option(True, "estimate a constant term C<coef>_0 per coefficient")
    reference: str = option("mean", "regressors as perturbations from the record's 'mean', "
                                    "its 'initial' value, or 'none'")
    colored: bool = option(True, "standard errors corrected for colored residuals "
                                 "(Morelli & Klein 2016 eq. 5.71)")
    consistent_smoothing: bool = option(
        True, "regressors of a differentiated moment coefficient through the same "
              "smoothing filter")
    a_priori: dict[str, float] | None = option(
        None, "derivatives held at these values (default: the record's a priori table)")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """Equation error for every coefficient of ``model``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : str, optional
        A preset or an explicit structure 'Cn=beta+rhat; ...'. Default 'lateral'.
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        One estimate; the coefficients' fits under ``fit['coefficients']``, the held a
        priori values under ``fit['a_priori']``.
    """
    options = options or Options()
    structure = model_structure.regression(model, options.coefficients)
    held = a_priori.from_record(record) if options.a_priori is None else options.a_priori
    est = merge(ID, [estimate(record, c, t, bias=options.bias, reference=options.reference,
                              colored=options.colored,
                              consistent_smoothing=options.consistent_smoothing,
                              a_priori=held)
                     for c, t in structure.items()])
    used = {n: v for part in est.fit["coefficients"].values() for n, v in part["fixed"].items()}
    est.fit["a_priori"] = a_priori.describe(record, used)
    return est


METHOD = Method(
    id=ID, name="equation error",
    summary="ordinary least squares of each measured force and moment coefficient on its "
            "explanatory variables",
    reference="Morelli & Klein, Aircraft System Identification: Theory and Practice, "
              "2nd ed., 2016, ch. 5",
    options=Options, models=(*model_structure.REGRESSION, "structure"),
    default_model="lateral", channels=model_structure.regression_channels, run=run,
    contract_model="lateral",
)
