"""Canonical names of nondimensional stability and control derivatives.

A derivative is named ``C<coef>_<var>``: ``CL_alpha``, ``Cm_q``, ``Cn_beta``, ``Cl_da``.

coef: X Y Z (body-axis forces), L D (lift and drag, stability axes),
      l m n (rolling, pitching, yawing moment about the CG, body axes).
var:  alpha beta (per rad), p q r (per unit of the nondimensional rate
      phat = p b/2V, qhat = q cbar/2V, rhat = r b/2V), alphadot (per unit of
      alphadot cbar/2V), de da dr (per rad), dt (per unit throttle), and ``0`` for the
      value of the coefficient at the reference condition.
The conventions match ``flightid.channels`` (control signs) and Morelli & Klein (2016).
"""

from __future__ import annotations

import re

COEFFICIENTS: tuple[str, ...] = ("X", "Y", "Z", "L", "D", "l", "m", "n")
VARIABLES: tuple[str, ...] = (
    "0", "alpha", "beta", "p", "q", "r", "alphadot", "de", "da", "dr", "dt",
)

# which nondimensional rate each rate variable is scaled with (b for p, r; cbar for q)
RATE_LENGTH: dict[str, str] = {"p": "span", "r": "span", "q": "chord", "alphadot": "chord"}

_NAME = re.compile(r"^C([XYZLDlmn])_(0|alpha|beta|p|q|r|alphadot|de|da|dr|dt)$")


def name(coef: str, var: str) -> str:
    """Canonical name of d(C<coef>)/d(var), e.g. name('m', 'alpha') == 'Cm_alpha'.

    Parameters
    ----------
    coef : str
        Coefficient letter, one of ``COEFFICIENTS``.
    var : str
        Variable, one of ``VARIABLES``.

    Returns
    -------
    str
        The derivative name ``C<coef>_<var>``.

    Raises
    ------
    ValueError
        If ``coef`` or ``var`` is unknown.
    """
    if coef not in COEFFICIENTS:
        raise ValueError(f"unknown coefficient {coef!r}; expected one of {COEFFICIENTS}")
    if var not in VARIABLES:
        raise ValueError(f"unknown variable {var!r}; expected one of {VARIABLES}")
    return f"C{coef}_{var}"


def split(derivative: str) -> tuple[str, str]:
    """(coef, var) of a canonical derivative name.

    Parameters
    ----------
    derivative : str
        A canonical derivative name, ``C<coef>_<var>``.

    Returns
    -------
    tuple of str
        (coefficient letter, variable).

    Raises
    ------
    ValueError
        Naming ``derivative`` if it is malformed.
    """
    m = _NAME.match(derivative)
    if not m:
        raise ValueError(
            f"{derivative!r} is not a derivative name: expected C<coef>_<var> with coef in "
            f"{' '.join(COEFFICIENTS)} and var in {' '.join(VARIABLES)}"
        )
    return m.group(1), m.group(2)


def is_derivative(text: str) -> bool:
    """True when ``text`` is a canonical derivative name.

    Parameters
    ----------
    text : str
        Candidate name.

    Returns
    -------
    bool
        Whether ``text`` matches ``C<coef>_<var>``.
    """
    return bool(_NAME.match(text))


# the unit of a derivative by its variable: per rad for angles, per unit of the
# nondimensional rate (so dimensionless) for rates, per unit throttle, 1 for the value
_UNITS = {"alpha": "1/rad", "beta": "1/rad", "de": "1/rad", "da": "1/rad", "dr": "1/rad",
          "p": "1", "q": "1", "r": "1", "alphadot": "1", "dt": "1", "0": "1"}


def unit(derivative: str) -> str:
    """The unit of a canonical derivative.

    Parameters
    ----------
    derivative : str
        Derivative name.

    Returns
    -------
    str
        "1/rad" or "1" (dimensionless); "" for a name that is not canonical (a method's own
        parameter).
    """
    m = _NAME.match(derivative)
    return _UNITS[m.group(2)] if m else ""
