"""``identify(record, method, model, **options)``: the one door to every method.

Resolves the method (``methods.registry``), the model (``model_structure``: presets,
``lat``/``lon``; "auto" or None: the axis the record excites, ``excited_model``), and the
options (the method's dataclass, unknown keys refused); cuts a
simulated record to the maneuvers on the model's inputs (``windows``); checks that the
record has the channels the method needs; and returns the method's one Estimate with
the window in ``fit['window']``. Channels whose magnitudes cannot be in their SI unit
(``unit_sanity``: angles in degrees, rates in deg/s, speeds in knots) are refused first.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from flightid.channels import CONTROL_SURFACES, LATERAL_INPUTS, LONGITUDINAL_INPUTS
from flightid.identification import nuisance
from flightid.identification.data import time_base, windows
from flightid.identification.data.axes import excited_axes
from flightid.identification.data.unit_sanity import check_units
from flightid.identification.engine import convergence
from flightid.identification.engine import identifiability as ident
from flightid.identification.estimate import Estimate
from flightid.identification.methods import registry
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

WINDOWS = ("auto", "none")
CONTROLS = CONTROL_SURFACES
# the surfaces whose maneuvers a model is fitted to
_MODEL_INPUTS = {"lateral": LATERAL_INPUTS, "short_period": LONGITUDINAL_INPUTS,
                 "longitudinal": (*LONGITUDINAL_INPUTS, "throttle")}


def model_inputs(model: str) -> tuple[str, ...]:
    """The control inputs of a model preset, or of a structure's variables.

    Parameters
    ----------
    model : str
        A model preset name or a structure (``"CZ = alpha + de"``).

    Returns
    -------
    tuple of str
        The controls (de, da, dr, throttle) the model takes; () for models of all axes
        (6dof, all).
    """
    name = model_structure.canonical(model)
    if name in _MODEL_INPUTS:
        return _MODEL_INPUTS[name]
    if "=" in name:
        variables = {v for terms in model_structure.regression(name).values() for v in terms}
        return tuple(s for s in ("de", "da", "dr", "throttle") if s in variables)
    return ()


def excited_model(record: FlightRecord, method: str = "oe") -> str:
    """The model preset for the axis ``record`` excites.

    ``short_period`` when the record excites the longitudinal axis only
    (``data.axes.excited_axes``; an unlisted record's elevator must also pass
    ``identifiability.input_excitation``) and the method takes that preset; otherwise the
    method's default model (lateral for the linear methods, 6dof for the nonlinear one).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    method : str, optional
        The registered method name. Default "oe".

    Returns
    -------
    str
        The model preset name.
    """
    spec = registry.get(method)
    elevator_only = excited_axes([record]) == ["longitudinal"] and (
        bool(windows.maneuvers(record)) or not ident.input_excitation(record, ["de"]))
    if elevator_only and "short_period" in spec.models:
        return "short_period"
    return spec.default_model


def identify(record: FlightRecord, method: str = "oe", model: str | None = "auto", *,
             window: str | Sequence[float] = "auto", strict: bool = False,
             **options: Any) -> Estimate:
    """Estimate a model's derivatives from a record by one identification method.

    Parameters
    ----------
    record : FlightRecord
        The flight data (SI units, angles in rad).
    method : str
        An id of ``flightid methods`` (default ``oe``, output error).
    model : str or None
        A preset, a structure, or 'auto'/None (default): ``excited_model``, the
        short-period model for an elevator-only record, the method's default otherwise
        (``fit['model']`` says which).
    window : str or sequence of float
        'auto' (default) fits a record that lists its maneuvers on the window of the
        maneuvers on the model's inputs; 'none' uses the whole record; (start, end) in s.
    strict : bool
        An iterative fit that does not converge raises ``convergence.NotConvergedError``
        instead of warning (``NotConvergedWarning``).
    **options
        The method's options (see its Options dataclass, ``flightid methods``).

    Returns
    -------
    Estimate
        The derivatives (per rad, rates nondimensional), their standard errors and the fit.

    A linear model's nuisance biases are split into their trim part and the excess
    (``nuisance.bias_budget``, in ``fit['biases']``); an excess beyond what an instrument
    can have is warned about (``ImplausibleBiasWarning``).

    Every method sees a uniformly sampled record: time jitter below 1 % of the step is
    re-gridded (``time_base``, with a ``RegriddedWarning``), gaps are refused.
    """
    spec = registry.get(method)
    model = (excited_model(record, method) if model in (None, "auto")
             else model_structure.canonical(model))
    opts = spec.make_options(options)
    record = time_base.regrid_jitter(record)
    record.uniform_step(f"method {spec.id}", min_samples=10)
    record, span = _windowed(record, model, window)
    missing = [c for c in spec.channels(model) if c not in record]
    if missing:
        raise ValueError(
            f"record lacks channel(s) {', '.join(missing)} needed by method {spec.id} with "
            f"model {model}; it has {', '.join(sorted(record.channels))}")
    inputs = [c for c in (model_inputs(model) or CONTROLS) if c in record]
    check_units(record, None, f"method {spec.id}")  # every channel: one wrong unit is
    # a conversion error that may have touched the others
    quiet = ident.input_excitation(record, inputs)
    if inputs and len(quiet) == len(inputs):
        where = f" in the window {span[0]:g}-{span[1]:g} s" if span else ""
        raise ValueError(
            f"the record cannot determine model {model}: no input is excited{where} "
            f"({'; '.join(quiet.values())}); fly a maneuver on {', '.join(inputs)}")
    estimate = spec.run(record, model, opts)
    (convergence.require if strict else convergence.warn)(estimate, f"method {spec.id}")
    biases = nuisance.bias_budget(estimate, record, model)
    if biases:
        estimate.fit["biases"] = [t.to_json() for t in biases]
        nuisance.warn_implausible(biases, f"method {spec.id}")
    estimate.fit.setdefault("model", model)
    if span is not None:
        estimate.fit["window"] = [float(span[0]), float(span[1])]
    return estimate


def _windowed(record: FlightRecord, model: str, window: str | Sequence[float]
              ) -> tuple[FlightRecord, tuple[float, float] | None]:
    if isinstance(window, str):
        if window not in WINDOWS:
            raise ValueError(f"window must be one of {', '.join(WINDOWS)} or (start, end) "
                             f"in s, got {window!r}")
        if window == "none":
            return record, None
        inputs = model_inputs(model)
        return windows.select(record, inputs) if inputs else (record, None)
    start, end = (float(x) for x in window)
    if not start < end:
        raise ValueError(f"window start {start} s must be before its end {end} s")
    return record.slice(start, end), (start, end)
