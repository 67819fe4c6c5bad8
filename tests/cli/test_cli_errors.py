"""Bad input on the command line ends in one line naming the cause and exit code 2."""

import subprocess
import sys

import pytest

from tests.conftest import TWIN_OTTER


@pytest.mark.parametrize("args, expected", [
    (["identify", "no/such/flight.parquet"], "no/such/flight.parquet: no such file"),
    (["identify", str(TWIN_OTTER), "--method", "xx"], "--method 'xx' is not accepted"),
    (["identify", str(TWIN_OTTER), "--method", "oe", "--option", "foo=1"],
     "unknown option(s) foo for method oe; valid: derivatives"),
    (["frequency-response", str(TWIN_OTTER), "--input", "zz", "--output", "q"],
     "record has no channel 'zz'"),
    (["truth", "navion", "--altitude", "-5", "--speed", "50"], "altitude must be >= 0 m"),
    (["trim", "nosuch", "--altitude", "0", "--speed", "50"], "unknown aircraft 'nosuch'"),
])
def test_bad_input_is_one_clear_line(tmp_path, args, expected):
    out = subprocess.run([sys.executable, "-m", "flightid.cli.app", *args],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert out.returncode == 2, (out.stdout, out.stderr)
    assert expected in out.stderr
    assert "Traceback" not in out.stderr


def test_corrupt_parquet_is_named(tmp_path):
    bad = tmp_path / "bad.parquet"
    bad.write_text("not a parquet file")
    out = subprocess.run([sys.executable, "-m", "flightid.cli.app", "identify", str(bad)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "bad.parquet" in out.stderr and "Traceback" not in out.stderr
