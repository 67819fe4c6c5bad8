"""Input-design experiments (flightid design-compare): designs made comparable at equal
amplitude or equal energy, their cards, and a small Monte Carlo on the Navion elevator in
which the 3211 beats the doublet of equal amplitude where that is clear with n = 6."""

from __future__ import annotations

import io
import json
import math
import re
import tomllib

import numpy as np
import pandas as pd
import pytest
from rich.console import Console
from scipy import stats
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.cli.tables import split_tables
from flightid.scenarios import montecarlo
from flightid.scenarios.cards import CardError, card_from_dict, load_card, load_maneuvers
from flightid.scenarios.inputs import Maneuvers
from flightid.scenarios.montecarlo import store
from flightid.scenarios.montecarlo.design import comparison, experiment
from flightid.scenarios.montecarlo.design import report as design_report
from flightid.scenarios.montecarlo.intervals import interval_text
from flightid.scenarios.montecarlo.summary import summarize
from flightid.units import DEG

RATE = 100.0


def test_equal_amplitude_designs_share_the_peak_and_multisteps_scale_energy_by_length():
    built = experiment.equalized_designs(experiment.DESIGNS, experiment.DesignSettings(),
                                         "amplitude", RATE)
    amplitude = experiment.DesignSettings().amplitude
    for kind, d in built.items():
        # the multisine's peak is set on a 64-per-cycle grid, so 100 Hz sampling can miss
        # its crest by a little; the sweep's crest likewise
        assert experiment.peak(d, RATE) == pytest.approx(amplitude, rel=2e-3), kind
    e = {k: experiment.input_energy(d, RATE) for k, d in built.items()}
    # full-amplitude pulses of 2, 4 and 7 base times (doublet, 2-1-1, 3211): energy a^2 T
    base = experiment.DesignSettings().base
    for kind, units in (("doublet", 2), ("211", 4), ("3211", 7)):
        assert e[kind] == pytest.approx(amplitude**2 * units * base, rel=0.02), kind


def test_equal_energy_designs_have_the_reference_energy():
    built = experiment.equalized_designs(experiment.DESIGNS, experiment.DesignSettings(),
                                         "energy", RATE, reference="3211")
    target = experiment.input_energy(built["3211"], RATE)
    for kind, d in built.items():
        assert experiment.input_energy(d, RATE) == pytest.approx(target, rel=1e-5), kind
    # the doublet needs sqrt(7/2) times the 3211's amplitude to carry the same energy
    ratio = experiment.peak(built["doublet"], RATE) / experiment.peak(built["3211"], RATE)
    assert ratio == pytest.approx(math.sqrt(7 / 2), rel=0.02)
    with pytest.raises(ValueError, match="equal must be one of"):
        experiment.equalized_designs(("3211",), experiment.DesignSettings(), "power", RATE)


def test_design_cards_round_trip_through_toml():
    base = load_card("navion-demo")
    for kind in experiment.DESIGNS:
        d = experiment.make_design(kind)
        data = experiment.design_card(base.to_dict(), kind, d, base.rate)
        text = experiment.card_text(data)
        card = card_from_dict(tomllib.loads(text), f"{kind}.toml", text)
        assert len(card.maneuvers) == 1 and card.maneuvers[0] == d
        assert card.duration == pytest.approx(d.end + experiment.SETTLE_S)
        assert card.sensors is not None and card.disturbances and card.a_priori
    with pytest.raises(ValueError, match="unknown design 'chirp'"):
        experiment.make_design("chirp")


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """design-compare on the Navion elevator, doublet and 3211, n = 6, via the CLI."""
    folder = tmp_path_factory.mktemp("dc") / "study"
    result = CliRunner().invoke(app, [
        "design-compare", "-n", "6", "-o", str(folder), "--design", "doublet",
        "--design", "3211", "--workers", "2", "--quiet", "--format", "json"])
    assert result.exit_code == 0, result.output
    return folder, json.loads(result.output)


