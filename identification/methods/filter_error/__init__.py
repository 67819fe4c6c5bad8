"""``--method fem``: the filter-error method, maximum likelihood with a steady-state
Kalman filter inside.

``estimation`` (the estimate and its result), ``relaxation`` (the relaxation between
the Gauss-Newton passes and the noise step, the joint noise fit from two starts),
``method`` (the options, the preset entry point and the registry entry),
``kalman_filter`` (the steady-state filter and its likelihood), ``iteration`` (one
Gauss-Newton pass, the noise step and the robust bounds),
``flight_condition`` (the derivatives corrected for the measured dynamic pressure and
airspeed leaving the reference condition). The package exports
the method's API.
"""

from flightid.identification.methods.filter_error.estimation import (
    ID,
    KINEMATIC_STATES,
    estimate,
)
from flightid.identification.methods.filter_error.method import METHOD, Options, run

__all__ = ["ID", "KINEMATIC_STATES", "METHOD", "Options", "estimate", "run"]
