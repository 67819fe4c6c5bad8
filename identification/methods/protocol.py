"""The method protocol: what every identification method declares and returns.

Like scikit-learn's estimator protocol: a method is a ``Method`` value with a stable id
(``ee``, ``oe``, ...), its options declared once as a dataclass (field type, default and
a ``help`` text in the field metadata), the model structures it takes, the channels a
record must hold, and ``run(record, model, options) -> Estimate``. The command line
(``--option KEY=VALUE``), the option check and ``flightid methods`` are all derived from
the dataclass; ``tests/contract`` holds every registered method to the protocol.
"""

from __future__ import annotations

import dataclasses
import json
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from flightid.identification.engine import convergence
from flightid.identification.engine import identifiability as ident
from flightid.identification.estimate import Estimate
from flightid.record import FlightRecord


@dataclass(frozen=True)
class Method:
    """One identification method, as the registry, the command line and the contract see it.

    id: stable short name (``--method``); name: what it is ("output error");
    summary: one line; reference: the publication it follows (author, title, year);
    options: the dataclass of its keyword options; models: the model presets it takes
    ("structure" where it also takes 'Cn=beta+phat; ...'); default_model: used when the
    caller gives none; channels(model): the record channels the model needs;
    run(record, model, options): the estimate, with ``method`` equal to ``id``.
    """

    id: str
    name: str
    summary: str
    reference: str
    options: type
    models: tuple[str, ...]
    default_model: str
    channels: Callable[[str], tuple[str, ...]]
    run: Callable[[FlightRecord, str, Any], Estimate]
    # an example model of each structure kind for the contract suite
    contract_model: str = ""

    def option_fields(self) -> list[dataclasses.Field]:
        """The option fields: the method's own and the model's first, the shared tuning
        options (convergence, identifiability thresholds) last."""
        fields = dataclasses.fields(self.options)
        return sorted(fields, key=lambda f: bool(f.metadata.get("tuning", False)))

    def make_options(self, values: Mapping[str, Any] | None = None) -> Any:
        """The options dataclass from keyword values (texts from the command line are
        read as JSON where the field is not a string); unknown keys are refused naming
        the valid ones, wrong types naming the field and its type."""
        values = dict(values or {})
        known = {f.name: f for f in self.option_fields()}
        unknown = sorted(k for k in values if k not in known)
        if unknown:
            raise ValueError(
                f"unknown option(s) {', '.join(unknown)} for method {self.id}; valid: "
                f"{', '.join(known) or 'none'}")
        hints = typing.get_type_hints(self.options)
        converted = {k: convert_option(self.id, k, v, hints[k]) for k, v in values.items()}
        for key, value in converted.items():
            if key.startswith("max_"):  # iteration and relaxation limits
                convergence.check_limit(self.id, key, value)
        return self.options(**converted)

    def describe(self) -> list[dict[str, str]]:
        """One row per option: name, type, default, meaning (for ``flightid methods``)."""
        hints = typing.get_type_hints(self.options)
        rows = []
        for f in self.option_fields():
            default = f.default if f.default is not dataclasses.MISSING else (
                f.default_factory() if f.default_factory is not dataclasses.MISSING else None)
            rows.append({"name": f.name, "type": type_name(hints[f.name]),
                         "default": json.dumps(default, default=str),
                         "help": f.metadata.get("help", "")})
        return rows


