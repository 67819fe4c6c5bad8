"""The effect contract: what every entry of the effect catalogue, a new one included, must meet.

- its declaration is complete: a one-line description, parameters with unit, meaning, a
  default magnitude and a neutral value inside the allowed range, declared exactly as the
  implementation's fields (or, for the bridge's link faults and clocks, mapped onto
  existing fields of the referenced class), what it changes, and the card sections that
  take it resolve its name to it;
- injected at its default magnitude into a short real JSBSim flight (the Navion, 3 s, an
  elevator and an aileron doublet) it changes the data where the catalogue says it acts
  (sensor, mounting and vibration effects nothing else), and at zero magnitude it leaves
  the data unchanged (to float precision). Sensor, mounting and vibration effects go
  through ``measure``; disturbances are flown; link faults and clocks go through the
  bridge into a byte sink (the bytes a recorder would write to its tlog); airframe and
  actuator effects are written into a copy of the Navion's JSBSim XML
  (``flightid.sim.augment``), which is trimmed and flown like the original.
"""

from __future__ import annotations

import dataclasses
import math
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flightid.channels import CHANNELS
from flightid.record import FlightRecord
from flightid.sim.augment import augment
from flightid.sim.bridge.air.schedule import single_stream
from flightid.sim.bridge.air.serve import BridgeConfig, serve_record
from flightid.sim.bridge.decoding import message_time
from flightid.sim.bridge.frames import FrameScanner
from flightid.sim.bridge.link import Link
from flightid.sim.effects.base import ExternalImplementation
from flightid.sim.effects.catalogue import (
    ARRIVAL_TIMES,
    CATALOGUE,
    PACKET_BYTES,
    SECTIONS,
    TIME_STAMPS,
    ActsOn,
    Entry,
)
from flightid.sim.flight import disturbed as dist
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.sensors.suites import SensorSuite, measure
from flightid.units import DEG

RATE, DURATION = 100.0, 3.0  # the contract flight: Hz, s
ALTITUDE, SPEED = 500.0, 53.64  # its trim: m, m/s
# channels the measurement checks read (every record-level entry's changes among them)
MEASURED = ("V", "alpha", "beta", "p", "q", "r", "phi", "theta", "ax", "ay", "az")
LINK_DATA = (PACKET_BYTES, ARRIVAL_TIMES, TIME_STAMPS)
# the checks of check_effect, in order: the declaration first, then the injections
EFFECT_CHECKS = ("declaration", "implementation", "sections", "default_changes",
                 "zero_unchanged")


def _doublet(t: np.ndarray, start: float, half: float, amplitude: float) -> np.ndarray:
    return amplitude * (((t >= start) & (t < start + half)).astype(float)
                        - ((t >= start + half) & (t < start + 2 * half)).astype(float))


@dataclass
class ContractFlight:
    """The short real Navion flight effects are injected into, and its clean truth.

    Build one with ``contract_flight(folder)``; ``folder`` takes the augmented aircraft."""

    model: Any
    trim: Any
    controls: dict[str, np.ndarray]  # surface deflections, rad
    folder: Path
    truth: FlightRecord = field(init=False)

    def __post_init__(self) -> None:
        self.truth = self.fly([])

    def fly(self, disturbances: list, model: Any = None) -> FlightRecord:
        """The contract flight with ``disturbances``; ``model`` (an augmented aircraft) is
        trimmed at the same condition."""
        tr = self.trim
        if model is None:
            model = self.model
        else:
            tr = trim(model, ALTITUDE, SPEED)
        n = len(next(iter(self.controls.values())))
        gusts, turb = dist.wind_schedule(disturbances, n, RATE, tr, np.random.default_rng(1))
        return dist.fly_disturbed(model, tr, self.controls, DURATION, RATE,
                                  dist.atmosphere_for(disturbances, 1), wind=gusts,
                                  turbulence=turb)


