"""The model structures that ``--model`` names: one table for every method.

Linear perturbation models (``lateral``, ``short_period``, ``longitudinal``; state
space, used by output error, filter error, frequency-domain output error and the
frequency-response fit) are the presets of ``linear_models``; a regression method
(equation error, stepwise, frequency-domain equation error) takes the same names as
sets of coefficients with their explanatory variables, or an explicit structure
``"Cn=beta+phat+rhat+da+dr; CY=beta+rhat+dr"``. ``lat`` and ``lon`` are short for
``lateral`` and ``longitudinal``.
"""

from __future__ import annotations

from collections.abc import Sequence

from flightid.channels import LATERAL_INPUTS
from flightid.identification.models import linear as lm
from flightid.identification.models.reference_condition import (
    CONDITION_CHANNELS,
)

ALIASES = {"lat": "lateral", "lon": "longitudinal"}

LATERAL_VARIABLES = ("beta", "phat", "rhat", "da", "dr")
LONGITUDINAL_VARIABLES = ("alpha", "qhat", "de")
# a global model's variables (Morelli 1995): every coefficient may depend on all of them,
# e.g. the c172p's drag on |beta|, its roll moment due to yaw rate on alpha; and the
# thrust coefficient Tc = T / (qbar S), on which the derivatives of surfaces in the
# propeller slipstream depend (the c172p's Cm_de and Cn_dr take the slipstream's
# dynamic pressure)
GLOBAL_VARIABLES = ("alpha", "beta", "phat", "qhat", "rhat", "de", "da", "dr", "Tc")
# the regression form of each preset: {coefficient: explanatory variables}
REGRESSION: dict[str, dict[str, tuple[str, ...]]] = {
    "lateral": {"CY": LATERAL_VARIABLES, "Cl": LATERAL_VARIABLES, "Cn": LATERAL_VARIABLES},
    # lift and drag in stability axes: on the Navion card (10 seeds, light turbulence)
    # 91 % of the estimates lie within 3 sigma of the truth, with CX and CZ 82 % (the
    # body-axis X force mixes the small drag derivatives with lift and thrust changes)
    "longitudinal": {"CL": LONGITUDINAL_VARIABLES, "CD": LONGITUDINAL_VARIABLES,
                     "Cm": LONGITUDINAL_VARIABLES},
    "short_period": {"CL": LONGITUDINAL_VARIABLES, "Cm": LONGITUDINAL_VARIABLES},
}
REGRESSION["all"] = {**REGRESSION["longitudinal"], **REGRESSION["lateral"]}
REGRESSION["global"] = {c: GLOBAL_VARIABLES for c in REGRESSION["all"]}
LINEAR = tuple(lm.MODELS)

# channels a regression variable is computed from
_VARIABLE_CHANNELS = {"phat": ("p", "V"), "qhat": ("q", "V"), "rhat": ("r", "V"),
                      "alphadot_hat": ("alpha", "V"), "Tc": ("thrust", "qbar")}
# channels each coefficient is computed from (rigid-body equations, body axes)
_COEFFICIENT_CHANNELS = {
    "CX": ("ax",), "CY": ("ay",), "CZ": ("az",), "CL": ("ax", "az", "alpha"),
    "CD": ("ax", "az", "alpha"), "Cl": ("p", "q", "r"), "Cm": ("p", "q", "r"),
    "Cn": ("p", "q", "r"),
}


def canonical(model: str) -> str:
    """The model name with ``lat``/``lon`` spelled out and surrounding blanks removed.

    Parameters
    ----------
    model : str
        A ``--model`` value.

    Returns
    -------
    str
        The canonical name (or the stripped text, when it is no alias).
    """
    text = model.strip()
    return ALIASES.get(text, text)


