"""Every effect of the catalogue meets its contract; a new effect is covered by being registered.

For each entry of ``flightid.sim.effects.catalogue.CATALOGUE``:
- its declaration is complete: a one-line description, parameters with unit, meaning, a
  default magnitude and a neutral value inside the allowed range, declared exactly as the
  implementation's fields (or, for the bridge's link faults and clocks, mapped onto
  existing fields of the referenced class), what it changes, and the card sections that
  take it resolve its name to it;
- it resolves to an implementation, which accepts the default and the zero magnitude;
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
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from flightid.channels import CHANNELS
from flightid.cli.effects import effects_command
from flightid.identification.compatibility.reconstruction import CATALOGUE_EFFECTS
from flightid.record import FlightRecord
from flightid.sim.augment import augment
from flightid.sim.bridge.air import BridgeConfig, serve_record
from flightid.sim.bridge.frames import FrameScanner
from flightid.sim.bridge.link import Link
from flightid.sim.bridge.messages import message_time
from flightid.sim.bridge.schedule import single_stream
from flightid.sim.effects.base import Reference
from flightid.sim.effects.catalogue import (
    ARRIVAL_TIMES,
    CATALOGUE,
    PACKET_BYTES,
    RESERVED,
    SECTIONS,
    TIME_STAMPS,
    ActsOn,
    Entry,
    listing,
    markdown_table,
)
from flightid.sim.flight import disturbed as dist
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.sensors.suites import SensorSuite, measure
from flightid.units import DEG

ENTRIES = list(CATALOGUE.values())
IDS = [e.name for e in ENTRIES]
DOCS = Path(__file__).resolve().parents[2] / "docs" / "effects.md"
RATE, DURATION = 100.0, 3.0
# channels the measurement tests read (every record-level entry's changes among them)
MEASURED = ("V", "alpha", "beta", "p", "q", "r", "phi", "theta", "ax", "ay", "az")
LINK_DATA = (PACKET_BYTES, ARRIVAL_TIMES, TIME_STAMPS)


# -- a short real flight -----------------------------------------------------------------


def _doublet(t: np.ndarray, start: float, half: float, amplitude: float) -> np.ndarray:
    return amplitude * (((t >= start) & (t < start + half)).astype(float)
                        - ((t >= start + half) & (t < start + 2 * half)).astype(float))


@pytest.fixture(scope="module")
def aircraft():
    model = load("navion")
    tr = trim(model, 500.0, 53.64)
    t = np.arange(int(round(DURATION * RATE)) + 1) / RATE
    controls = {"de": _doublet(t, 0.3, 0.4, 2 * DEG), "da": _doublet(t, 1.2, 0.4, 3 * DEG)}
    return model, tr, controls


def fly(aircraft, disturbances, model=None):
    base, tr, controls = aircraft
    if model is None:
        model = base
    else:  # an augmented aircraft: its own trim at the same condition
        tr = trim(model, 500.0, 53.64)
    n = len(next(iter(controls.values())))
    gusts, turb = dist.wind_schedule(disturbances, n, RATE, tr, np.random.default_rng(1))
    return dist.fly_disturbed(model, tr, controls, DURATION, RATE,
                              dist.atmosphere_for(disturbances, 1), wind=gusts,
                              turbulence=turb)


@pytest.fixture(scope="module")
def truth(aircraft):
    return fly(aircraft, [])


# -- injection by where the effect acts ------------------------------------------------------


def _measure(truth, chain=(), mounting=(), channel="q"):
    channels = {c: [] for c in MEASURED}
    channels[channel] = list(chain)
    suite = SensorSuite("contract", channels, list(mounting), output_rate=RATE)
    return measure(truth, suite, seed=3)


class _Sink(Link):
    """Bytes the air side writes: what a recorder would log."""

    def __init__(self) -> None:
        self.data = bytearray()

    def write(self, data: bytes) -> None:
        self.data += data


def _bridged(truth, entry: Entry | None = None, values=None) -> dict[str, list]:
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


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("augmented")


def _augmented(entry: Entry, values, aircraft, folder: Path):
    """The contract flight on the Navion with ``entry`` written into its XML."""
    xml = augment("navion", [entry.build(values)], folder / entry.name)
    return fly(aircraft, [], model=load(str(xml)))


def inject(entry: Entry, values, truth, aircraft, folder=None) -> dict[str, np.ndarray | list]:
    """The data an entry changes, with it injected at ``values``: channel or link data."""
    if entry.acts_on is ActsOn.SENSOR:
        rec = _measure(truth, [entry.build(values)], channel=entry.channel)
    elif entry.acts_on in (ActsOn.MOUNTING, ActsOn.VIBRATION):
        rec = _measure(truth, mounting=[entry.build(values)])
    elif entry.acts_on is ActsOn.DISTURBANCE:
        rec = fly(aircraft, [entry.build(values)])
    elif entry.acts_on in (ActsOn.LINK, ActsOn.CLOCK):
        return _bridged(truth, entry, values)
    elif entry.acts_on in (ActsOn.AIRFRAME, ActsOn.ACTUATOR):
        rec = _augmented(entry, values, aircraft, folder)
    else:
        raise AssertionError(f"{entry.name}: the contract does not know how to inject an "
                             f"effect acting on {entry.acts_on}; extend inject()")
    return dict(rec.channels)


def baseline(entry: Entry, truth, aircraft):
    if entry.acts_on in (ActsOn.SENSOR, ActsOn.MOUNTING, ActsOn.VIBRATION):
        return dict(_measure(truth).channels)
    if entry.acts_on in (ActsOn.DISTURBANCE, ActsOn.AIRFRAME, ActsOn.ACTUATOR):
        return dict(truth.channels)
    return _bridged(truth)


def _same(a, b) -> bool:
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return False
    scale = max(float(np.nanmax(np.abs(b))) if b.size else 0.0, 1.0)
    return bool(np.allclose(a, b, rtol=0.0, atol=1e-12 * scale, equal_nan=True))


# -- the declaration -------------------------------------------------------------------------


def test_names_are_unique_and_reserved_places_are_empty():
    assert len(set(IDS)) == len(IDS)
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*", n) for n in IDS)
    assert not [e.name for e in ENTRIES if e.acts_on in RESERVED]
    # every place but the reserved ones has effects
    assert {e.acts_on for e in ENTRIES} == set(ActsOn) - RESERVED


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
def test_declaration_is_complete(entry: Entry):
    assert entry.description and "\n" not in entry.description and len(entry.description) < 120
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
    assert entry.changes
    if entry.acts_on in (ActsOn.LINK, ActsOn.CLOCK):
        assert set(entry.changes) <= set(LINK_DATA)
    else:
        assert all(c in CHANNELS for c in entry.changes), entry.changes
    if entry.acts_on is ActsOn.SENSOR:
        assert entry.channel in CHANNELS and entry.changes == (entry.channel,)
    assert entry.how()


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
def test_resolves_to_an_implementation_that_takes_its_parameters(entry: Entry):
    impl = entry.resolve()
    assert dataclasses.is_dataclass(impl), impl
    declared = {p.name for p in entry.parameters}
    fields = {f.name: f for f in dataclasses.fields(impl) if f.init}
    if isinstance(entry.implementation, Reference):
        mapping = entry.implementation.mapping()
        assert set(mapping) == declared
        assert set(mapping.values()) <= set(fields), f"{impl} lacks {set(mapping.values())}"
        impl_kwargs = entry.fields()
        assert set(impl_kwargs) == set(mapping.values())
    else:
        options = {o.name for o in entry.options}
        floats = {n for n in fields if n != "source" and n not in options}
        assert declared == floats, f"declared {sorted(declared)}, implemented {sorted(floats)}"
        assert options <= set(fields)
        assert CATALOGUE.of(impl) is entry
        for values in (entry.defaults(), entry.zeros()):
            assert entry.build(values).parameters() == pytest.approx(values)


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
def test_card_sections_resolve_the_name_to_this_entry(entry: Entry):
    sections = entry.sections()
    if entry.acts_on in (ActsOn.LINK, ActsOn.CLOCK):
        assert not sections
    else:
        assert sections
    for sec in sections:
        table = {sec.key: entry.name, **entry.defaults()}
        assert CATALOGUE.lookup_table(table, sec.name, "x") is entry
        assert CATALOGUE.from_dict(table, sec.name, "x") == entry.build()
    for sec in SECTIONS.values():
        if sec not in sections:
            with pytest.raises(ValueError, match=f"'x.{sec.key}'.*{entry.acts_on} effect"):
                CATALOGUE.lookup_table({sec.key: entry.name}, sec.name, "x")


def test_unknown_names_list_the_valid_ones():
    for sec in SECTIONS.values():
        valid = [e.name for e in ENTRIES if e.acts_on in sec.acts_on]
        with pytest.raises(ValueError, match=f"unknown {sec.label} 'nope'; known: "
                           + re.escape(", ".join(valid))):
            CATALOGUE.lookup("nope", sec.name, "x")


# -- injection -----------------------------------------------------------------------------


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
def test_default_magnitude_changes_the_data_where_declared(entry: Entry, truth, aircraft, folder):
    clean = baseline(entry, truth, aircraft)
    hit = inject(entry, entry.defaults(), truth, aircraft, folder)
    for c in entry.changes:
        assert not _same(hit[c], clean[c]), f"{entry.name} left {c} unchanged"
    if entry.acts_on in (ActsOn.SENSOR, ActsOn.MOUNTING, ActsOn.VIBRATION):
        untouched = [c for c in clean if c not in entry.changes and not _same(hit[c], clean[c])]
        assert not untouched, f"{entry.name} also changed {untouched}"


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
def test_zero_magnitude_leaves_the_data_unchanged(entry: Entry, truth, aircraft, folder):
    clean = baseline(entry, truth, aircraft)
    zero = inject(entry, entry.zeros(), truth, aircraft, folder)
    assert set(zero) == set(clean)
    changed = [c for c in clean if not _same(zero[c], clean[c])]
    assert not changed, f"{entry.name} at zero magnitude changed {changed}"


# -- who else names effects ---------------------------------------------------------------------


def test_compatibility_parameters_name_catalogue_entries():
    assert {"bias_q", "scale_ax", "upwash_alpha", "vane_beta_x", "delay_V"} <= set(
        CATALOGUE_EFFECTS)
    for effect, parameter in CATALOGUE_EFFECTS.values():
        CATALOGUE[effect].parameter(parameter)  # raises naming what is missing


def test_docs_list_every_entry_and_are_current():
    text = DOCS.read_text(encoding="utf-8")
    for name in IDS:
        assert f"| `{name}` |" in text, f"docs/effects.md does not list {name}"
    assert markdown_table() in text, ("docs/effects.md is out of date: paste the output of "
                                      "`flightid effects --format markdown`")


def test_the_effects_command_prints_the_catalogue():
    app = typer.Typer()
    app.command()(effects_command)
    runner = CliRunner()
    out = runner.invoke(app, ["--format", "json"], env={"COLUMNS": "200"})
    assert out.exit_code == 0, out.output
    assert json.loads(out.output) == listing()
    table = runner.invoke(app, ["--acts-on", "link"], env={"COLUMNS": "200"})
    assert table.exit_code == 0 and "[ch]" in table.output
    assert all(e.name in table.output for e in CATALOGUE.acting_on(ActsOn.LINK))
    assert "noise" not in table.output
