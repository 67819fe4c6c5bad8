"""SIDPAC reader: the real NASA Twin Otter record in SI units, and lossless round trips."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from flightid import record as record_io
from flightid.sidpac import read_mat
from flightid.units import DEG, FT, G0, SLUG, SLUG_FT2
from tests.conftest import TWIN_OTTER

# the record in shared/ beside the repository (tests/conftest.py); a missing file fails, not skips

@pytest.fixture(scope="module")
def rec():
    return read_mat(TWIN_OTTER)


def test_trim_values_match_the_published_ones(rec):
    # README trim: V ~ 237 ft/s, h ~ 6,200 ft, mass ~ 339 slug, inertias in slug ft^2
    # (record means; the README quotes them to 3-4 significant figures, hence 0.5 %)
    published = {
        "V": (237.0, FT),
        "h": (6200.0, FT),
        "mass": (339.0, SLUG),
        "Ixx": (20900.0, SLUG_FT2),
        "Iyy": (24260.0, SLUG_FT2),
        "Izz": (38460.0, SLUG_FT2),
        "Ixz": (1127.0, SLUG_FT2),
    }
    for name, (value, factor) in published.items():
        back = np.mean(rec[name]) / factor
        assert back == pytest.approx(value, rel=0.005), name
    # alpha ~ 0.2 deg is quoted to one decimal, i.e. +/- 0.05 deg; a relative tolerance on
    # a value this close to 0 would be meaningless
    assert np.mean(rec["alpha"]) / DEG == pytest.approx(0.2, abs=0.05)


def test_units_names_and_metadata(rec):
    assert rec.meta.aircraft == "NASA Twin Otter (DHC-6)"
    assert rec.meta.sample_rate == pytest.approx(50.0)
    assert len(rec) == 1001 and rec.time[0] == 0.0 and rec.time[-1] == pytest.approx(20.0)
    ref = rec.meta.reference
    assert ref.area == pytest.approx(422.483473 * FT**2)
    assert ref.span == pytest.approx(64.993436 * FT)
    assert ref.chord == pytest.approx(6.496063 * FT)
    # 1 g level flight: az about -1 g in SI
    assert np.mean(rec["az"]) == pytest.approx(-1.008 * G0, rel=0.01)
    # qbar = rho V^2 / 2 in SI, to the accuracy of the air-data system (1 %)
    qbar = 0.5 * rec["rho"] * rec["V"] ** 2
    assert np.mean(qbar) == pytest.approx(np.mean(rec["qbar"]), rel=0.01)
    # phat = p b / 2V: the file's column is a perturbation (mean removed), so compare shapes
    phat = rec["p"] * ref.span / (2 * rec["V"])
    assert np.corrcoef(phat, rec["phat"])[0, 1] > 0.999
    for name in ("ax_meas", "thrust_1", "CT"):
        assert name in rec.meta.units
    assert rec.unit("ax_meas") == "m/s^2"


def test_thrust_is_both_engines(rec):
    # CT column = total thrust / (qbar S): the sum of columns 38 and 39 reproduces it
    ct = rec["thrust"] / (rec["qbar"] * rec.meta.reference.area)
    np.testing.assert_allclose(ct, rec["CT"], rtol=1e-9)


def test_control_signs_follow_project_convention(rec):
    # project convention: da > 0 gives Cl < 0, dr > 0 gives Cn < 0. A least-squares slope
    # with the main lateral regressors must have those signs (published -0.21, -0.13).
    x = np.column_stack(
        [rec["beta"], rec["phat"], rec["rhat"], rec["da"], rec["dr"], np.ones(len(rec))]
    )
    cl = np.linalg.lstsq(x, rec["Cl"], rcond=None)[0]
    cn = np.linalg.lstsq(x, rec["Cn"], rcond=None)[0]
    assert cl[3] < -0.1 and cn[4] < -0.1


def test_missing_fdata_is_a_clear_error(tmp_path):
    bad = tmp_path / "no_fdata.mat"
    scipy.io.savemat(bad, {"t": np.arange(5.0), "other": np.zeros(3)})
    with pytest.raises(ValueError, match=r"variable 'fdata' is missing.*other"):
        read_mat(bad)
    bad_t = tmp_path / "no_t.mat"
    scipy.io.savemat(bad_t, {"fdata": np.zeros((5, 90))})
    with pytest.raises(ValueError, match=r"variable 't' is missing"):
        read_mat(bad_t)


def test_wrong_column_count_is_a_clear_error(tmp_path):
    bad = tmp_path / "narrow.mat"
    scipy.io.savemat(bad, {"t": np.arange(5.0), "fdata": np.zeros((5, 12))})
    with pytest.raises(ValueError, match=r"fdata has shape \(5, 12\)"):
        read_mat(bad)


def test_record_read_dispatches_mat(rec):
    again = record_io.read(TWIN_OTTER)
    np.testing.assert_array_equal(again["Cn"], rec["Cn"])


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_lossless_round_trip(rec, tmp_path, suffix):
    path = rec.write(tmp_path / f"totter{suffix}")
    back = record_io.read(path)
    np.testing.assert_array_equal(back.time, rec.time)
    assert set(back.channels) == set(rec.channels)
    for name, values in rec.channels.items():
        # equal to the bit
        assert np.array_equal(back[name].view(np.uint64), values.view(np.uint64)), name
    assert back.meta == rec.meta
