"""``--method fem``'s options, its entry point with a linear-model preset and its entry in
the method registry."""

from __future__ import annotations

from dataclasses import dataclass

from flightid.identification.estimate import Estimate
from flightid.identification.methods.filter_error.estimation import ID, estimate
from flightid.identification.methods.protocol import HeldOptions, Method, option
from flightid.identification.models import a_priori
from flightid.identification.models import measured_inputs as mi
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord


@dataclass(frozen=True)
class Options(HeldOptions):
    """Options of ``--method fem``."""

    free: list[str] | None = option(None, "parameters to estimate (default: all not held)")
    start: dict[str, float] | None = option(None, "start (a priori) values")
    process_noise: list[str] | None = option(
        None, "states with process noise (default: all but the Euler angles)")
    process_noise_start: dict[str, float] | None = option(
        None, "start values of F_<state> (state units per sqrt(s))")
    initial_state: str = option("measured", "'measured' or 'zero' (the filter forgets it)")
    hold: str = option("cubic", "inputs between samples: 'cubic' (Catmull-Rom through four "
                                "samples), 'foh' (linear) or 'zoh' (held)")
    max_iterations: int = option(60, "Gauss-Newton iterations (per relaxation without "
                                     "joint_noise)")
    max_relaxations: int = option(20, "limit of alternating parameter / R updates")
    step_tolerance: float = option(1e-3, "converged when no step exceeds this many std")
    cost_tolerance: float = option(1e-6, "or when the cost falls less than this times |cost|")
    noise_tolerance: float = option(1e-3, "and R changes less than this (relative)")
    check_identifiability: bool = option(True, "report parameters the data cannot determine")
    dynamic_pressure: bool = option(
        True, "lateral model: the aerodynamic terms follow the measured qbar(t)/qbar_ref, "
              "with the full kinematics and inertial coupling as known inputs (as output "
              "error)")
    propulsive_moments: bool = option(
        True, "drive the lateral model with the record's L_prop, N_prop (N m) where it has "
              "them (as output error)")
    moment_axes: str = option(
        "body", "lateral model: 'stability' for an aircraft whose rolling and yawing "
                "moments are linear in the stability axes of the instantaneous alpha")
    condition_correction: bool = option(
        True, "models not following the measured qbar: correct the derivatives for qbar "
              "and V leaving the reference (first order)")
    colored: bool = option(True, "bounds corrected for colored innovations (Morelli & Klein "
                                 "2016 eq. 6.54 on the innovations)")
    joint_noise: bool = option(True, "estimate the measurement noise with the other "
                                      "parameters, from the output-error and the "
                                      "relaxation's end point, lower J kept")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """Filter error with a linear-model preset at the record's reference condition.

    A priori parameters are held, and the model takes the known inputs output error takes
    from the record (``measured_inputs.driven_by_measurements``).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, uniform sample interval.
    model : str, optional
        A linear-model preset ('lateral' default, 'longitudinal', 'short_period').
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        The estimate (``estimation.estimate``); ``fit`` also holds the a priori values
        ('a_priori') and the known inputs.
    """
    options = options or Options()
    linear, free, held = a_priori.linear_model(
        model_structure.linear(model), record, options.derivatives, options.a_priori,
        "filter error")
    record, linear = mi.driven_by_measurements(
        record, linear, dynamic_pressure=options.dynamic_pressure,
        propulsive_moments=options.propulsive_moments, moment_axes=options.moment_axes)
    est = estimate(
        record, linear, free=free if options.free is None else list(options.free),
        start=options.start, process_noise=options.process_noise,
        process_noise_start=options.process_noise_start,
        initial_state=options.initial_state, hold=options.hold,
        max_iterations=options.max_iterations, max_relaxations=options.max_relaxations,
        step_tolerance=options.step_tolerance, cost_tolerance=options.cost_tolerance,
        noise_tolerance=options.noise_tolerance,
        check_identifiability=options.check_identifiability,
        condition_correction=options.condition_correction, colored=options.colored,
        joint_noise=options.joint_noise)
    est.fit["a_priori"] = a_priori.describe(record, held)
    est.fit.update(mi.known_input_notes(linear))
    return est


METHOD = Method(
    id=ID, name="filter error",
    summary="maximum likelihood with a steady-state Kalman filter in the loop: process "
            "noise (turbulence) and measurement noise together",
    reference="Jategaonkar, Flight Vehicle System Identification: A Time-Domain "
              "Methodology, 2nd ed., 2015, ch. 5; Morelli & Klein 2016 ch. 6",
    options=Options, models=model_structure.LINEAR, default_model="lateral",
    channels=model_structure.linear_channels, run=run, contract_model="lateral",
)