def test_3211_beats_a_doublet_of_equal_amplitude(small):
    folder, doc = small
    assert (folder / "design-compare.png").exists()
    assert "data:image/png;base64," in (folder / "design-compare.html").read_text()
    table = pd.read_csv(folder / "design-compare.csv")
    assert set(table["design"]) == {"doublet", "3211"}
    # the same rows as Markdown and LaTeX for a paper, beside the HTML
    markdown = (folder / "design-compare.md").read_text()
    latex = (folder / "design-compare.tex").read_text()
    assert markdown.count("\n| ") >= len(table) and "\\begin{tabular}" in latex
    assert f"{table['scatter'].dropna().iloc[0]:.4g}" in markdown and "Cm\\_alpha" in latex
    assert doc["equal"] == "amplitude" and doc["model"] == "lon"
    by = {d["kind"]: d for d in doc["designs"]}
    for d in by.values():
        assert d["summary"]["realizations"] == 6
        # a doublet on an 11 s record in light turbulence fails to converge in about
        # 1 of 8 realizations (6 of 50 in the n = 50 study): failures are counted, not
        # dropped, and at least 4 of 6 must estimate
        assert d["summary"]["failures"] <= 2
        assert d["peak"] == pytest.approx(3 * DEG, rel=1e-6)
    # the same realization seeds for both designs
    seeds = {k: montecarlo.load(folder / k).groupby("index")["seed"].first().tolist()
             for k in by}
    assert seeds["doublet"] == seeds["3211"] and len(set(seeds["3211"])) == 6
    doublet = {r["name"]: r for r in by["doublet"]["summary"]["rows"]}
    three = {r["name"]: r for r in by["3211"]["summary"]["rows"]}
    assert set(doublet) == set(three) and len(doublet) >= 5
    # The mean Cramer-Rao bound hardly varies between realizations, so n = 6 pins it: at
    # equal amplitude and base the 3211 carries 3.5 times the doublet's energy with a
    # broader spectrum, and its bound is smaller for every derivative (by 1/sqrt(3.5) =
    # 0.53 if the information grew with energy alone; measured 0.35-0.72 at n = 50).
    for name in doublet:
        assert three[name]["mean_bound"] < 0.85 * doublet[name]["mean_bound"], name
    # The scatter is random: with n = 6 the log of a sample standard deviation has a
    # standard deviation of about 1/sqrt(2 (n - 1)) = 0.32, so the log of a ratio of two
    # about 0.45, and the mean over the derivatives (correlated, so not divided by sqrt
    # of their number) at most 0.45. The expected mean log ratio is about log(0.5) =
    # -0.69 (1.5 of those sigmas); assert only that the 3211 is better on the whole.
    logs = [math.log(three[n]["scatter"] / doublet[n]["scatter"]) for n in doublet]
    assert float(np.mean(logs)) < 0.0, logs
    verdict = doc["3211_beats_doublet"]
    assert verdict["derivatives"] == verdict["of"] == len(doublet)


