"""The method contract: what every identification method, yours included, must meet.

Like scikit-learn's ``check_estimator``: on a standard record (the Navion demo card, seed
5: elevator 3211, aileron doublet, rudder 2-1-1, research sensors, light turbulence) a
method returns one Estimate whose ``method`` is its id, with finite values and positive
standard errors of a declared kind and the fitted outputs; refuses an unknown option
naming the valid ones and a wrongly typed option naming it; refuses a record without a
channel it needs, naming it; and gives the same numbers twice.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from functools import cached_property

import numpy as np

from flightid.identification.estimate import Estimate, StdKind
from flightid.identification.identify import identify
from flightid.identification.methods import registry
from flightid.identification.methods.protocol import Method
from flightid.record import FlightRecord
from flightid.scenarios.cards import fly_card, load_card

CONTRACT_CARD = "navion-demo"
CONTRACT_SEED = 5
# the aileron doublet and the rudder 2-1-1 with their free responses: what every lateral
# model needs, and 20 s instead of 45 for the 6-DOF model (s)
CONTRACT_WINDOW = (12.0, 32.0)
# the checks of MethodContract, in the order check_method runs them
METHOD_CHECKS = ("declaration", "estimate", "unknown_option", "typed_option",
                 "missing_channel", "deterministic")


def contract_record(card: str = CONTRACT_CARD, seed: int = CONTRACT_SEED) -> FlightRecord:
    """The measured record of the contract flight.

    Parameters
    ----------
    card : str
        A flight card of the library (default: ``navion-demo``).
    seed : int
        The seed of sensor noise and turbulence.

    Returns
    -------
    FlightRecord
        The measured record (SI units, angles in rad).
    """
    measured, _ = fly_card(load_card(card), seed)
    return measured


def _raises_naming(call: Callable[[], object], patterns: list[str], what: str) -> None:
    """Fail unless ``call`` raises a ValueError whose message matches every regular
    expression of ``patterns`` (``re.search``)."""
    try:
        call()
    except ValueError as exc:
        message = str(exc)
        missing = [p for p in patterns if not re.search(p, message)]
        if missing:
            raise AssertionError(f"{what}: the error does not name {missing}: {message}") \
                from exc
        return
    raise AssertionError(f"{what}: no ValueError raised")


class MethodContract:
    """The contract's checks of one method on one record; each ``check_*`` raises an
    AssertionError saying what is wrong.

    Parameters
    ----------
    method : str or Method
        A registered method's id (built-in or from a ``flightid.methods`` entry point), or a
        Method value, registered for the checks if its id is not yet.
    record : FlightRecord, optional
        The record to identify from (default: ``contract_record()``).
    window : tuple of float
        The (start, end) window of the record to fit, s.
    """

    def __init__(self, method: str | Method, record: FlightRecord | None = None,
                 window: tuple[float, float] = CONTRACT_WINDOW) -> None:
        if isinstance(method, Method) and method.id not in registry.methods():
            registry.register(method)
        self.id = method.id if isinstance(method, Method) else method
        self.spec = registry.get(self.id)
        self.record = contract_record() if record is None else record
        self.window = window
        self.model = self.spec.contract_model or self.spec.default_model

    def identify(self) -> Estimate:
        """The method's estimate on the contract record and window (computed afresh)."""
        return identify(self.record, self.id, self.spec.contract_model or None,
                        window=self.window)

    @cached_property
    def estimate(self) -> Estimate:
        """The method's estimate, computed once per contract."""
        return self.identify()

    @property
    def boolean_options(self) -> list[str]:
        """The names of the method's boolean options (the typed-option check needs one)."""
        return [f.name for f in dataclasses.fields(self.spec.options)
                if f.type in (bool, "bool")]

    def check_declaration(self) -> None:
        """Name, summary, reference, models, options with defaults and help, channels."""
        spec = self.spec
        assert spec.id == self.id and spec.name and spec.summary and spec.reference, \
            f"{self.id}: id, name, summary and reference must all be declared"
        assert spec.default_model in spec.models, \
            f"{self.id}: default model {spec.default_model!r} not among {spec.models}"
        assert dataclasses.is_dataclass(spec.options), f"{self.id}: options is no dataclass"
        spec.options()  # every option has a default
        for row in spec.describe():
            assert row["help"], f"option {row['name']} of {self.id} has no help text"
        assert spec.channels(self.model), f"{self.id}: no channels declared for {self.model}"

    def check_estimate(self) -> None:
        """One Estimate meeting the protocol: finite values, positive standard errors of a
        stated kind, a consistent covariance, and the measured and fitted outputs."""
        est = self.estimate
        assert isinstance(est, Estimate), f"{self.id} returned {type(est).__name__}"
        assert est.method == self.id, f"estimate.method is {est.method!r}, not {self.id!r}"
        assert isinstance(est.std_kind, StdKind) and est.std_kind is not StdKind.NONE, \
            f"{self.id}: the standard errors' kind is not stated"
        assert est.names and len(set(est.names)) == len(est.names), \
            f"{self.id}: no names, or a name twice: {est.names}"
        assert np.all(np.isfinite(est.values)) and np.all(est.std > 0), \
            f"{self.id}: values not finite or standard errors not positive"
        assert not set(est.names) & set(est.unidentifiable), \
            f"{self.id}: estimated and unidentifiable at once: " \
            f"{sorted(set(est.names) & set(est.unidentifiable))}"
        if est.covariance is not None:
            assert est.covariance.shape == (len(est.names),) * 2, \
                f"{self.id}: covariance shape {est.covariance.shape}"
            assert np.allclose(np.sqrt(np.diag(est.covariance)), est.std, rtol=1e-6), \
                f"{self.id}: std is not the root of the covariance's diagonal"
        assert est.outputs, "the fitted and measured outputs are part of the estimate"
        for name, series in est.outputs.items():
            assert {"measured", "model"} <= set(series), f"{self.id}: output {name}"
            assert np.shape(series["measured"]) == np.shape(series["model"]), \
                f"{self.id}: output {name}: measured and model differ in shape"

    def check_unknown_option(self) -> None:
        """An unknown option is refused, naming it and every valid option."""
        names = ["no_such_option"] + [f.name for f in dataclasses.fields(self.spec.options)]
        _raises_naming(lambda: identify(self.record, self.id, no_such_option=1),
                       [re.escape(n) for n in names],
                       f"{self.id} with an unknown option")

    def check_typed_option(self) -> None:
        """A boolean option given a string is refused, naming it (no boolean: nothing)."""
        for name in self.boolean_options[:1]:
            _raises_naming(lambda n=name: identify(self.record, self.id, **{n: "maybe"}),
                           [re.escape(name)],
                           f"{self.id} with {name}='maybe'")

    def check_missing_channel(self) -> None:
        """A record without one of the first two channels the model needs is refused,
        naming that channel."""
        for missing in self.spec.channels(self.model)[:2]:
            lacking = FlightRecord(self.record.time,
                                   {k: v for k, v in self.record.channels.items()
                                    if k != missing}, self.record.meta)
            _raises_naming(lambda r=lacking: identify(r, self.id, self.model),
                           [rf"\b{re.escape(missing)}\b"],
                           f"{self.id} on a record without {missing}")

    def check_deterministic(self) -> None:
        """The same record and window give the same names and bit-identical numbers."""
        first, again = self.estimate, self.identify()
        assert again.names == first.names, f"{self.id}: names differ between two runs"
        np.testing.assert_array_equal(again.values, first.values,
                                      err_msg=f"{self.id}: values differ between two runs")
        np.testing.assert_array_equal(again.std, first.std,
                                      err_msg=f"{self.id}: std differs between two runs")


def check_method(method: str | Method, record: FlightRecord | None = None, *,
                 window: tuple[float, float] = CONTRACT_WINDOW) -> Estimate:
    """Run every check of the method contract; fail on the first that does not hold.

    Parameters
    ----------
    method : str or Method
        A method's id (built-in or from an installed ``flightid.methods`` entry point), or a
        Method value (registered for the checks if its id is not yet).
    record : FlightRecord, optional
        The record to identify from (default: the contract flight, ``contract_record()``).
    window : tuple of float
        The (start, end) window of the record to fit, s.

    Returns
    -------
    Estimate
        The method's estimate on the contract record.

    Raises
    ------
    AssertionError
        Naming the method and the check that failed.
    """
    contract = MethodContract(method, record, window)
    for name in METHOD_CHECKS:
        getattr(contract, f"check_{name}")()
    return contract.estimate
