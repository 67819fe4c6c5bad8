"""The flight record: validation, slicing and a lossless Parquet/CSV round trip."""

import numpy as np
import pytest

from flightid.record import FlightRecord, RecordMeta, Reference, read


def _record(seed: int = 3) -> FlightRecord:
    rng = np.random.default_rng(seed)
    t = np.arange(0, 5, 0.02)
    channels = {
        "alpha": 0.05 + 0.01 * rng.standard_normal(t.size),
        "q": np.sin(2 * np.pi * 0.7 * t) * 0.1,
        "de": np.where((t > 1) & (t < 2), -0.05, 0.0),
        "V": 53.64 + rng.standard_normal(t.size) * 1e-9,  # digits a text format must keep
    }
    meta = RecordMeta(
        aircraft="navion",
        condition={"altitude_m": 0.0, "speed_m_s": 53.64},
        sample_rate=50.0,
        provenance="test",
        scenario={"card": "none", "seed": seed},
        reference=Reference(area=17.09, span=10.18, chord=1.74),
    )
    return FlightRecord(t, channels, meta)


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
@pytest.mark.parametrize("seed", [3, 11])
def test_round_trip_is_bit_exact(tmp_path, suffix, seed):
    rec = _record(seed)
    back = read(rec.write(tmp_path / f"flight{suffix}"))
    np.testing.assert_array_equal(back.time, rec.time)
    assert set(back.channels) == set(rec.channels)
    for name in rec.channels:
        np.testing.assert_array_equal(back[name], rec[name])
    assert back.meta == rec.meta


def test_unknown_channel_needs_a_unit():
    t = np.arange(3.0)
    with pytest.raises(ValueError, match="'strain'.*not canonical"):
        FlightRecord(t, {"strain": t})
    rec = FlightRecord(t, {"strain": t}, RecordMeta(units={"strain": "-"}))
    assert rec.unit("strain") == "-"
    assert rec.unit("alpha" if "alpha" in rec else "q") == "rad/s"


def test_bad_shapes_and_time_are_named():
    with pytest.raises(ValueError, match="channel 'q' has"):
        FlightRecord(np.arange(3.0), {"q": np.zeros(4)})
    with pytest.raises(ValueError, match="between samples 1 and 2"):
        FlightRecord(np.array([0.0, 1.0, 1.0]), {})


def test_missing_channel_lists_what_exists():
    with pytest.raises(KeyError, match="has no channel 'p'.*alpha"):
        _record()["p"]


def test_slice_keeps_metadata():
    part = _record().slice(1.0, 2.0)
    assert part.time[0] >= 1.0 and part.time[-1] <= 2.0
    assert part.meta.aircraft == "navion"
    with pytest.raises(ValueError, match="no samples"):
        _record().slice(10, 11)


def test_unknown_format_is_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown record format '.txt'"):
        _record().write(tmp_path / "x.txt")