def test_tables_keep_every_digit_at_80_columns(small):
    """The rerun continues the stored study (nothing flies) and prints its tables in an
    80-column terminal: every number of the JSON output appears whole, none cut by an
    ellipsis, and the verdict counts the derivatives both designs estimated."""
    folder, doc = small
    result = CliRunner().invoke(app, [
        "design-compare", "-n", "6", "-o", str(folder), "--design", "doublet",
        "--design", "3211", "--workers", "1", "--quiet"], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    out = result.output
    assert "…" not in out
    assert max(len(line) for line in out.splitlines() if not line.startswith("wrote")) <= 80
    cells = [c.strip(" *") for line in out.splitlines() for c in line.split("│")]
    for d in doc["designs"]:
        for r in d["summary"]["rows"]:
            assert f"{r['scatter']:.4g}" in cells or f"{r['scatter']:.4g}*" in [
                c.strip() for line in out.splitlines() for c in line.split("│")], r
            assert f"{r['mean_bound']:.4g}" in cells, r
    verdict = doc["3211_beats_doublet"]
    for name, r in verdict["ratios"].items():
        assert interval_text(r["low"], r["high"]) in cells, name
    wins = len(verdict["3211_smaller_scatter"])
    assert (f"3211 smaller scatter than the doublet for {wins} of {verdict['derivatives']} "
            "derivatives estimated by both") in " ".join(out.split())


def test_command_line_refuses_bad_settings_with_exit_2(tmp_path):
    for args, message in (((["--equal", "power"]), "--equal 'power' is not accepted; use one of"),
                          (["--design", "chirp"], "--design 'chirp' is not accepted"),
                          (["--amplitude-deg", "0"], "--amplitude-deg must be > 0")):
        result = CliRunner().invoke(app, ["design-compare", "-n", "2", "-o",
                                          str(tmp_path / "s"), "--quiet", *args])
        assert result.exit_code == 2, result.output
        assert message in result.output


def _comparison_of(scatters: dict[str, dict[str, float | None]], n: int = 20
                   ) -> comparison.Comparison:
    """A Comparison of designs whose rows have exactly the given scatters (None: the
    derivative found unidentifiable by that design), from errors z * scatter with z
    fixed-seed normal draws standardized to sample standard deviation 1."""
    truth = {"Cm_alpha": -0.683, "CY_r": 0.0, "Cn_r": -0.125}
    z = np.random.default_rng(7).normal(size=n)
    z = (z - z.mean()) / z.std(ddof=1)
    out = comparison.Comparison("navion-demo", "navion", "oe", "lat", n, "amplitude", "3211",
                            experiment.DesignSettings())
    for kind, by_name in scatters.items():
        rows = []
        for name, s in by_name.items():
            for i in range(n):
                rows.append({"index": i, "seed": i, "name": name, "truth": truth[name],
                             "estimate": truth[name] + (z[i] * s if s else math.nan),
                             "std": s or math.nan, "error": z[i] * s if s else math.nan,
                             "sigmas": z[i] if s else math.nan,
                             "status": "estimated" if s else "unidentifiable",
                             "reason": ""})
        summary = summarize(store.frame(rows))
        out.results.append(comparison.DesignResult(kind, 12.0, 2.8, 0.007, 3 * DEG, summary,
                                               kind))
    return out


def test_verdict_counts_only_derivatives_both_estimated_and_claims_only_clear_ratios():
    comparison = _comparison_of({"doublet": {"Cm_alpha": 0.2, "CY_r": 0.010, "Cn_r": None},
                                 "3211": {"Cm_alpha": 0.05, "CY_r": 0.009, "Cn_r": 0.02}})
    verdict = comparison.verdict("3211", "doublet")
    # three derivatives in the study, two estimated by both
    assert verdict["of"] == 3 and verdict["derivatives"] == 2
    # 0.25 at n = 20 is clear (90 % interval 0.170-0.368); 0.9 is not (0.611-1.325)
    assert verdict["3211_smaller_scatter"] == ["Cm_alpha"]
    assert verdict["undecided"] == ["CY_r"] and verdict["doublet_smaller_scatter"] == []
    r = verdict["ratios"]["CY_r"]
    assert r["ratio"] == pytest.approx(0.9, rel=1e-9)
    assert (r["low"], r["high"]) == pytest.approx(
        (0.9 / math.sqrt(stats.f.ppf(0.95, 19, 19)), 0.9 / math.sqrt(stats.f.ppf(0.05, 19, 19))),
        rel=1e-9)
    assert verdict["ratios"]["Cm_alpha"]["high"] == pytest.approx(0.25 * 1.4726, rel=1e-3)
    assert comparison.best() == {"CY_r": "", "Cm_alpha": "3211", "Cn_r": ""}
    # the figure keeps CY_r (truth 0): its bars are its scatters in its own unit
    ax = design_report.figure(comparison).axes[0]
    heights = sorted(round(p.get_height(), 6) for p in ax.patches
                     if np.isfinite(p.get_height()))  # (the doublet's Cn_r: NaN, no bar)
    assert heights == sorted([0.2, 0.010, 0.05, 0.009, 0.02])
    assert "CY_r\n[1]" in [t.get_text() for t in ax.get_xticklabels()]
    assert "derivative's unit" in ax.get_ylabel()


OWN = """name = "ail-rud"
description = "aileron 3211 with a 0.3 s base, then a rudder doublet"

[[maneuver]]
kind = "3211"
surface = "da"
start = 2.0
base = 0.3
amplitude_deg = 4

[[maneuver]]
kind = "doublet"
surface = "dr"
start = 5.0
base = 0.5
amplitude_deg = 3
"""


def test_a_maneuver_table_is_one_design_on_several_surfaces_scaled_like_the_builtins(
        tmp_path):
    (tmp_path / "own.toml").write_text(OWN)
    name, parts = load_maneuvers(tmp_path / "own.toml")
    own = Maneuvers(parts=parts)
    assert name == "ail-rud" and own.surfaces() == ("da", "dr")
    assert (own.start, own.end) == (2.0, 6.0)  # the doublet ends at 5 + 2 x 0.5 s
    t = np.arange(0, 8, 1 / RATE)
    u = own.signals(t)
    assert u["da"].max() == pytest.approx(4 * DEG) and u["dr"].max() == pytest.approx(3 * DEG)
    settings = experiment.DesignSettings(surface="da")
    built = experiment.equalized_designs(("3211",), settings, "amplitude", RATE, own={name: own})
    # equal amplitude: the largest |u| of any surface is the settings' 3 deg, the rudder
    # keeping its 3/4 of the aileron
    scaled = built[name].signals(t)
    assert experiment.peak(built[name], RATE) == pytest.approx(3 * DEG, rel=1e-9)
    assert scaled["dr"].max() == pytest.approx(3 * DEG * 3 / 4, rel=1e-9)
    # energy summed over both surfaces: 4, 2+2 (and 7 x 0.3, 2 x 0.5) s at full amplitude
    a = 3 * DEG
    assert experiment.input_energy(built[name], RATE) == pytest.approx(
        a**2 * 7 * 0.3 + (0.75 * a) ** 2 * 2 * 0.5, rel=0.02)
    energy = experiment.equalized_designs(("3211",), settings, "energy", RATE, reference=name,
                                      own={name: own})
    target = experiment.input_energy(built[name], RATE)
    for k, d in energy.items():
        assert experiment.input_energy(d, RATE) == pytest.approx(target, rel=1e-5), k
    assert len(experiment.maneuver_dicts(energy[name])) == 2


def test_a_bad_maneuver_table_is_refused_naming_file_line_and_field(tmp_path):
    bad = tmp_path / "bad.toml"
    for text, message in (
            (OWN.replace('kind = "doublet"', 'kind = "chirp"'),
             r"bad.toml:12: field 'maneuver\[1\].kind': unknown input kind 'chirp'"),
            ('name = "x"\n', "at least one \\[\\[maneuver\\]\\]"),
            ("duration = 10\n" + OWN, "field 'duration': unknown field in a maneuver table"),
            (OWN.replace('"ail-rud"', '"3211"'), None)):
        bad.write_text(text)
        if message is None:  # a built-in's name: refused by the command line, exit 2
            result = CliRunner().invoke(app, ["design-compare", "-n", "1", "-o",
                                              str(tmp_path / "s"), "--design-file", str(bad)])
            assert result.exit_code == 2 and "is a built-in design's" in result.output
            continue
        with pytest.raises(CardError, match=message):
            load_maneuvers(bad)
    result = CliRunner().invoke(app, ["design-compare", "-n", "1", "-o", str(tmp_path / "s"),
                                      "--multisine-band", "0.5", "0.4"])
    assert result.exit_code == 2 and "--multisine-band F_MAX must be > 0.5" in result.output
    assert not (tmp_path / "s").exists()


def test_own_design_runs_end_to_end_at_its_own_energy_with_a_set_multisine_band(tmp_path):
    (tmp_path / "own.toml").write_text(OWN)
    folder = tmp_path / "study"
    result = CliRunner().invoke(app, [
        "design-compare", "-n", "2", "-o", str(folder), "--model", "lat", "--surface",
        "da", "--design", "multisine", "--multisine-band", "0.3", "1.5", "--design-file",
        str(tmp_path / "own.toml"), "--equal", "energy", "--reference", "ail-rud",
        "--workers", "2", "--quiet", "--format", "json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    by = {d["kind"]: d for d in doc["designs"]}
    assert list(by) == ["multisine", "ail-rud"]
    assert by["multisine"]["energy"] == pytest.approx(by["ail-rud"]["energy"], rel=1e-5)
    assert [m["surface"] for m in by["ail-rud"]["maneuvers"]] == ["da", "dr"]
    flown = load_card(folder / "cards" / "multisine.toml").maneuvers[0]
    assert (flown.f_min, flown.f_max) == (0.3, 1.5)
    assert len(load_card(folder / "cards" / "ail-rud.toml").maneuvers) == 2
    # the rudder moves only in the own design: it alone estimates the rudder derivatives
    own_rows = {r["name"]: r for r in by["ail-rud"]["summary"]["rows"]}
    ms_rows = {r["name"]: r for r in by["multisine"]["summary"]["rows"]}
    assert own_rows["Cn_dr"]["estimated"] == 2 and "Cn_dr" not in ms_rows or \
        ms_rows["Cn_dr"]["estimated"] == 0
    assert (folder / "design-compare.png").exists()


def test_a_comparison_of_many_designs_splits_into_tables_that_fit_80_columns():
    """Six designs with 9-digit cells (five built-ins and a user's) do not fit one
    80-column table: they are split by design, each part repeating the derivative
    column, no cell folded onto a second line and no header broken."""
    kinds = ["doublet", "211", "3211", "sweep", "multisine", "ail-rud-own"]
    rows = [[name, *(f"{0.0009408 * (i + 1) * (j + 1):.4g}" for j in range(len(kinds)))]
            for i, name in enumerate(("CY_beta", "Cl_da", "Cn_beta"))]
    tables = split_tables("scatter by design", ["derivative", *kinds], rows, 80)
    assert len(tables) == 2
    buffer = io.StringIO()
    console = Console(file=buffer, width=80)
    for t in tables:
        console.print(t)
    text = buffer.getvalue()
    assert "…" not in text and max(len(line) for line in text.splitlines()) <= 80
    cells = [c.strip() for line in text.splitlines() for c in re.split("[│┃]", line)]
    assert cells.count("derivative") == 2 and cells.count("Cl_da") == 2
    assert {c for r in rows for c in r} <= set(cells)
    assert set(kinds) <= set(cells)
    # narrow enough, one table
    assert len(split_tables("t", ["derivative", *kinds[:3]], [r[:4] for r in rows], 80)) == 1
