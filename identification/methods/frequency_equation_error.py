"""Frequency-domain equation error (``--method fdee``): each coefficient's Fourier
transform regressed on its variables' transforms (Morelli & Klein 2016 ch. 7, eq. 7.16).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.identification.estimate import Estimate, merge
from flightid.identification.frequency import state_space_fit as frequency_domain
from flightid.identification.methods.protocol import Method, RegressionOptions, option
from flightid.identification.models import structure as model_structure
from flightid.record import FlightRecord

ID = "fdee"


@dataclass(frozen=True)
class Options(RegressionOptions):
    """Options of ``--method fdee``."""

    frequencies: list[float] | None = option(
        None, "analysis frequencies, Hz (default 0.1-1.5 Hz spaced 1/T)")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """Frequency-domain equation error for every coefficient of ``model``.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    model : str, optional
        A regression preset or an explicit structure 'Cn=beta+rhat; ...'. Default
        'lateral'.
    options : Options or None, optional
        Method options; None takes the defaults.

    Returns
    -------
    Estimate
        One estimate merging the coefficients' fits.
    """
    options = options or Options()
    structure = model_structure.regression(model, options.coefficients)
    freqs = None if options.frequencies is None else np.asarray(options.frequencies, float)
    return merge(ID, [frequency_domain.equation_error(record, c, terms, frequencies=freqs)
                      for c, terms in structure.items()])


METHOD = Method(
    id=ID, name="frequency-domain equation error",
    summary="least squares of each coefficient's finite Fourier transform on its "
            "variables' transforms, over a band of frequencies",
    reference="Morelli & Klein, Aircraft System Identification: Theory and Practice, "
              "2nd ed., 2016, ch. 7",
    options=Options, models=(*model_structure.REGRESSION, "structure"),
    default_model="lateral", channels=model_structure.regression_channels, run=run,
    contract_model="lateral",
)
