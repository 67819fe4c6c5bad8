"""``--method ee``: equation error, ordinary least squares of each measured coefficient.

``estimation`` (the estimate, the identifiability of the regressors, the prediction, the
method's options and protocol entry), ``terms`` (regressor terms: parsing, parameter
names, reference values, the regressor matrix and its smoothing), ``least_squares``
(the fit with Cramer-Rao bounds, corrected for colored residuals). The package exports
the method's API.
"""

from flightid.identification.methods.equation_error.estimation import (
    ID,
    METHOD,
    Options,
    estimate,
    estimate_model,
    predict,
    run,
)

__all__ = ["ID", "METHOD", "Options", "estimate", "estimate_model", "predict", "run"]
