"""The gap across the envelope: records from several conditions, each diagnosed at its
own (``regimes``: where in the envelope the model departs), and a derivative error's trend
over the conditions (``trend``)."""

from flightid.identification.gap.envelope.regimes import (
    Condition,
    EnvelopeResult,
    conditions,
    envelope,
    regime_bins,
    trend_effects,
    write_envelope_aircraft,
)

__all__ = ["Condition", "EnvelopeResult", "conditions", "envelope", "regime_bins",
           "trend_effects", "write_envelope_aircraft"]
