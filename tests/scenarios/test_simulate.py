"""`flightid simulate`: library listing, records, truth and plot files, clear errors."""

from __future__ import annotations

import numpy as np
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.record import read
from flightid.scenarios.simulate import plot_record, simulate

runner = CliRunner()


def test_list_shows_library_cards_with_descriptions():
    result = runner.invoke(app, ["simulate", "--list"])
    assert result.exit_code == 0, result.output
    line = next(s for s in result.output.splitlines() if s.startswith("navion-demo"))
    assert "3211" in line and "53.64" in line


def test_simulate_writes_measured_truth_and_plot(tmp_path):
    out, truth, png = tmp_path / "f.parquet", tmp_path / "t.csv", tmp_path / "f.png"
    result = runner.invoke(app, ["simulate", "telemaster-elevator-doublet", "-o", str(out),
                                 "--truth", str(truth), "--plot", str(png), "--seed", "4"])
    assert result.exit_code == 0, result.output
    measured, exact = read(out), read(truth)
    assert measured.meta.scenario["seed"] == 4
    assert measured.meta.scenario["card"]["aircraft"] == "telemaster"
    assert measured.meta.sample_rate == 100.0  # the hobby suite's output rate
    assert exact.time[-1] == 8.0 and "turb_w" in exact
    # the measured pitch rate follows the truth within the hobby gyro errors: 0.5 deg/s
    # bias, 1.2 deg/s noise (Sofyan Table 8-6; 3 sigma 3.6) and the engine vibration
    # (2 deg/s at the rotation frequency, 1 deg/s at its harmonic and blade passing: 4)
    q_truth = np.interp(measured.time, exact.time, exact["q"])
    assert np.max(np.abs(measured["q"] - q_truth)) < np.radians(0.5 + 3.6 + 4.0)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_simulate_reports_a_bad_card_with_its_line(tmp_path):
    card = tmp_path / "bad.toml"
    card.write_text('aircraft = "navion"\nduration = 5.0\n[condition]\naltitude = 0\n'
                    'speed = "fast"\n', encoding="utf-8")
    result = runner.invoke(app, ["simulate", str(card), "-o", str(tmp_path / "x.parquet")])
    assert result.exit_code == 2
    assert f"{card}:5" in result.output and "condition.speed" in result.output


def test_same_seed_same_file_through_the_runner(tmp_path):
    a = simulate("twinotter-lateral-0alpha", tmp_path / "a.csv", seed=9)[0]
    b = simulate("twinotter-lateral-0alpha", tmp_path / "b.csv", seed=9)[0]
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    plot_record(a, tmp_path / "p.png", title="x")
    assert np.array_equal(a["p"], b["p"])
