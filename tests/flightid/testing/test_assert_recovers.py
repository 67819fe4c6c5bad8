"""``flightid.testing``: sigma and relative tolerances, either or both, a zero truth held to
an absolute tolerance, and a failure message with estimate, truth, error in % and sigmas."""

from __future__ import annotations

import re

import pytest

from flightid.testing import assert_recovers, miss_text, within


def test_within_checks_sigmas_relative_error_either_or_both():
    # truth 1.0, estimate 1.04 (4 %), std 0.01 (4 sigma)
    assert not within(1.0, 1.04, 0.01, sigma=3)
    assert within(1.0, 1.04, 0.01, sigma=5)
    assert within(1.0, 1.04, 0.01, sigma=None, rel=0.05)
    assert not within(1.0, 1.04, 0.01, sigma=3, rel=0.05)  # both by default
    assert within(1.0, 1.04, 0.01, sigma=3, rel=0.05, need="either")
    assert not within(1.0, 1.04, 0.01, sigma=3, rel=0.03, need="either")
    assert within(-1.0, -1.04, None, sigma=None, rel=0.05)  # negative truth: |truth|
    assert not within(1.0, 1.0, None, sigma=3)  # no bound: cannot be within sigmas
    # a zero truth: the relative test becomes |error| <= abs_tol
    assert within(0.0, 0.0009, 1.0, sigma=None, rel=0.05)
    assert not within(0.0, 0.0011, 1.0, sigma=None, rel=0.05)
    assert within(0.0, 0.0011, 1.0, sigma=None, rel=0.05, abs_tol=0.002)
    with pytest.raises(ValueError, match="need must be one of both, either"):
        within(1.0, 1.0, 1.0, need="all")
    with pytest.raises(ValueError, match="give sigma, rel or both"):
        within(1.0, 1.0, 1.0, sigma=None)


def test_miss_text_gives_estimate_truth_percent_and_sigmas():
    assert miss_text(3, "Cn_p", -0.0644, -0.0612, 0.00076) == (
        "seed 3 Cn_p: estimate -0.0612, truth -0.0644, error +5.0 % (+4.2 sigma)")
    assert "truth 0" in miss_text(1, "Cm_alphadot", 0.0, 0.5, 0.1)


def test_assert_recovers_either_or_both_and_the_failure_message():
    # hobby sensors, equation error: on seed 1 CL_alpha is far off in both senses
    # (measured -100 %, -4.1 sigma), the other five are within 3 sigma
    card = "telemaster-elevator-doublet"
    result = assert_recovers("ee", card=card, seeds=[1], sigma=3, rel=0.2, need="either",
                             fraction=0.8)
    assert result.pairs == 6 and result.inside == 5
    with pytest.raises(AssertionError) as failure:
        assert_recovers("ee", card=card, seeds=[1], sigma=3, rel=0.2)
    message = str(failure.value)
    assert "within 3 sigma and 20 %" in message
    line = next(s for s in message.splitlines() if "CL_alpha" in s)
    assert re.fullmatch(r"\s*seed 1 CL_alpha: estimate \S+, truth 4\.\d+, "
                        r"error [+-]\d+\.\d % \([+-]\d+\.\d sigma\)", line), line
