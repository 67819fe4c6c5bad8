"""Injectable effects: one catalogue, and the implementations it declares.

``catalogue`` declares every effect once (``CATALOGUE``: name, where it acts, parameters
with units, default magnitudes and ranges, the implementation); the other modules hold
the implementations by where they act: ``sensor`` (per-channel errors of the sensor
chain), ``mounting`` (lever arm, vanes), ``vibration`` (engine vibration on the IMU),
``disturbance`` (wind, gust, turbulence), ``link`` and ``clock`` (the bridge's link faults
and recorder clocks, referenced by a parameter mapping). ``base`` holds the common form.

The names below are re-exported so that ``from flightid.sim.effects import Bias`` keeps
working; ``docs/effects.md`` lists the catalogue (``flightid effects`` prints it).
"""

from flightid.sim.effects.base import Effect, ExternalImplementation, NamedEffect
from flightid.sim.effects.catalogue import (
    CATALOGUE,
    EFFECTS,
    SECTIONS,
    ActsOn,
    Catalogue,
    Entry,
    Option,
    Parameter,
    effect_from_dict,
)
from flightid.sim.effects.listing import listing
from flightid.sim.effects.sensor import (
    Bias,
    Delay,
    Drift,
    Lag,
    LowPass,
    Quantization,
    RandomWalk,
    Sample,
    Saturation,
    ScaleFactor,
    SecondOrder,
    WhiteNoise,
    antialias,
    lti_filter,
    uniform_dt,
)

__all__ = [
    "CATALOGUE", "EFFECTS", "SECTIONS", "ActsOn", "Bias", "Catalogue", "Delay", "Drift",
    "Effect", "Entry", "ExternalImplementation", "Lag", "LowPass", "NamedEffect", "Option",
    "Parameter", "Quantization", "RandomWalk", "Sample", "Saturation", "ScaleFactor",
    "SecondOrder", "WhiteNoise", "antialias", "effect_from_dict", "listing", "lti_filter",
    "uniform_dt",
]
