"""The maximum-likelihood engine shared by the time-domain methods.

Output error on linear models (``methods.output_error``), on the nonlinear 6-DOF equations
(``methods.nonlinear_6dof``), filter error (``methods.filter_error``) and flight path
reconstruction (``compatibility``) all minimise a negative log-likelihood by damped
Newton steps, bound their estimates by the Cramer-Rao inequality and refit without the
parameters the flight cannot determine (Morelli & Klein 2016, ch. 6; Jategaonkar 2015,
ch. 4-5). One module per job:

- ``problem``: the skeleton every output-error problem extends (measured outputs, fixed
  parameters, initial states, noise floor), its fit and its unidentifiable parameters;
- ``likelihood``: measurement-noise covariance R, the cost with R concentrated out, the
  Fisher information matrix and the Hessian of the concentrated cost;
- ``gauss_newton``: the damped (Levenberg-Marquardt) Newton step and the output-error
  optimiser ``maximum_likelihood`` with its result ``MaximumLikelihoodFit``;
- ``bounds``: Cramer-Rao bounds, with the correction for colored residuals;
- ``refit``: the loop "fit, find the unidentifiable parameters, fix them at their a priori
  values, refit";
- ``results``: the ``Estimate`` of an output-error fit;
- ``threads``: one BLAS thread for work made of many small matrices.

The engine knows no model: a method hands it functions of the parameter values.
"""
