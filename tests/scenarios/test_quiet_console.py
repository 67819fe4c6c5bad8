"""JSBSim's console output stays silent: nothing on the process's stdout or stderr while a
card is flown, and ``flightid simulate`` prints only its own line on stdout."""

from __future__ import annotations

import subprocess
import sys

from flightid.scenarios.cards import fly_card, load_card


def test_flying_a_card_prints_nothing(capfd):
    # capfd reads the file descriptors, where JSBSim's C++ output would go
    fly_card(load_card("telemaster-elevator-doublet"), seed=2)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_simulate_prints_only_its_result_on_stdout(tmp_path):
    out = subprocess.run([sys.executable, "-m", "flightid.cli.app", "simulate",
                          "twinotter-lateral-0alpha", "-o", str(tmp_path / "f.parquet")],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == [out.stdout.strip()]
    assert out.stdout.startswith("wrote ")
    assert "JSBSim" not in out.stderr
