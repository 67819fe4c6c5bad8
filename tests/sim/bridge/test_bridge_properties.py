"""Property tests of the tlog decoder (hypothesis, deterministic): random bytes and
mutated real tlogs never raise anything but the documented errors (ValueError for a file
that cannot give a record, exit 2 on the command line), and a record that comes out has
only finite values and no channel interpolated across more than the allowed gap.
"""

import tempfile
from functools import cache
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from flightid.record import FlightRecord, RecordMeta
from flightid.sim.bridge.air.serve import BridgeConfig
from flightid.sim.bridge.frames import read_tlog
from flightid.sim.bridge.ground.gaps import MAX_GAP_SAMPLES, nominal_interval
from flightid.sim.bridge.ground.tlog import convert_tlog
from flightid.sim.bridge.ground.tlog_decode import decode_tlog
from flightid.sim.bridge.loopback import record_bridged

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True, database=None)


@cache
def real_tlog() -> bytes:
    """A real 3 s recording (50 Hz source, 115,200 baud, over a pty)."""
    t = np.arange(150) / 50.0
    ch = {"V": 30 + np.sin(t), "alpha": 0.05 + 0.02 * np.sin(3 * t), "q": 0.1 * np.cos(3 * t),
          "theta": 0.05 + 0.03 * np.sin(2 * t), "de": 0.05 * np.sign(np.sin(4 * t)),
          "ax": 0.5 * np.sin(t), "az": -9.8 + np.cos(t), "h": 300 + t}
    rec = FlightRecord(t, ch, RecordMeta(aircraft="synthetic", sample_rate=50.0))
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "real.tlog"
        record_bridged(rec, path, BridgeConfig(baud=115200))
        return path.read_bytes()


def _check(data: bytes) -> None:
    """Decode and convert ``data`` as a tlog: a record with finite values and no long
    interpolated gap, or a ValueError with a message."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "x.tlog"
        path.write_bytes(data)
        read_tlog(path)  # reading never fails on an existing file
        for segment in ("all", "longest"):
            try:
                rec = convert_tlog(path, segment=segment)
            except ValueError as exc:
                assert str(exc)
                continue
            assert len(rec) >= 2
            assert all(np.all(np.isfinite(v)) for v in rec.channels.values())
            series = decode_tlog(path).series
            for ch, gap in rec.meta.extra["bridge"]["resampling"]["max_gap_s"].items():
                t = max((s.t for (_, _, c), s in series.items() if c == ch), key=len)
                assert gap <= (MAX_GAP_SAMPLES + 1.5) * nominal_interval(t) + 1e-9, ch


@SETTINGS
@given(st.binary(max_size=3000))
def test_random_bytes(data):
    _check(data)


@SETTINGS
@given(st.lists(st.tuples(st.integers(0, 10**7), st.integers(1, 255)), max_size=60),
       st.integers(0, 10**7), st.integers(0, 3))
def test_mutated_real_tlog(flips, cut, splice):
    data = bytearray(real_tlog())
    for pos, x in flips:
        data[pos % len(data)] ^= x
    if splice:  # a stretch repeated (a joined file) or removed
        a = cut % len(data)
        b = min(len(data), a + 500 * splice)
        data = data[:b] + data[a:b] + data[b:] if splice % 2 else data[:a] + data[b:]
    elif cut % 3 == 0:
        data = data[: cut % len(data)]
    _check(bytes(data))
