"""Test helpers shipped with flightid, for your own methods and effects as for the built-in ones.

- ``check_method(method)``: the method contract (like scikit-learn's ``check_estimator``);
- ``check_effect(entry)``: the effect contract of a catalogue entry (like gymnasium's
  ``check_env``);
- ``assert_recovers(method, ...)``: a method held to the exact JSBSim truth over seeds.

    from flightid.testing import assert_recovers, check_method

    def test_my_method_meets_the_contract():
        check_method("mymethod")

    def test_my_method_recovers_the_navion():
        assert_recovers("mymethod", card="navion-demo", seeds=range(5), sigma=3)
"""

from flightid.testing.effect_contract import (
    EFFECT_CHECKS,
    ContractFlight,
    check_effect,
    contract_flight,
    run_effect_check,
)
from flightid.testing.method_contract import (
    CONTRACT_WINDOW,
    METHOD_CHECKS,
    MethodContract,
    check_method,
    contract_record,
)
from flightid.testing.recovery import Recovery, assert_recovers, miss_text, recovery, within

__all__ = ["CONTRACT_WINDOW", "EFFECT_CHECKS", "METHOD_CHECKS", "ContractFlight",
           "MethodContract", "Recovery", "assert_recovers", "check_effect", "check_method",
           "contract_flight", "contract_record", "miss_text", "recovery", "run_effect_check",
           "within"]
