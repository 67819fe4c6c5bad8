"""``--method fem``: the filter-error method, maximum likelihood with a steady-state
Kalman filter inside.

``estimation`` (the relaxation between the Gauss-Newton passes and the noise step, the
result, the method's options and protocol entry), ``kalman_filter`` (the steady-state
filter, its likelihood, one Gauss-Newton pass, the noise step and the robust bounds),
``flight_condition`` (the derivatives corrected for the measured dynamic pressure and
airspeed leaving the reference condition). The package exports
the method's API.
"""

from flightid.identification.methods.filter_error.estimation import (
    ID,
    METHOD,
    Options,
    estimate,
    run,
)

__all__ = ["ID", "METHOD", "Options", "estimate", "run"]