def contract_flight(folder: Path | None = None) -> ContractFlight:
    """The Navion trimmed at 500 m and 53.64 m/s, an elevator doublet of 2 deg at 0.3 s and
    an aileron doublet of 3 deg at 1.2 s (0.4 s halves), 3 s at 100 Hz.

    Parameters
    ----------
    folder : Path, optional
        Where augmented copies of the aircraft are written (default: a new temporary
        folder).

    Returns
    -------
    ContractFlight
        The model, its trim, the controls (rad) and the clean flight's truth.
    """
    model = load("navion")
    tr = trim(model, ALTITUDE, SPEED)
    t = np.arange(int(round(DURATION * RATE)) + 1) / RATE
    controls = {"de": _doublet(t, 0.3, 0.4, 2 * DEG), "da": _doublet(t, 1.2, 0.4, 3 * DEG)}
    if folder is None:
        folder = Path(tempfile.mkdtemp(prefix="flightid-effect-contract-"))
    return ContractFlight(model, tr, controls, folder)


def _measure(truth: FlightRecord, chain=(), mounting=(), channel: str = "q") -> FlightRecord:
    channels: dict[str, list] = {c: [] for c in MEASURED}
    channels[channel] = list(chain)
    suite = SensorSuite("contract", channels, list(mounting), output_rate=RATE)
    return measure(truth, suite, seed=3)


class _Sink(Link):
    """Bytes the air side writes: what a recorder would log."""

    def __init__(self) -> None:
        self.data = bytearray()

    def write(self, data: bytes) -> None:
        self.data += data


def _bridged(truth: FlightRecord, entry: Entry | None = None, values=None) -> dict[str, list]:
    record = FlightRecord(truth.time, {c: truth[c] for c in MEASURED}, truth.meta)
    config = BridgeConfig(baud=None, seed=5)
    if entry is not None:
        fields = entry.fields(values)
        if entry.acts_on is ActsOn.LINK:
            config.faults = entry.resolve()(**fields)
        else:  # a recorder clock
            config.streams = tuple(dataclasses.replace(s, **fields) for s in single_stream())
    sink = _Sink()
    report = serve_record(record, sink, config)
    frames = FrameScanner().feed(bytes(sink.data))
    return {PACKET_BYTES: list(bytes(sink.data)),
            ARRIVAL_TIMES: [f.arrive for f in report.transmit.fates],
            TIME_STAMPS: [message_time(f.msg) for f in frames]}


def inject(entry: Entry, values: dict[str, float] | None,
           flight: ContractFlight) -> dict[str, np.ndarray | list]:
    """The data an entry changes, with the effect injected at ``values``.

    Parameters
    ----------
    entry : Entry
        The catalogue entry.
    values : dict of str to float or None
        Parameter name to value, in the parameter's unit; None for the defaults.
    flight : ContractFlight
        The reference flight.

    Returns
    -------
    dict
        The record's channels, or the link data, by name.
    """
    truth = flight.truth
    if entry.acts_on is ActsOn.SENSOR:
        rec = _measure(truth, [entry.build(values)], channel=entry.channel)
    elif entry.acts_on in (ActsOn.MOUNTING, ActsOn.VIBRATION):
        rec = _measure(truth, mounting=[entry.build(values)])
    elif entry.acts_on is ActsOn.DISTURBANCE:
        rec = flight.fly([entry.build(values)])
    elif entry.acts_on in (ActsOn.LINK, ActsOn.CLOCK):
        return _bridged(truth, entry, values)
    elif entry.acts_on in (ActsOn.AIRFRAME, ActsOn.ACTUATOR):
        xml = augment("navion", [entry.build(values)], flight.folder / entry.name)
        rec = flight.fly([], model=load(str(xml)))
    else:
        raise AssertionError(f"{entry.name}: the contract does not know how to inject an "
                             f"effect acting on {entry.acts_on}; extend inject()")
    return dict(rec.channels)


def baseline(entry: Entry, flight: ContractFlight) -> dict[str, np.ndarray | list]:
    """The same data as :func:`inject` returns, without the effect.

    Parameters
    ----------
    entry : Entry
        The catalogue entry.
    flight : ContractFlight
        The reference flight.

    Returns
    -------
    dict
        The record's channels, or the link data, by name.
    """
    if entry.acts_on in (ActsOn.SENSOR, ActsOn.MOUNTING, ActsOn.VIBRATION):
        return dict(_measure(flight.truth).channels)
    if entry.acts_on in (ActsOn.DISTURBANCE, ActsOn.AIRFRAME, ActsOn.ACTUATOR):
        return dict(flight.truth.channels)
    return _bridged(flight.truth)