def regression(model: str, coefficients: Sequence[str] | None = None) -> dict[str, list[str]]:
    """{coefficient: variables} of a preset or of an explicit structure.

    Parameters
    ----------
    model : str
        A preset of ``REGRESSION`` (or an alias) or 'Cn=beta+phat; CY=beta+rhat'.
    coefficients : sequence of str or None, optional
        Coefficients to keep; None or empty keeps all.

    Returns
    -------
    dict of str to list of str
        {coefficient: explanatory variables}.

    Raises
    ------
    ValueError
        An unknown model, a malformed structure part, or a coefficient not in the model.
    """
    text = canonical(model)
    if text in REGRESSION:
        structure = {c: list(t) for c, t in REGRESSION[text].items()}
    elif "=" in text:
        structure = {}
        for part in filter(None, (p.strip() for p in text.split(";"))):
            coef, sep, terms = part.partition("=")
            if not sep or not terms.strip():
                raise ValueError(f"model part {part!r}: expected 'Coef=term+term'")
            structure[coef.strip()] = [t.strip() for t in terms.split("+") if t.strip()]
    else:
        raise ValueError(f"unknown model {model!r}: use a preset ({', '.join(REGRESSION)}) "
                         "or 'Coef=term+term; Coef=...'")
    if not coefficients:
        return structure
    missing = [c for c in coefficients if c not in structure]
    if missing:
        raise ValueError(f"coefficients {missing} are not in the model ({', '.join(structure)})")
    return {c: structure[c] for c in coefficients}


def regression_channels(model: str) -> tuple[str, ...]:
    """The record channels a regression model needs (variables and coefficients).

    Parameters
    ----------
    model : str
        A preset or explicit structure, as for ``regression``.

    Returns
    -------
    tuple of str
        Channel names, each once, in order of first use.
    """
    out: list[str] = []
    for coef, terms in regression(model).items():
        out.extend(_COEFFICIENT_CHANNELS.get(coef, (coef,)))
        for term in terms:
            for factor in term.split("^")[0].split("*"):
                out.extend(_VARIABLE_CHANNELS.get(factor, (factor,)))
    return tuple(dict.fromkeys(out))


def linear(model: str) -> str:
    """The linear-model preset named by ``model``.

    Parameters
    ----------
    model : str
        A preset name or alias (lat, lon).

    Returns
    -------
    str
        The preset: 'lateral', 'short_period' or 'longitudinal'.

    Raises
    ------
    ValueError
        ``model`` is not a linear-model preset; the message names the presets.
    """
    text = canonical(model)
    if text not in lm.MODELS:
        raise ValueError(f"model {model!r} is not a linear-model preset; use one of "
                         f"{', '.join(lm.MODELS)} (or lat, lon)")
    return text


def linear_channels(model: str) -> tuple[str, ...]:
    """The record channels a linear-model preset needs.

    Its inputs and outputs, and the channels its reference condition is averaged from
    (``condition_from_record``).

    Parameters
    ----------
    model : str
        A preset name or alias.

    Returns
    -------
    tuple of str
        Channel names, each once.
    """
    preset = _PRESET_SIGNALS[linear(model)]
    return tuple(dict.fromkeys((*preset[0], *preset[1], *CONDITION_CHANNELS)))


# outputs output error fits without: attitudes a hobby recorder does not measure (the
# states stay, integrated from the rates; the reference pitch attitude then comes from
# the specific force, ``level_pitch_attitude``)
OPTIONAL_OUTPUTS = ("phi", "theta")


def output_error_channels(model: str) -> tuple[str, ...]:
    """``linear_channels`` without the attitudes (``OPTIONAL_OUTPUTS``), which output error
    leaves out of the outputs when the record has none.

    Parameters
    ----------
    model : str
        A preset name or alias.

    Returns
    -------
    tuple of str
        Channel names, each once.
    """
    return tuple(c for c in linear_channels(model) if c not in OPTIONAL_OUTPUTS)


# inputs and outputs of each linear preset (checked against the models in the tests)
_PRESET_SIGNALS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "lateral": (LATERAL_INPUTS, ("beta", "p", "r", "phi", "ay")),
    "short_period": (("de",), ("alpha", "q", "az")),
    "longitudinal": (("de",), ("V", "alpha", "q", "theta", "az")),
}
