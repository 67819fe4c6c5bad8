"""Regressor terms of equation error: parsing, parameter names and the regressor matrix.

A term is a channel ("beta", "phat", "de"), a derivative variable ("p" means phat), or a
product or power of them ("alpha^2", "alpha*de"), taken as a perturbation from a
reference value (``reference_values``); ``derivative_name`` and ``bias_name`` name the
parameters of a coefficient model (Morelli & Klein 2016, ch. 5).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flightid.identification.data.coefficients import HINGE, channel_values, smoothed
from flightid.record import FlightRecord

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
REFERENCES = ("mean", "initial", "none")
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


def _letter(coefficient: str) -> str:
    try:
        return COEF_LETTER[coefficient]
    except KeyError:
        raise ValueError(
            f"unknown coefficient {coefficient!r}; expected one of {', '.join(COEF_LETTER)}"
        ) from None
