"""Frequency-domain output error (``--method fdoe``): maximum likelihood of a linear
model's transfer functions against the outputs' Fourier transforms (Morelli & Klein
2016 ch. 7, example 7.1)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.identification.estimate import Estimate
from flightid.identification.frequency import state_space_fit as frequency_domain
from flightid.identification.methods.protocol import HeldOptions, Method, option
from flightid.identification.models import a_priori
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

ID = "fdoe"
# Morelli & Klein example 7.1 (SIDPAC sidpac_text_examples): 0.1-1.5 Hz spaced 0.02 Hz
DEFAULT_BAND_HZ = (0.1, 1.5, 0.02)


@dataclass(frozen=True)
class Options(HeldOptions):
    """Options of ``--method fdoe``."""

    estimate: list[str] | None = option(
        None, "parameters to estimate (default: all derivatives not held)")
    start: dict[str, float] | None = option(None, "start values")
    frequencies: list[float] | None = option(
        None, "analysis frequencies, Hz (default 0.1-1.5 Hz spaced 0.02 Hz)")
    noise: str = option("full", "residual spectral density: 'full' or 'diagonal'")
    end_terms: bool = option(True, "model the transform's end effects (no periodicity "
                                   "assumed)")
    max_relaxations: int = option(20, "limit of alternating parameter / noise updates")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """Frequency-domain output error with a linear-model preset, a priori parameters held.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : str, optional
        A linear-model preset ('lateral' default, 'short_period', 'longitudinal').
    options : Options or None, optional
        Method options; None takes the defaults (band 0.1-1.5 Hz spaced 0.02 Hz).

    Returns
    -------
    Estimate
        The estimate; the held a priori values under ``fit['a_priori']``.
    """
    options = options or Options()
    linear, free, held = a_priori.linear_model(
        model_structure.linear(model), record, options.derivatives, options.a_priori,
        "frequency-domain output error")
    names = options.estimate if options.estimate is not None else [
        p for p in free if not p.startswith("bias_")]
    lo, hi, step = DEFAULT_BAND_HZ
    freqs = np.arange(lo, hi + 1e-9, step) if options.frequencies is None else np.asarray(
        options.frequencies, float)
    est = frequency_domain.output_error(
        record, linear, estimate=names, frequencies=freqs, start=options.start,
        end_terms=options.end_terms, noise=options.noise,
        max_relaxations=options.max_relaxations)
    est.fit["a_priori"] = a_priori.describe(record, held)
    return est


METHOD = Method(
    id=ID, name="frequency-domain output error",
    summary="maximum likelihood of a linear model's outputs against their Fourier "
            "transforms, residual spectral density estimated",
    reference="Morelli & Klein, Aircraft System Identification: Theory and Practice, "
              "2nd ed., 2016, ch. 7",
    options=Options, models=model_structure.LINEAR, default_model="lateral",
    channels=model_structure.linear_channels, run=run, contract_model="lateral",
)
