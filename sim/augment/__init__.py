"""Augmented aircraft: airframe and actuator effects written into a copy of a JSBSim model."""

from flightid.sim.augment.writer import AugmentError, augment, cache_folder
from flightid.sim.effects.airframe import (
    ACTUATOR_EFFECTS,
    AIRFRAME_EFFECTS,
    ActuatorBias,
    ActuatorLag,
    AugmentEffect,
    Backlash,
    CgOffset,
    ControlEffectiveness,
    Deadband,
    DerivativeDelta,
    InertiaScale,
    MassScale,
    RateLimit,
    ThrustMoment,
)

__all__ = ["ACTUATOR_EFFECTS", "AIRFRAME_EFFECTS", "ActuatorBias", "ActuatorLag",
           "AugmentEffect", "AugmentError", "Backlash", "CgOffset", "ControlEffectiveness",
           "Deadband", "DerivativeDelta", "InertiaScale", "MassScale", "RateLimit",
           "ThrustMoment", "augment", "cache_folder"]
