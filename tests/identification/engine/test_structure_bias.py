"""The model-structure check of output error against equation error (engine.structure_bias)."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.engine.structure_bias import (
    STRUCTURE_LIMIT,
    StructureBiasWarning,
    widen_for_structure,
)
from flightid.identification.estimate import Estimate


def _estimate() -> Estimate:
    std = np.array([0.01, 0.0003, 0.002])
    return Estimate("oe", ["Cl_p", "Cn_beta", "bias_pdot"], np.array([-0.41, 0.0694, 0.0]),
                    std.copy(), covariance=np.diag(std**2), fit={})


def test_agreeing_estimates_keep_their_bounds():
    est = _estimate()
    # 0.02 apart with combined bound hypot(0.01, 0.005) = 0.0112: 1.8 bounds, agree
    assert widen_for_structure(est, {"Cl_p": (-0.43, 0.005)}) == {}
    assert est.std[0] == 0.01 and "structure" not in est.fit


def test_a_disagreement_widens_the_bound_by_the_difference():
    est = _estimate()
    # navion-sweep-roll seed 1: output error Cn_beta 0.0694, equation error 0.0669
    with pytest.warns(StructureBiasWarning, match="Cn_beta"):
        widened = widen_for_structure(est, {"Cn_beta": (0.0669, 0.0001),
                                            "Cl_p": (-0.41, 0.002)})
    assert list(widened) == ["Cn_beta"] and "equation error 0.0669" in widened["Cn_beta"]
    wide = np.hypot(0.0003, 0.0694 - 0.0669)  # 8.3 combined bounds apart
    assert est.std[1] == pytest.approx(wide)
    assert est.covariance[1, 1] == pytest.approx(wide**2)  # covariance follows the bound
    assert est.std[0] == 0.01 and est.values[1] == 0.0694  # the estimate itself is kept
    assert est.fit["structure"] == widened


def test_the_limit_is_three_combined_bounds():
    assert STRUCTURE_LIMIT == 3.0
    just_inside = 0.01 * np.hypot(1, 1) * 2.99
    est = _estimate()
    assert widen_for_structure(est, {"Cl_p": (-0.41 - just_inside, 0.01)}) == {}
    with pytest.warns(StructureBiasWarning):
        assert widen_for_structure(est, {"Cl_p": (-0.41 - 1.02 * just_inside / 0.99,
                                                  0.01)})
