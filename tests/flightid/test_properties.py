"""Property tests (hypothesis): random and mutated inputs to the card parser, the record
readers and the command line's argument checks never raise anything but the documented
errors (docs/errors.md: ValueError and its kind, CardError, for bad input), and whatever
they accept is valid. Derandomized with modest example counts: deterministic and fast."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flightid.cli import checks
from flightid.cli.identify import parse_options, parse_window
from flightid.record import FlightRecord, RecordMeta, read
from flightid.scenarios.cards import CardError, load_card

FAST = settings(max_examples=60, derandomize=True, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])

CARD = """name = "prop"
duration = 10.0
aircraft = "navion"
rate = 50.0
seed = 1

[condition]
altitude = 300.0
speed = 50.0

[[maneuver]]
kind = "doublet"
surface = "de"
start = 1.0
base = 0.5
amplitude_deg = 2.0

[sensors]
suite = "research"
"""


def scratch(suffix: str, data: bytes) -> Path:
    folder = Path(tempfile.mkdtemp(prefix="flightid-prop-"))
    path = folder / f"x{suffix}"
    path.write_bytes(data)
    return path


def mutate(data: bytes, edits: list[tuple[int, int]], cut: int | None) -> bytes:
    """Overwrite bytes at the given relative positions and optionally cut the end off."""
    b = bytearray(data)
    for where, value in edits:
        if b:
            b[where % len(b)] = value
    return bytes(b[: cut % (len(b) + 1)]) if cut is not None else bytes(b)


EDITS = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), max_size=12)


# -- flight cards ----------------------------------------------------------------------
@FAST
@given(text=st.text(max_size=300))
def test_random_card_text_is_a_card_error(text):
    path = scratch(".toml", text.encode("utf-8", errors="surrogatepass"))
    try:
        load_card(str(path))
    except CardError as exc:
        assert str(path) in str(exc)


@FAST
@given(edits=EDITS, cut=st.one_of(st.none(), st.integers(0, 10**4)))
def test_mutated_card_is_a_card_error_or_a_valid_card(edits, cut):
    path = scratch(".toml", mutate(CARD.encode(), edits, cut))
    try:
        card = load_card(str(path))
    except CardError as exc:
        assert str(path) in str(exc)
        return
    assert card.duration > 0 and card.rate > 0
    assert all(0 <= m.start < card.duration for m in card.maneuvers)


# -- record readers --------------------------------------------------------------------
@pytest.fixture(scope="module")
def record_files(tmp_path_factory) -> dict[str, bytes]:
    t = np.arange(200) * 0.02
    rng = np.random.default_rng(5)
    rec = FlightRecord(t, {c: rng.normal(0, 0.1, t.size) for c in ("p", "q", "r", "de")},
                       RecordMeta(aircraft="navion", sample_rate=50.0))
    folder = tmp_path_factory.mktemp("prop")
    return {s: rec.write(folder / f"r{s}").read_bytes() for s in (".parquet", ".csv")}


def assert_valid(rec: FlightRecord) -> None:
    assert np.all(np.isfinite(rec.time)) and np.all(np.diff(rec.time) > 0)
    assert all(np.all(np.isfinite(v)) for v in rec.channels.values())


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
@FAST
@given(edits=EDITS, cut=st.one_of(st.none(), st.integers(0, 10**5)))
def test_mutated_record_is_refused_or_valid(record_files, suffix, edits, cut):
    path = scratch(suffix, mutate(record_files[suffix], edits, cut))
    try:
        rec = read(path)
    except ValueError as exc:
        assert str(path) in str(exc)
        return
    assert_valid(rec)


@FAST
@given(data=st.binary(max_size=400), suffix=st.sampled_from([".parquet", ".csv", ".mat"]))
def test_random_bytes_are_refused(data, suffix):
    path = scratch(suffix, data)
    try:
        rec = read(path)
    except ValueError as exc:
        assert str(path) in str(exc)
        return
    assert_valid(rec)


@settings(max_examples=30, derandomize=True, deadline=None)
@given(rows=st.integers(0, 20), cols=st.integers(0, 100),
       fill=st.sampled_from([0.0, 1.0, math.nan, math.inf]),
       t_kind=st.sampled_from(["ok", "short", "reversed", "matrix"]))
def test_sidpac_shapes_are_refused_or_valid(rows, cols, fill, t_kind):
    fdata = np.full((rows, cols), fill)
    t = {"ok": np.arange(rows) * 0.1, "short": np.arange(max(rows - 1, 0)) * 0.1,
         "reversed": -np.arange(rows) * 0.1, "matrix": np.ones((2, 2))}[t_kind]
    path = scratch(".mat", b"")
    scipy.io.savemat(path, {"fdata": fdata, "t": t})
    try:
        rec = read(path)
    except ValueError as exc:
        assert str(path) in str(exc)
        return
    assert_valid(rec)


# -- argument checks -------------------------------------------------------------------
NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**9, 10**9))


@FAST
@given(value=NUMBERS, low=st.one_of(st.none(), st.floats(-1e6, 1e6)),
       high=st.one_of(st.none(), st.floats(-1e6, 1e6)))
def test_check_number(value, low, high):
    try:
        out = checks.check_number("--x", value, low=low, high=high)
    except ValueError as exc:
        assert "--x" in str(exc)
        return
    assert math.isfinite(out)
    assert (low is None or out >= low) and (high is None or out <= high)


@FAST
@given(rate=NUMBERS, duration=st.one_of(st.none(), st.floats(0, 1e5)))
def test_check_rate(rate, duration):
    try:
        out = checks.check_rate("--rate", rate, duration)
    except ValueError as exc:
        assert "--rate" in str(exc)
        return
    assert 0 < out <= checks.MAX_RATE_HZ
    assert duration is None or duration * out + 1 >= checks.MIN_SAMPLES


@FAST
@given(f_min=st.one_of(st.none(), NUMBERS), f_max=st.one_of(st.none(), NUMBERS),
       dt=st.floats(1e-4, 1.0))
def test_check_frequency_band(f_min, f_max, dt):
    try:
        lo, hi = checks.check_frequency_band(f_min, f_max, dt)
    except ValueError as exc:
        assert "--f-m" in str(exc)
        return
    for f in (lo, hi):
        assert f is None or 0 < f <= 0.5 / dt
    assert lo is None or hi is None or lo < hi


@FAST
@given(text=st.text(max_size=30))
def test_check_udp(text):
    try:
        host, port = checks.check_udp("--udp", text)
    except ValueError as exc:
        assert "--udp" in str(exc)
        return
    assert 1 <= port <= 65535 and text.endswith(str(port))


@FAST
@given(baud=st.integers(-10**7, 10**7))
def test_check_baud(baud):
    try:
        out = checks.check_baud("--baud", baud)
    except ValueError as exc:
        assert "--baud" in str(exc)
        return
    assert out == 0 or out in checks.BAUDS


@FAST
@given(texts=st.lists(st.text(max_size=20), max_size=4),
       method=st.sampled_from(["ee", "oe", "fdee", "fr", "xx"]))
def test_method_options(texts, method):
    try:
        checks.read_options(method, parse_options(texts))
    except ValueError as exc:
        assert str(exc)


@FAST
@given(text=st.text(max_size=20))
def test_parse_window(text):
    try:
        out = parse_window(text)
    except ValueError as exc:
        assert "--window" in str(exc)
        return
    assert out in ("auto", "none") or (math.isfinite(out[0]) and out[0] < out[1])
