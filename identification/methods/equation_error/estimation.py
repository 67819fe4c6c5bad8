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

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flightid.identification.data.coefficients import channel_values, differentiated
from flightid.identification.estimate import Estimate, merge
from flightid.identification.methods.equation_error.least_squares import least_squares
from flightid.identification.methods.equation_error.terms import (
    FACTOR_CHANNEL,
    Term,
    _letter,
    bias_name,
    derivative_name,
    parse_term,
    reference_values,
    regressor_matrix,
    smooth_columns,
)
from flightid.identification.methods.protocol import Method, RegressionOptions, option
from flightid.identification.models import a_priori
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

ID = "ee"
COLLINEAR_R = 0.99  # pairwise |correlation| above which two regressors are inseparable
# VIF above which a regressor is (nearly) a linear combination of the others; the same
# threshold as the pairwise one: R_j^2 > 0.99^2
VIF_LIMIT = 1.0 / (1.0 - COLLINEAR_R**2)
# A control that moves less than this (peak to peak, SI unit) carries no excitation: below
# the resolution of control-position sensors (about 0.1 deg = 1.7e-3 rad) and far below
# any test input; the same limit as identification/engine/identifiability.py MIN_INPUT_RANGE.
MIN_CONTROL_RANGE = {"de": 1e-3, "da": 1e-3, "dr": 1e-3, "df": 1e-3, "throttle": 1e-3}
CONTROL_CHANNELS = tuple(MIN_CONTROL_RANGE)


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


def _held_terms(coefficient: str, a_priori: Mapping[str, float]) -> dict[str, float]:
    """{regressor channel: value} of the a priori derivatives of ``coefficient``."""
    letter = _letter(coefficient)
    out = {}
    for name, value in a_priori.items():
        coef, _, variable = name.partition("_")
        if coef == f"C{letter}" and variable:
            out[FACTOR_CHANNEL.get(variable, variable)] = value
    return out


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
