"""``--method oe6dof``: output error on the nonlinear 6-DOF rigid-body equations.

``estimation`` (the estimate, the method's options and protocol entry), ``problem`` (a
record as a 6-DOF problem), ``simulation`` (its RK4 integration, outputs and
sensitivities). The package exports the method's API; the model structure is
``models.six_dof``.
"""

from flightid.identification.methods.nonlinear_6dof.estimation import (
    ID,
    METHOD,
    Options,
    estimate,
    run,
    start_from_equation_error,
)
from flightid.identification.methods.nonlinear_6dof.problem import (
    model_from_record,
    problem_from_record,
)
from flightid.identification.methods.nonlinear_6dof.simulation import simulate
from flightid.identification.models.six_dof import default_structure

__all__ = ["ID", "METHOD", "Options", "default_structure", "estimate", "model_from_record",
           "problem_from_record", "run", "simulate", "start_from_equation_error"]
