"""Augmented aircraft: airframe and actuator effects (``flightid.sim.effects.airframe``)
written into a copy of a JSBSim model."""

from flightid.sim.augment.writer import (
    AugmentError,
    augment,
    augment_cached,
    cache_folder,
    publish,
)

__all__ = ["AugmentError", "augment", "augment_cached", "cache_folder", "publish"]
