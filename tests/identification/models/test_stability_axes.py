"""The lateral model for stability-axis aerodynamics (``moment_axes="stability"``,
``measured_inputs.with_stability_axes``): the Navion's JSBSim model writes its rolling and
yawing moments about the stability axes of the instantaneous alpha, with stability-axis
rates, so its body-axis derivatives move with alpha along the flight. On navion-demo's
exact truth record (calm air, alpha within 0.25 deg of trim) the body-axis linear model
put Cl_dr 2.3 % and Cn_da 4.1 % off; the stability-axis terms take it out."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest

from flightid.identification.evaluation.scoring import record_truth, score
from flightid.identification.identify import identify
from flightid.identification.models import linear as lm
from flightid.identification.models import measured_inputs as mi
from flightid.identification.models.reference_condition import condition_from_record
from flightid.record import FlightRecord
from flightid.scenarios.cards import fly_card, load_card
from flightid.scenarios.cards.overrides import overridden_card
from flightid.sim.jsbsim.model import quiet


@pytest.fixture(scope="module")
def truth_record():
    card = overridden_card(load_card("navion-demo"), turbulence="none")
    with quiet(), contextlib.redirect_stdout(io.StringIO()):
        _, truth = fly_card(card, 1)
    return truth


def _errors(record, **options) -> dict[str, float]:
    est = identify(record, "oe", "lat", **options)
    return {r.name: r.error / r.truth for r in score(est, record_truth(record)).rows
            if r.truth}


def test_stability_axis_terms_close_the_moments(truth_record):
    # the truth record's Cl, Cn against the model's roll and yaw rows at the truth
    # derivatives (rates scaled to the reference airspeed, so that only the axes differ),
    # without and with the alpha terms of with_stability_axes
    t = record_truth(truth_record)
    c = condition_from_record(truth_record)
    base = lm.lateral(c, start={n: t[n] for n in lm.LATERAL_EXAMPLE_6_1 if n in t})
    model = mi.with_stability_axes(base)
    scale = c.V / truth_record["V"]
    channels = {**truth_record.channels, "p": truth_record["p"] * scale,
                "r": truth_record["r"] * scale}
    record = mi.with_stability_axes_channels(
        FlightRecord(truth_record.time, channels, truth_record.meta), base)
    A, B, _, _ = model.matrices()
    rows = [model.states.index("p"), model.states.index("r")]
    x = np.column_stack([record[s] for s in model.states])
    u = np.column_stack([record[n] for n in model.inputs])
    surfaces = len(lm.LATERAL_INPUTS)
    inertia = np.array([[c.Ixx, -c.Ixz], [-c.Ixz, c.Izz]])
    k = c.qbar * c.area * c.span
    body = (x @ A[rows].T + u[:, :surfaces] @ B[rows, :surfaces].T) @ inertia.T / k
    turned = body + u[:, surfaces:] @ B[rows, surfaces:-1].T @ inertia.T / k
    measured = np.column_stack([truth_record["Cl"], truth_record["Cn"]])
    without = np.sqrt(np.mean((measured - body) ** 2, axis=0))
    with_terms = np.sqrt(np.mean((measured - turned) ** 2, axis=0))
    # measured (a regression check of the same closure): 5.5e-6 and 1.1e-5 rms of Cl and
    # Cn without the terms, 2e-7 and 3e-8 with them
    assert np.all(with_terms < 0.1 * without), (without, with_terms)


def test_output_error_on_the_truth_record(truth_record):
    body = _errors(truth_record)
    stability = _errors(truth_record, moment_axes="stability")
    # a noise-free record: the errors are the model's. Body axes: Cl_dr +2.3 %, Cn_da
    # +4.1 %, Cn_p -1.0 %; stability axes: every derivative within 0.3 % (measured: Cl_dr
    # +0.23 %, Cn_da +0.28 %, Cn_p -0.23 %, the rest within 0.03 %)
    assert body["Cl_dr"] > 0.015 and body["Cn_da"] > 0.03
    worst = max(stability, key=lambda n: abs(stability[n]))
    assert abs(stability[worst]) < 0.004, (worst, stability[worst])


def test_bad_moment_axes_named():
    with pytest.raises(ValueError, match="moment_axes must be one of body, stability"):
        mi.driven_by_measurements(None, None, moment_axes="wind")
