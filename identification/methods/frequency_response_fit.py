"""Frequency-response fit (``--method fr``): conditioned frequency responses of every model
output to every excited input (composite windows, coherence), then a linear state-space
model fitted to them with the CIFER cost (Tischler & Remple, Aircraft and Rotorcraft
System Identification, 2nd ed., 2012, ch. 11).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flightid.identification.estimate import Estimate
from flightid.identification.frequency import state_space_fit as frequency_domain
from flightid.identification.frequency.grids import default_windows
from flightid.identification.frequency.response import frequency_response_arrays
from flightid.identification.frequency.transfer_function import COHERENCE_MIN
from flightid.identification.methods.protocol import LinearModelOptions, Method, option
from flightid.identification.models import linear as lm
from flightid.identification.models import structure as model_structure
from flightid.identification.models.reference_condition import condition_from_record
from flightid.record import FlightRecord

ID = "fr"

# outputs whose responses the CIFER fit uses, per linear model preset
OUTPUTS = {"lateral": ("beta", "p", "r", "phi", "ay"), "short_period": ("alpha", "q", "az"),
              "longitudinal": ("V", "alpha", "q", "theta", "az")}
MAX_PAIR_COST = 100.0  # CIFER guideline per pair (Tischler & Remple sec. 11.5)
TRIM_SECONDS = 2.0  # the record's first seconds at trim define the reference condition


def reference_condition(records: Sequence[FlightRecord], trim_seconds: float = TRIM_SECONDS):
    """Linearisation point of several maneuvers.

    Channel means over the first ``trim_seconds`` of each record (the trim before the
    input), averaged over the records. A maneuver's own mean is not the trim: an open-loop
    roll sweep excites the phugoid and moves the mean dynamic pressure 1 % (all derivatives
    scale with it).

    Parameters
    ----------
    records : sequence of FlightRecord
        The maneuvers, SI channels.
    trim_seconds : float, optional
        Seconds at the start of each record that define the condition, s; <= 0 uses the
        whole records. Default ``TRIM_SECONDS`` (2 s).

    Returns
    -------
    ReferenceCondition
        The condition of the first record with V, qbar, alpha, theta, mass and inertias
        averaged over the records (SI).
    """
    conds = []
    for rec in records:
        t0 = rec.time[0]
        part = rec.slice(t0, t0 + trim_seconds) if trim_seconds > 0 else rec
        conds.append(condition_from_record(part if len(part) >= 2 else rec))
    fields = ("V", "qbar", "alpha", "theta", "mass", "Ixx", "Iyy", "Izz", "Ixz")
    return dataclasses.replace(conds[0], **{
        k: float(np.mean([getattr(c, k) for c in conds])) for k in fields})




@dataclass(frozen=True)
class Options(LinearModelOptions):
    """Options of ``--method fr``."""

    estimate: list[str] | None = option(None, "parameters to estimate (default: all but "
                                              "the biases)")
    start: dict[str, float] | None = option(
        None, "start values (default: frequency-domain output error on the same data)")
    frequencies: list[float] | None = option(None, "analysis frequencies, Hz (default: 60 "
                                                   "log-spaced from the longest window)")
    windows: list[float] | None = option(None, "composite window lengths, s (default: "
                                               "2/3, 1/3 and 1/6 of the record)")
    coherence_min: float = option(COHERENCE_MIN, "points with lower coherence are not fitted")
    max_cost: float | None = option(None, "drop pairs whose CIFER cost exceeds this and "
                                          "refit (guideline 100)")
    whole_record: bool = option(True, "single-input records: responses from the whole "
                                      "record's transform")
    trim_seconds: float = option(0.0, "first seconds of each record that define the "
                                      "reference condition (0: the whole record)")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """The frequency-response fit of one record (see ``fit`` for several).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval.
    model : str, optional
        A linear-model preset ('lateral' default, 'short_period', 'longitudinal').
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        As ``fit``.
    """
    return fit([record], model, options)


def fit(records: Sequence[FlightRecord], model: str = "lateral",
        options: Options | None = None) -> Estimate:
    """``flightid identify --method fr``: conditioned frequency responses of every model
    output to every excited input (composite windows), then the CIFER state-space fit.

    Pairs whose cost exceeds ``max_cost`` (``MAX_PAIR_COST`` = 100 is the guideline of
    Tischler & Remple sec. 11.5; default None keeps all: on the Twin Otter doublets 8 of
    10 pairs exceed it) after a first fit are dropped and the fit repeated.
    A record with one excited input (a single-axis sweep) gets its responses from the
    whole-record transform (``whole_record``, default True; the windows then give
    coherence and random error only). The model is linearised at
    ``reference_condition``: the first ``trim_seconds`` s of each record when given (the
    trim before a simulated sweep), else the records' means. Start values come
    from frequency-domain output error on the same records unless ``start`` is given.

    Parameters
    ----------
    records : sequence of FlightRecord
        The maneuvers, SI channels, each with a uniform sample interval.
    model : str, optional
        A linear-model preset ('lateral' default, 'short_period', 'longitudinal').
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        The CIFER fit; the pairs kept and dropped in ``fit['pairs']`` and
        ``fit['dropped_pairs']``, with the windows (s), the number of responses and the
        reference condition.

    Raises
    ------
    ValueError
        No record, no input of the model varies, or no response has 3 points of enough
        coherence.
    """
    opts = options or Options()
    records = list(records)
    if not records:
        raise ValueError("give at least one record")
    model = model_structure.linear(model)
    derivs = opts.derivatives
    cond = reference_condition(records, float(opts.trim_seconds))
    lin = lm.MODELS[model](cond, **({"derivatives": tuple(derivs)} if derivs else {}))
    lin = lin.with_start(**{p: 0.0 for p in lin.parameters if p.startswith("bias_")})
    windows = opts.windows
    coh_min = float(opts.coherence_min)
    max_cost = opts.max_cost
    whole = bool(opts.whole_record)
    responses = []
    for rec in records:
        rec.uniform_step("frequency-response fit")
        # an input is excited when its spread is at least a tenth of the largest one
        # (sensor noise on a surface held at trim is not an excitation)
        spread = {i: float(np.std(rec[i])) for i in lin.inputs if i in rec}
        top = max(spread.values(), default=0.0)
        excited = [i for i, s in spread.items() if top > 0 and s >= 0.1 * top]
        if not excited:
            raise ValueError(f"no input of model {lin.name} ({', '.join(lin.inputs)}) "
                             "varies in the record")
        duration = rec.time[-1] - rec.time[0]
        wins = tuple(windows) if windows else default_windows(duration, rec.dt, len(excited))
        freqs = opts.frequencies
        if freqs is None:
            freqs = np.geomspace(max(2.0 / max(wins), 0.1), min(2.0, 0.2 / rec.dt), 60)
        for out in OUTPUTS.get(model, lin.outputs):
            if out not in rec:
                continue
            resp = frequency_response_arrays({i: rec[i] for i in excited}, rec[out], rec.dt,
                                             output_name=out, windows=wins,
                                             frequencies=freqs,
                                             whole_record=whole and len(excited) == 1)
            responses.extend(r for r in resp.values() if r.valid(coh_min).sum() >= 3)
    if not responses:
        raise ValueError(f"no frequency response has 3 or more points with coherence >= "
                         f"{coh_min}")
    names = opts.estimate
    start = opts.start
    if start is None:
        # the CIFER cost has local minima far from the answer: start from the
        # frequency-domain output error of the same maneuvers
        first = frequency_domain.output_error(records, lin, estimate=names)
        start = dict(zip(first.names, first.values, strict=True))
    est = frequency_domain.fit_state_space(responses, lin, estimate=names,
                                           coherence_min=coh_min, start=start)
    costs = est.fit["cost_per_pair"]
    dropped = [] if max_cost is None else [k for k, c in costs.items() if c > max_cost]
    if dropped and len(dropped) < len(costs):
        kept = [r for r in responses if f"{r.output}/{r.input}" not in dropped]
        est = frequency_domain.fit_state_space(kept, lin, estimate=names,
                                               coherence_min=coh_min, start=start)
    est.method = ID
    est.fit.update(pairs=list(est.fit["cost_per_pair"]), dropped_pairs=dropped,
                   windows=wins, responses=len(responses), whole_record=whole,
                   condition=cond)
    return est


METHOD = Method(
    id=ID, name="frequency-response fit",
    summary="conditioned frequency responses with coherence, then a state-space model "
            "fitted with the CIFER cost",
    reference="Tischler & Remple, Aircraft and Rotorcraft System Identification: "
              "Engineering Methods with Flight-Test Examples, 2nd ed., 2012, ch. 11",
    options=Options, models=model_structure.LINEAR, default_model="lateral",
    channels=model_structure.linear_channels, run=run, contract_model="lateral",
)
