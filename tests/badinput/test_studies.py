"""Every study validated before it flies (issue 38): method, model, options, seed and one
realization's trim are checked before study.json is written; damaged study files are
named; an unreachable Dask scheduler is refused naming its address."""

from __future__ import annotations

import socket

import pytest

from flightid.scenarios.montecarlo import store


def test_negative_seed_names_the_option_and_writes_nothing(cli, card_path, tmp_path):
    study = tmp_path / "study"
    cli(["montecarlo", card_path, "-n", "2", "-o", study, "--seed", "-1", "--quiet"], 2,
        "--seed must be 0..4294967295, got -1")
    assert not study.exists()


@pytest.mark.parametrize(("args", "expected"), [
    (["--method", "zz"], "--method 'zz' is not accepted; use one of ee, swr, oe"),
    (["--model", "zz"], "--model: model 'zz' is not a model of method oe; use auto, lateral"),
    (["--option", "zz=1"], "--option: unknown option(s) zz for method oe"),
])
def test_design_compare_names_the_option_and_what_is_allowed(cli, card_path, tmp_path, args,
                                                             expected):
    study = tmp_path / "dc"
    cli(["design-compare", "--card", card_path, "-n", "2", "-o", study, "--quiet", *args], 2,
        expected)
    assert not study.exists()


def test_a_card_that_cannot_trim_fails_before_the_study(cli, tmp_path):
    card = tmp_path / "slow.toml"
    card.write_text('name = "slow"\nduration = 5.0\naircraft = "navion"\nrate = 20.0\n\n'
                    "[condition]\naltitude = 300.0\nspeed = 12.0\n")
    study = tmp_path / "study"
    cli(["montecarlo", card, "-n", "3", "-o", study, "--quiet"], 3, "cannot trim",
        "below stall")
    assert not study.exists()


def test_damaged_study_files_are_named(cli, tmp_path):
    study = tmp_path / "study"
    (study / store.RESULTS).mkdir(parents=True)
    (study / store.DESCRIPTION).write_text('{"identity": {"card": ')
    cli(["montecarlo-report", study], 2, f"{study / store.DESCRIPTION}: a damaged study")
    (study / store.DESCRIPTION).write_text(
        '{"identity": {}, "description": {"card": "x", "n": 1, "method": "oe", '
        '"model": "lat"}}\n')
    bad = store.result_path(study, 0)
    bad.write_bytes(b"PAR1 truncated")
    cli(["montecarlo-report", study], 2, f"{bad}: a damaged realization result")


def test_unreachable_dask_scheduler_names_the_address(cli, card_path, tmp_path):
    with socket.socket() as s:  # a free port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    study = tmp_path / "study"
    cli(["montecarlo", card_path, "-n", "2", "-o", study, "--dask", address, "--quiet"], 2,
        f"--dask {address}: no Dask scheduler answered within 5 s")
    assert not study.exists()
