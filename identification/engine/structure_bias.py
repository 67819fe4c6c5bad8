"""Model-structure check: an output-error fit against equation error on the same record.

Output error integrates a linear perturbation model at a constant flight condition;
equation error regresses each coefficient, formed from the measured accelerations, the
measured dynamic pressure and the full kinematics, on the measured states. Where the
record leaves the linear model's domain (a 90 s roll sweep banking the Navion to 19 deg
with its airspeed moving by +-5 %; inertial coupling and the changing dynamic pressure
that the model holds constant) the two disagree far beyond their bounds, and output
error's Cramer-Rao bound, which covers the noise but not a structure error, no longer
says how far its estimate can be from the aircraft (Morelli & Klein 2016 and Jategaonkar
2015 on model validation: estimates of different methods from the same data that differ
beyond their error bounds point to a model structure error).

``widen_for_structure`` makes the bound say so: where the two estimates differ by more
than ``STRUCTURE_LIMIT`` times their combined standard errors, the output-error standard
error becomes sqrt(s_oe^2 + (theta_oe - theta_ee)^2), the difference taken as a model
structure error of that size, and the derivative is listed with the reason (printed as a
warning by the command line). Estimates that agree keep their bounds.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping

import numpy as np

from flightid.identification.estimate import Estimate

# combined standard errors beyond which output error and equation error are taken to
# disagree (at 3, two unbiased estimates of the same quantity exceed it in 0.3 % of cases
# when their errors are independent; correlated errors only make the difference smaller)
STRUCTURE_LIMIT = 3.0


class StructureBiasWarning(UserWarning):
    """Output error and equation error disagree beyond their bounds on some derivatives."""


def widen_for_structure(est: Estimate, reference: Mapping[str, tuple[float, float]],
                        limit: float = STRUCTURE_LIMIT) -> dict[str, str]:
    """Widen ``est``'s standard errors where it disagrees with ``reference``.

    Parameters
    ----------
    est : Estimate
        An output-error estimate, changed in place: ``std`` (and the matching rows and
        columns of ``covariance``) of the derivatives that disagree, and
        ``fit['structure']`` listing them with the reason.
    reference : mapping of str to (float, float)
        Equation-error (value, standard error) per derivative, same units as ``est``.
    limit : float
        Disagreement, in combined standard errors, beyond which a bound is widened.

    Returns
    -------
    dict of str to str
        The widened derivatives and the reason for each (empty when all agree).
    """
    widened: dict[str, str] = {}
    for i, name in enumerate(est.names):
        if name not in reference or name in est.unidentifiable:
            continue
        value, std = float(est.values[i]), float(est.std[i])
        ref_value, ref_std = reference[name]
        combined = math.hypot(std, ref_std)
        if not (np.isfinite(combined) and combined > 0):
            continue
        gap = (value - ref_value) / combined
        if abs(gap) <= limit:
            continue
        wide = math.hypot(std, value - ref_value)
        if est.covariance is not None:
            scale = wide / std if std > 0 else 1.0
            est.covariance[i, :] *= scale
            est.covariance[:, i] *= scale
        est.std[i] = wide
        widened[name] = (f"output error {value:.4g} and equation error {ref_value:.4g} "
                         f"differ by {gap:+.1f} combined bounds: a model structure error "
                         f"the linear model does not hold; bound widened from {std:.3g} to "
                         f"{wide:.3g}")
    if widened:
        est.fit["structure"] = widened
        warnings.warn(
            f"{len(widened)} derivative(s) ({', '.join(widened)}): output error and "
            f"equation error disagree by more than {limit:g} combined bounds; the linear "
            "model's structure does not hold on this record, and their bounds now include "
            "the difference", StructureBiasWarning, stacklevel=2)
    return widened
