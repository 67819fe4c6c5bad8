"""The standard data reduction of ``flightid identify``: accelerometers and vanes to the CG
from the sensor positions a record carries, the vane scale from flight path
reconstruction; ``--raw`` skips it; a record without positions gets a warning."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.identification.data.reduction import NO_POSITIONS, calibration_doubts, reduce_record
from flightid.identification.evaluation.scoring import score
from flightid.identification.identify import identify
from flightid.record import FlightRecord
from flightid.scenarios.cards import fly_card, load_card, overridden_card

runner = CliRunner()
# the research suite's mounting (sim/sensors/suites.py): IMU 0.3 m ahead and 0.2 m below the CG,
# nose-boom vanes 4.5 m ahead with flow amplification 1.06 (alpha) and 1.10 (beta)
MOUNTING = ('sensors.mounting=[{effect="lever_arm", x=0.3, z=0.2}, {effect="vanes", '
            'alpha_x=4.5, beta_x=4.5, upwash=0.06, sidewash=0.10}]')


@pytest.fixture(scope="module")
def research_flight(tmp_path_factory):
    """twinotter-lateral-0alpha as in the library (research sensors, vanes, lever arm)."""
    measured, _ = fly_card(load_card("twinotter-lateral-0alpha"), 1)
    path = tmp_path_factory.mktemp("reduction") / "lateral.parquet"
    measured.write(path)
    return measured, path


def test_records_carry_their_sensor_positions():
    measured, _ = fly_card(load_card("navion-demo"), 1)  # vanes and lever arm dropped
    assert measured.meta.extra["sensor_positions"] == {"accelerometers": [0.0, 0.0, 0.0]}
    reduction = reduce_record(measured)
    assert reduction.applied == [] and reduction.warnings == []
    assert reduction.record is measured


def test_exact_sensors_off_the_cg_come_back_to_the_cg():
    # ideal sensors with the research mounting: after the reduction only the
    # differentiation of the rates (0.2 s local fits) and the linearised vane geometry
    # are left between the record and the CG truth
    card = overridden_card(load_card("twinotter-lateral-0alpha"),
                           ["sensors.suite=ideal", MOUNTING])
    measured, truth = fly_card(card, 1)
    assert measured.meta.extra["sensor_positions"] == {
        "accelerometers": [0.3, 0.0, 0.2], "alpha_vane": [4.5, 0.0, 0.0],
        "beta_vane": [4.5, 0.0, 0.0]}
    reduction = reduce_record(measured)
    reduced = reduction.record
    assert reduced.meta.extra["sensor_positions"] == {"accelerometers": [0.0, 0.0, 0.0]}
    assert reduced.meta.extra["data_reduction"] == reduction.applied

    def rms(x: np.ndarray) -> float:
        return float(np.sqrt(np.mean(x ** 2)))

    for c in ("ax", "ay", "az", "beta"):
        before, after = rms(measured[c] - truth[c]), rms(reduced[c] - truth[c])
        assert after < 0.1 * before, (c, before, after)
    # beta: the sidewash of 0.10 estimated from the kinematics, to 1e-3
    assert "beta scale 1 + 0.100" in reduction.applied[1]
    assert rms(reduced["beta"] - truth["beta"]) < 1e-4  # rad; beta moves 0.09 rad
    # a second reduction finds nothing left to do
    assert reduce_record(reduced).applied == []


def test_reduction_brings_the_mounting_biased_derivatives_within_3_sigma(research_flight):
    measured, _ = research_flight
    reduced = reduce_record(measured).record

    def rows(record, **options):
        return {r.name: r for r in score(identify(record, "oe", "lat", **options), record).rows}

    # the model's own bounds (no structure check, which widens the raw record's biased
    # bounds too): vanes ahead of the CG read beta + x r/V and a 10 % sidewash scales beta,
    # so the side force derivatives of the raw record are off (seed 1: CY_beta -7.0 %,
    # +3.9 sigma; CY_dr -20 %, -3.7; CY_r -23 %, -3.7), and the yaw ones by 1 % (Cn_beta
    # -0.9 %, Cn_r +1.3 %, 2.5 sigma)
    raw, done = rows(measured, structure_check=False), rows(reduced, structure_check=False)
    moved = ("CY_beta", "CY_dr", "CY_r")
    assert all(abs(raw[n].sigmas) > 3 for n in moved), raw
    # reduced, the mounting errors are gone: 0.01-0.09 % on these, 0.01 % and 0.12 % on
    # Cn_beta and Cn_r (a fifth of their raw error or less)
    assert all(abs(done[n].sigmas) <= 3 for n in moved), done
    assert all(abs(done[n].error) < 0.2 * abs(raw[n].error)
               for n in (*moved, "Cn_beta", "Cn_r")), done
    assert abs(done["Cl_beta"].sigmas) <= 3 and abs(done["Cl_r"].sigmas) <= 3
    # with the defaults the structure check widens no bound the reduction made right
    checked = rows(reduced)
    assert all(abs(checked[n].sigmas) <= 3 for n in moved), checked


def test_identify_prints_the_reduction_and_raw_skips_it(research_flight):
    _, path = research_flight
    result = runner.invoke(app, ["identify", str(path)])
    assert result.exit_code == 0, result.output
    assert "data reduction: accelerometers moved to the CG from (0.3, 0, 0.2) m" \
        in result.stdout
    assert "data reduction: flow angles: alpha vane at (4.5, 0, 0) m" in result.stdout
    result = runner.invoke(app, ["identify", str(path), "--raw", "--format", "json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["data_reduction"] == "skipped (--raw)"
    raw_rows = {r["name"]: r["sigmas"] for r in out["score"]["rows"]}
    result = runner.invoke(app, ["identify", str(path), "--format", "json"])
    reduced = json.loads(result.stdout)
    assert reduced["data_reduction"][0].startswith("accelerometers moved to the CG")
    # the estimates differ: the reduction reached the fit
    assert {r["name"]: r["sigmas"] for r in reduced["score"]["rows"]} != raw_rows


def test_a_record_without_positions_gets_a_warning_naming_the_bias(research_flight, tmp_path):
    measured, _ = research_flight
    extra = {k: v for k, v in measured.meta.extra.items() if k != "sensor_positions"}
    bare = FlightRecord(measured.time, dict(measured.channels),
                        dataclasses.replace(measured.meta, extra=extra))
    reduction = reduce_record(bare)
    assert reduction.applied == [] and reduction.warnings == [NO_POSITIONS]
    path = tmp_path / "bare.parquet"
    bare.write(path)
    result = runner.invoke(app, ["identify", str(path)])
    assert result.exit_code == 0, result.output
    assert "warning: the record carries no sensor positions" in result.stderr
    assert "CY_beta" in result.stderr and "1/K" in result.stderr


# `flightid montecarlo twinotter-lateral-0alpha --turbulence light --seed 9100`, realization 3
TURBULENT_SEED = 3517412064


def test_turbulence_is_not_taken_for_vane_errors(research_flight, tmp_path):
    # flight path reconstruction assumes steady air: in light turbulence it fitted the gusts
    # as K_alpha = -0.005 and a beta bias of +5.15 deg, the reduced alpha reached 85 rad and
    # identify refused the record ("alpha looks like degrees")
    card = overridden_card(load_card("twinotter-lateral-0alpha"), turbulence="light")
    measured, _ = fly_card(card, TURBULENT_SEED)
    reduction = reduce_record(measured)
    assert not any("from flight path reconstruction (" in a for a in reduction.applied)
    assert "vane scale and bias not applied" in reduction.applied[-1]
    (warning,) = reduction.warnings
    assert warning.startswith("vane scale and bias from flight path reconstruction not "
                              "applied: the reconstruction leaves residuals of alpha")
    assert "turbulence" in warning and "1/K" in warning
    # the reconstruction's own estimates, out of the physical range, are named
    assert "outside the physical 0.8-1.2" in warning
    reduced = reduction.record
    # light turbulence moves alpha by +-3 deg about its 0.6 deg trim: only the position
    # effect (x q / V, under 0.1 deg here) separates it from the vane reading
    assert np.max(np.abs(reduced["alpha"])) < 0.1
    assert np.max(np.abs(reduced["alpha"] - measured["alpha"])) < np.radians(0.5)
    rows = {r.name: r for r in score(identify(reduced, "oe", "lat"), reduced).rows}
    # the uncorrected sidewash (K_beta 1.10) is inside the fit's bounds (measured: -0.1 %)
    assert abs(rows["CY_beta"].sigmas) <= 3, rows["CY_beta"]
    # calm air: the calibration passes every check and is applied
    assert calibration_doubts(*research_flight[:1], reduce_record(research_flight[0])
                              .reconstruction) == []
    path = tmp_path / "turbulent.parquet"
    measured.write(path)
    result = runner.invoke(app, ["identify", str(path)])
    assert result.exit_code == 0, result.output
    assert "warning: vane scale and bias from flight path reconstruction not applied" \
        in result.stderr
    # compatibility runs the same checks on its own reconstruction and says so
    result = runner.invoke(app, ["compatibility", str(path), "--format", "json"])
    assert result.exit_code == 0, result.output
    assert "warning: vane calibration doubtful: the reconstruction leaves residuals of " \
        "alpha" in result.stderr
    assert any("turbulence" in d for d in json.loads(result.stdout)["calibration_doubts"])
