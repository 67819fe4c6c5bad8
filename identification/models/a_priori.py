"""A priori values: parameters held fixed at values from a stated source.

A short maneuver cannot separate some derivatives (CL_q from CL_alpha, Cm_alphadot from
Cm_q: Morelli & Klein 2016 sec. 6.3); a flight-test engineer holds them at a priori
values from wind-tunnel data, a handbook method or an earlier flight, and says so. A
record carries them in ``meta.extra['a_priori']`` as {name: {"value", "std", "source"}}
(a flight card's ``[a_priori]`` table puts them there); the identification methods that
fit a linear model hold every a priori parameter of the model at its value. They never
come from the truth being scored.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from flightid.identification.models import linear as lm
from flightid.record import FlightRecord

META_KEY = "a_priori"


def from_record(record: FlightRecord) -> dict[str, float]:
    """The record's a priori table as {parameter: value}.

    Parameters
    ----------
    record : FlightRecord
        The flight; its table is ``meta.extra['a_priori']``.

    Returns
    -------
    dict of str to float
        {parameter: value}, in the parameter's units (nondimensional derivatives: 1/rad or
        1); empty when the record has no table.
    """
    table = record.meta.extra.get(META_KEY) or {}
    return {name: float(entry["value"] if isinstance(entry, Mapping) else entry)
            for name, entry in table.items()}


def sources(record: FlightRecord) -> dict[str, str]:
    """The record's a priori table as {parameter: source}.

    Parameters
    ----------
    record : FlightRecord
        The flight; its table is ``meta.extra['a_priori']``.

    Returns
    -------
    dict of str to str
        {parameter: source} ("" where an entry names none); entries given as a bare value
        are left out.
    """
    table = record.meta.extra.get(META_KEY) or {}
    return {name: str(entry.get("source", "")) for name, entry in table.items()
            if isinstance(entry, Mapping)}


def linear_model(preset: str, record: FlightRecord, derivatives: Sequence[str] | None,
                 a_priori: Mapping[str, float] | None, method: str
                 ) -> tuple[lm.LinearModel, list[str], dict[str, float]]:
    """The preset at the record's condition with its a priori parameters held.

    The model has the preset's ``derivatives`` plus every a priori parameter the preset
    has, held at its value (start value of the model).

    Parameters
    ----------
    preset : str
        Linear-model preset: 'lateral', 'short_period' or 'longitudinal'.
    record : FlightRecord
        The flight, SI channels; gives the reference condition.
    derivatives : sequence of str or None
        Derivatives to estimate; None takes the preset's default set with its rate
        derivatives (``models.linear.RATE_DERIVATIVES``).
    a_priori : mapping of str to float or None
        {parameter: value} to hold; None takes the record's table (``from_record``).
    method : str
        Name of the identification method asking, used in error messages.

    Returns
    -------
    model : LinearModel
        The model, held parameters at their values.
    free : list of str
        Parameters to estimate (model parameters not held, biases included).
    held : dict of str to float
        {parameter: value} held fixed.

    Raises
    ------
    ValueError
        An a priori value is not a finite number, or ``preset`` is not a preset.
    """
    held_all = from_record(record) if a_priori is None else dict(a_priori)
    for name, value in held_all.items():
        if isinstance(value, bool) or not isinstance(value, int | float) \
                or not math.isfinite(value):
            where = "the record's a priori table" if a_priori is None else "option a_priori"
            raise ValueError(f"{where}: {name} = {value!r} is not a finite number; give "
                             "the value it is held at")
    full = preset_derivatives(preset)
    held = {n: float(v) for n, v in held_all.items() if n in full}
    if derivatives is None:  # the preset's, with its rate derivatives (RATE_DERIVATIVES)
        derivatives = _default_derivatives(preset)
    base = lm.preset_for_record(preset, record, derivatives, method)
    names = [p for p in base.parameters if p not in lm_biases(base)]
    names += [n for n in held if n not in names]
    model = lm.preset_for_record(preset, record, [n for n in full if n in names], method)
    model = model.with_start(**held) if held else model
    free = [p for p in model.parameters if p not in held]
    return model, free, held


def lm_biases(model: lm.LinearModel) -> list[str]:
    """The bias parameters of a linear model (``bias_<equation>``).

    Parameters
    ----------
    model : LinearModel
        The model.

    Returns
    -------
    list of str
        Its parameter names starting with ``bias_``, in model order.
    """
    return [p for p in model.parameters if p.startswith("bias_")]


def _default_derivatives(preset: str) -> tuple[str, ...] | None:
    """The derivatives a method estimates by default: the preset's default set and the
    rate derivatives it leaves out (``models.linear.RATE_DERIVATIVES``), in the preset's
    order; None for a name that is not a preset (the error comes from the builder)."""
    defaults = {"lateral": lm.LATERAL_EXAMPLE_6_1, "short_period": lm.SHORT_PERIOD_DEFAULT,
                "longitudinal": lm.LONGITUDINAL_DEFAULT}.get(preset)
    if defaults is None:
        return None
    wanted = {*defaults, *lm.RATE_DERIVATIVES.get(preset, ())}
    return tuple(n for n in preset_derivatives(preset) if n in wanted)


def preset_derivatives(preset: str) -> tuple[str, ...]:
    """Every derivative a linear-model preset can take.

    Parameters
    ----------
    preset : str
        Model name: 'lateral', 'short_period' or 'longitudinal'.

    Returns
    -------
    tuple of str
        The preset's derivative names; () for another model.
    """
    return {"lateral": lm.LATERAL_DERIVATIVES, "short_period": lm.SHORT_PERIOD_DERIVATIVES,
            "longitudinal": lm.LONGITUDINAL_DERIVATIVES}.get(preset, ())


def describe(record: FlightRecord, held: Mapping[str, float]) -> dict[str, Any]:
    """{parameter: {"value", "source"}} of what a fit held, for ``Estimate.fit``.

    Parameters
    ----------
    record : FlightRecord
        The flight whose a priori table names the sources.
    held : mapping of str to float
        {parameter: value} the fit held fixed.

    Returns
    -------
    dict of str to dict
        {parameter: {"value": float, "source": str}}; the source is "given" for a value not
        in the record's table.
    """
    src = sources(record)
    return {n: {"value": float(v), "source": src.get(n, "given")} for n, v in held.items()}