def option(default: Any, help: str, tuning: bool = False) -> Any:
    """A dataclass field of an options class: its default and its meaning.

    Parameters
    ----------
    default : Any
        Default value; a list, dict or set is copied for each instance.
    help : str
        What the option means, with its unit.
    tuning : bool, optional
        Marks a convergence or threshold setting (listed after the others). Default False.

    Returns
    -------
    dataclasses.Field
        The field, ``help`` and ``tuning`` in its metadata.
    """
    metadata = {"help": help, "tuning": tuning}
    if isinstance(default, list | dict | set):
        return dataclasses.field(default_factory=lambda: type(default)(default),
                                 metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


def type_name(hint: Any) -> str:
    """A short readable name of a type hint ('float', 'list[str] | None').

    Parameters
    ----------
    hint : Any
        A type or type hint.

    Returns
    -------
    str
        Its name without the ``typing.`` and ``collections.abc.`` prefixes.
    """
    text = str(hint) if not isinstance(hint, type) else hint.__name__
    return text.replace("typing.", "").replace("collections.abc.", "")


def convert_option(method: str, name: str, value: Any, hint: Any) -> Any:
    """``value`` as the type ``hint`` asks; a text is read as JSON unless the hint is str.

    A text that is not JSON is split on commas where the hint allows a list or tuple.

    Parameters
    ----------
    method : str
        Method id, named in the error.
    name : str
        Option name, named in the error.
    value : Any
        The value given (a text from the command line, or a Python value).
    hint : Any
        The option's type hint.

    Returns
    -------
    Any
        The value converted (an int to float where a float is asked, a sequence to the
        list or tuple asked).

    Raises
    ------
    ValueError
        The value does not match the hint; names the method, the option and the type.
    """
    allowed = _flatten(hint)
    if isinstance(value, str) and str not in allowed:
        try:
            value = json.loads(value)
        except json.JSONDecodeError:
            if list in allowed or tuple in allowed:  # 'beta,r' from the command line
                value = [v.strip() for v in value.split(",") if v.strip()]
    for kind in allowed:
        if _matches(value, kind):
            if kind is float and isinstance(value, int) and not isinstance(value, bool):
                return float(value)
            if kind in (tuple, list) and isinstance(value, list | tuple):
                return kind(value)
            return value
    raise ValueError(f"option {name} of method {method}: expected {type_name(hint)}, got "
                     f"{value!r}")


def _flatten(hint: Any) -> list[Any]:
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        return [k for a in typing.get_args(hint) for k in _flatten(a)]
    if hint is Any:
        return [object]
    if hint is None or hint is type(None):
        return [type(None)]
    return [origin or hint]


def _matches(value: Any, kind: Any) -> bool:
    if kind is object:
        return True
    if kind is type(None):
        return value is None
    if kind is bool:
        return isinstance(value, bool)
    if kind is float:
        return isinstance(value, int | float) and not isinstance(value, bool)
    if kind is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if kind in (list, tuple, Sequence):
        return isinstance(value, list | tuple)
    if kind in (dict, Mapping):
        return isinstance(value, dict)
    return isinstance(value, kind) if isinstance(kind, type) else False


@dataclass(frozen=True)
class LinearModelOptions:
    """Options every method that fits a linear-model preset takes (oe, fem, fdoe, fr)."""

    derivatives: list[str] | None = option(
        None, "derivatives of the model structure (default: the preset's)")


@dataclass(frozen=True)
class HeldOptions(LinearModelOptions):
    """A linear-model method that holds the record's a priori derivatives."""

    a_priori: dict[str, float] | None = option(
        None, "parameters held at these values (default: the record's a priori table)")


@dataclass(frozen=True)
class RegressionOptions:
    """Options every per-coefficient regression method takes (ee, swr, fdee)."""

    coefficients: list[str] | None = option(
        None, "fit only these coefficients of the model, e.g. [\"Cl\", \"Cn\"]")


@dataclass(frozen=True)
class OutputErrorOptions:
    """The convergence and identifiability options of the output-error fits (oe, oe6dof)."""

    step_tolerance: float = option(1e-3, "converged when no step exceeds this many std",
                                   tuning=True)
    cost_tolerance: float = option(1e-7, "or when the ML cost N/2 ln det R changes less than "
                                         "this (absolute)", tuning=True)
    check_identifiability: bool = option(True, "report parameters the data cannot determine "
                                               "instead of estimating them", tuning=True)
    min_input_range: float = option(ident.MIN_INPUT_RANGE,
                                    "an input spanning less than this (rad) is not excited",
                                    tuning=True)
    singular_eigenvalue: float = option(ident.SINGULAR_EIGENVALUE,
                                        "relative eigenvalue of M below which it is singular",
                                        tuning=True)

    def tuning(self) -> dict[str, Any]:
        """These options as keywords of the estimate functions."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(OutputErrorOptions)}
