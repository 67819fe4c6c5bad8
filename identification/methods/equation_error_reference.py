"""Equation error on the record and model an output-error fit uses: the fit's start
values and the reference of its model-structure check.

As in Morelli & Klein (2016) example 6.1, one least-squares fit per coefficient (CY, Cl,
Cn, CL, CD, Cm) on the variables the linear model gives it. The start values take the
plain regressions; the structure check (``engine.structure_bias``) takes them as
``--method ee`` runs them (regressors smoothed with a differentiated moment coefficient,
a priori values held).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from flightid.derivatives import is_derivative, split
from flightid.identification.data.coefficients import THRUST_COEFFICIENTS
from flightid.identification.engine.structure_bias import widen_for_structure
from flightid.identification.estimate import Estimate
from flightid.identification.methods import equation_error
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

_EE_TERMS = {"alpha": "alpha", "beta": "beta", "p": "phat", "q": "qhat", "r": "rhat",
             "de": "de", "da": "da", "dr": "dr"}


def start_from_equation_error(record: FlightRecord, model: LinearModel) -> dict[str, float]:
    """Start values for ``model``'s derivatives from equation error on the same record.

    As in Morelli & Klein (2016) example 6.1: one least-squares fit per coefficient
    (CY, Cl, Cn, CL, CD, Cm) on the variables the model gives it. Derivatives the
    regression cannot estimate, or whose coefficient the record cannot give (CL, CD without
    a thrust channel), are left out, so they keep the model's start values.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : LinearModel
        The linear model whose derivatives are wanted.

    Returns
    -------
    dict of str to float
        {derivative: value}, per rad (dimensionless), for the derivatives estimated.
    """
    return {name: value for name, (value, _) in equation_error_fits(record, model).items()}


def equation_error_fits(record: FlightRecord, model: LinearModel,
                        consistent_smoothing: bool = False,
                        held: Mapping[str, float] | None = None,
                        ) -> dict[str, tuple[float, float]]:
    """Equation error's value and standard error of each of ``model``'s derivatives it can
    estimate from ``record``.

    The start values (``start_from_equation_error``) and, with ``consistent_smoothing``
    and the ``held`` (a priori) values as ``--method ee`` takes them, the structure check's
    reference.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : LinearModel
        The linear model whose derivatives are wanted.
    consistent_smoothing : bool, optional
        Regressors through the smoothing filter of a differentiated moment coefficient
        (``equation_error.estimate``). Default False.
    held : mapping of str to float or None, optional
        {derivative: value} held a priori (left out of the result).

    Returns
    -------
    dict of str to tuple of float
        {derivative: (value, standard error corrected for colored residuals)}, per rad.
    """
    held = dict(held or {})
    groups: dict[str, list[str]] = {}
    for name in model.parameters:
        if is_derivative(name) and name not in held:
            coef, var = split(name)
            if var in _EE_TERMS:
                groups.setdefault(f"C{coef}", []).append(var)
    out: dict[str, tuple[float, float]] = {}
    for coefficient, variables in groups.items():
        if (coefficient in THRUST_COEFFICIENTS and coefficient not in record
                and "thrust" not in record):
            continue  # no thrust channel: the x force cannot be made aerodynamic
        fixed = {n: v for n, v in held.items() if n.startswith(f"{coefficient}_")}
        fit = equation_error.estimate(record, coefficient, [_EE_TERMS[v] for v in variables],
                                      consistent_smoothing=consistent_smoothing,
                                      a_priori=fixed or None)
        for var in variables:
            name = f"{coefficient}_{var}"
            if name in fit.names and name not in fit.unidentifiable:
                out[name] = (fit[name], fit.std_of(name))
    return out


def check_structure(est: Estimate, record: FlightRecord, model: LinearModel,
                     free: Sequence[str], held: Mapping[str, float]) -> None:
    """Widen the bounds of the free derivatives on which equation error disagrees.

    Equation error runs as ``--method ee`` runs it; the bounds of ``est`` are widened in
    place (``engine.structure_bias``). Nothing is done when it cannot run (no
    accelerometers or coefficients).

    Parameters
    ----------
    est : Estimate
        The output-error estimate, changed in place.
    record : FlightRecord
        The flight it was fitted to, SI channels.
    model : LinearModel
        The fitted linear model.
    free : sequence of str
        The estimated parameters; only these are checked.
    held : mapping of str to float
        {parameter: value} held a priori.
    """
    try:
        fits = equation_error_fits(record, model, consistent_smoothing=True, held=held)
    except (KeyError, ValueError):  # no accelerometers or coefficients: no reference
        return
    widen_for_structure(est, {n: f for n, f in fits.items() if n in free})