def same(a, b) -> bool:
    """Whether two series are equal to float precision (1e-12 of the larger magnitude).

    Parameters
    ----------
    a, b : array_like
        The series; NaNs in the same places count as equal.

    Returns
    -------
    bool
        True when shapes agree and values are within 1e-12 * max(max|b|, 1).
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return False
    scale = max(float(np.nanmax(np.abs(b))) if b.size else 0.0, 1.0)
    return bool(np.allclose(a, b, rtol=0.0, atol=1e-12 * scale, equal_nan=True))


def check_declaration(entry: Entry) -> None:
    """Assert the entry's declaration is complete.

    A one-line description, parameters with unit, meaning, default and neutral value inside
    their range, options, and what the effect changes.

    Parameters
    ----------
    entry : Entry
        The catalogue entry.
    """
    assert entry.description and "\n" not in entry.description \
        and len(entry.description) < 120, f"{entry.name}: no one-line description"
    assert entry.parameters, "an effect without parameters cannot be sized or fitted"
    for p in entry.parameters:
        where = f"{entry.name}.{p.name}"
        assert p.unit and p.meaning, where
        assert p.low <= p.high, where
        assert math.isfinite(p.default) and p.allows(p.default), where
        assert p.allows(p.zero), where
    assert any(p.sizes and p.default != p.zero for p in entry.parameters), \
        f"{entry.name}: the default magnitude must differ from zero magnitude"
    for o in entry.options:
        assert o.default in o.choices and o.meaning, f"{entry.name}.{o.name}"
    assert entry.changes, f"{entry.name}: changes nothing"
    if entry.acts_on in (ActsOn.LINK, ActsOn.CLOCK):
        assert set(entry.changes) <= set(LINK_DATA), entry.changes
    else:
        assert all(c in CHANNELS for c in entry.changes), entry.changes
    if entry.acts_on is ActsOn.SENSOR:
        assert entry.channel in CHANNELS and entry.changes == (entry.channel,), entry.changes
    assert entry.how(), f"{entry.name}: how it acts is not said"


def check_implementation(entry: Entry) -> None:
    """Assert the entry resolves to a dataclass whose fields are the declared parameters.

    Through an ExternalImplementation the fields map onto them; the class takes the default
    and the zero magnitude.

    Parameters
    ----------
    entry : Entry
        The catalogue entry.
    """
    impl = entry.resolve()
    assert dataclasses.is_dataclass(impl), impl
    declared = {p.name for p in entry.parameters}
    fields = {f.name: f for f in dataclasses.fields(impl) if f.init}
    if isinstance(entry.implementation, ExternalImplementation):
        mapping = entry.implementation.mapping()
        assert set(mapping) == declared, f"{entry.name}: maps {sorted(mapping)}"
        assert set(mapping.values()) <= set(fields), f"{impl} lacks {set(mapping.values())}"
        assert set(entry.fields()) == set(mapping.values())
    else:
        options = {o.name for o in entry.options}
        floats = {n for n in fields if n != "source" and n not in options}
        assert declared == floats, f"declared {sorted(declared)}, implemented {sorted(floats)}"
        assert options <= set(fields), f"{entry.name}: options {sorted(options - set(fields))}"
        assert CATALOGUE.of(impl) is entry, f"{impl} is not catalogued as {entry.name}"
        for values in (entry.defaults(), entry.zeros()):
            built = entry.build(values).parameters()
            assert set(built) == set(values) and all(
                math.isclose(built[k], v, rel_tol=1e-6, abs_tol=1e-12)
                for k, v in values.items()), f"{entry.name}: built {built}, asked {values}"


def check_sections(entry: Entry) -> None:
    """Assert the card sections that take the entry resolve its name to it.

    The other sections refuse it, naming the key and the place it acts on.

    Parameters
    ----------
    entry : Entry
        The catalogue entry.
    """
    sections = entry.sections()
    if entry.acts_on in (ActsOn.LINK, ActsOn.CLOCK):
        assert not sections, f"{entry.name}: a link or clock effect in a card section"
    else:
        assert sections, f"{entry.name}: no card section takes it"
    for sec in sections:
        table = {sec.key: entry.name, **entry.defaults()}
        assert CATALOGUE.lookup_table(table, sec.name, "x") is entry, sec.name
        assert CATALOGUE.from_dict(table, sec.name, "x") == entry.build(), sec.name
    for sec in SECTIONS.values():
        if sec in sections:
            continue
        try:
            CATALOGUE.lookup_table({sec.key: entry.name}, sec.name, "x")
        except ValueError as exc:
            assert re.search(f"'x.{sec.key}'.*{entry.acts_on} effect", str(exc)), str(exc)
        else:
            raise AssertionError(f"section {sec.name} took {entry.name}")


def check_default_changes(entry: Entry, flight: ContractFlight) -> None:
    """Assert at its default magnitude the entry changes every datum it declares.

    A sensor, mounting or vibration effect changes nothing else.

    Parameters
    ----------
    entry : Entry
        The catalogue entry.
    flight : ContractFlight
        The reference flight.
    """
    clean = baseline(entry, flight)
    hit = inject(entry, entry.defaults(), flight)
    for c in entry.changes:
        assert not same(hit[c], clean[c]), f"{entry.name} left {c} unchanged"
    if entry.acts_on in (ActsOn.SENSOR, ActsOn.MOUNTING, ActsOn.VIBRATION):
        untouched = [c for c in clean if c not in entry.changes and not same(hit[c], clean[c])]
        assert not untouched, f"{entry.name} also changed {untouched}"


def check_zero_unchanged(entry: Entry, flight: ContractFlight) -> None:
    """Assert at zero magnitude the entry leaves every datum unchanged (to float precision).

    Parameters
    ----------
    entry : Entry
        The catalogue entry.
    flight : ContractFlight
        The reference flight.
    """
    clean = baseline(entry, flight)
    zero = inject(entry, entry.zeros(), flight)
    assert set(zero) == set(clean), f"{entry.name}: data {sorted(set(zero) ^ set(clean))}"
    changed = [c for c in clean if not same(zero[c], clean[c])]
    assert not changed, f"{entry.name} at zero magnitude changed {changed}"


def run_effect_check(name: str, entry: Entry, flight: ContractFlight | None = None) -> None:
    """Run one check of the effect contract by name.

    Parameters
    ----------
    name : str
        One of ``EFFECT_CHECKS``.
    entry : Entry
        The catalogue entry.
    flight : ContractFlight, optional
        The flight the injection checks fly (default: a new ``contract_flight()``).

    Raises
    ------
    AssertionError
        Naming the entry and what does not hold.
    """
    declared = {"declaration": check_declaration, "implementation": check_implementation,
                "sections": check_sections}
    injected = {"default_changes": check_default_changes,
                "zero_unchanged": check_zero_unchanged}
    if name in declared:
        declared[name](entry)
    elif name in injected:
        injected[name](entry, flight or contract_flight())
    else:
        raise ValueError(f"unknown effect check {name!r}; known: {', '.join(EFFECT_CHECKS)}")


def check_effect(entry: Entry | str, flight: ContractFlight | None = None) -> None:
    """Run every check of the effect contract; fail on the first that does not hold.

    Parameters
    ----------
    entry : Entry or str
        A catalogue entry, or its name in ``flightid.sim.effects.catalogue.CATALOGUE``.
    flight : ContractFlight, optional
        The flight to inject into (default: a new ``contract_flight()``, about 1 s to fly).

    Raises
    ------
    AssertionError
        Naming the entry and what does not hold.
    """
    if isinstance(entry, str):
        entry = CATALOGUE[entry]
    flight = flight or contract_flight()
    for name in EFFECT_CHECKS:
        run_effect_check(name, entry, flight)
