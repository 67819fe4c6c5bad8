"""The trimmed initial state written into JSBSim: every JSBSim model re-initialised at the
trim (turbulence filters, actuators), the steady wind added so that the airspeed stays
trimmed, and a re-evaluation at t = 0 without integrating."""

from __future__ import annotations

import math

import numpy as np

from flightid.sim.flight.atmosphere import Atmosphere, set_atmosphere
from flightid.sim.flight.properties import ned_to_body
from flightid.sim.jsbsim.model import Model, quiet, set_integrators
from flightid.sim.jsbsim.trim import _IC_STATE as _IC_ORDER
from flightid.sim.jsbsim.trim import Trim
from flightid.units import FT


def evaluate(model: Model) -> None:
    """Re-run every JSBSim model at the current time without integrating.

    Parameters
    ----------
    model : Model
        The loaded JSBSim model.
    """
    fdm = model.fdm
    fdm.suspend_integration()
    fdm.run()
    fdm.resume_integration()


def restart(model: Model, trim: Trim, atmosphere: Atmosphere) -> None:
    """Re-initialise every JSBSim model (turbulence filters, actuators) at the trim state.

    The steady wind of ``atmosphere`` is added to the initial ground velocities so that the
    airspeed stays trimmed.

    Parameters
    ----------
    model : Model
        The loaded JSBSim model.
    trim : Trim
        The trim state.
    atmosphere : Atmosphere
        Steady wind (NED, m/s) and turbulence settings.
    """
    fdm = model.fdm
    for prop, value in trim.jsbsim.items():
        if not prop.startswith("ic/"):
            fdm[prop] = value
    for prop in _IC_ORDER:
        fdm[prop] = trim.jsbsim[prop]
    # IC body velocities are ground-relative: add the wind so the airspeed stays trimmed
    n, e, d = atmosphere.wind_ned_m_s
    wind = np.array([n, e, d], dtype=float) / FT
    w_body = ned_to_body(wind[:, None], *(np.array([trim.jsbsim[f"ic/{a}"]])
                          for a in ("phi-rad", "theta-rad", "psi-true-rad")))[:, 0]
    for i, axis in enumerate("uvw"):
        fdm[f"ic/{axis}-fps"] = trim.jsbsim[f"ic/{axis}-fps"] + w_body[i]
    # JSBSim's IC takes the horizontal wind as magnitude and direction (ic/vw-north-fps
    # does not stick in 1.3.3); the vertical wind is set after run_ic (Simulation.reset)
    fdm["ic/vw-mag-fps"] = math.hypot(n, e) / FT
    fdm["ic/vw-dir-deg"] = math.degrees(math.atan2(e, n))
    with quiet():
        fdm.reset_to_initial_conditions(0)  # InitModel() of every model, then run_ic
    for prop, value in trim.jsbsim.items():  # the FCS re-initialisation cleared them
        if not prop.startswith("ic/"):
            fdm[prop] = value
    fdm["propulsion/set-running"] = -1
    set_integrators(fdm)  # InitModel restored JSBSim's defaults
    set_atmosphere(model, atmosphere)
