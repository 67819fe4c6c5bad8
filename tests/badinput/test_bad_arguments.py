"""Every argument is checked before any work starts: exit 2 and a message saying what was
wrong and what is accepted (docs/errors.md)."""

from __future__ import annotations

import pytest

from flightid.cli import checks

CARD = """name = "{name}"
duration = {duration}
aircraft = "navion"
rate = {rate}

[condition]
altitude = 300.0
speed = 50.0
"""


@pytest.mark.parametrize("extra, expected", [
    (["--f-min", "5", "--f-max", "1"], "--f-min 5 Hz must be below --f-max 1 Hz"),
    (["--f-max", "100"], "above the Nyquist frequency 25 Hz"),
    (["--f-min", "30"], "--f-min 30 Hz is above the Nyquist frequency"),
    (["--f-min", "-1"], "--f-min must be > 0 Hz"),
    (["--f-max", "nan"], "--f-max must be a finite number"),
    (["--window", "-1"], "--window must be > 0 s"),
    (["--window", "60"], "--window 60 s is longer than the record"),
    (["--plot", "bode.xml"], "unknown format '.xml'"),
    (["--condition-on", "zz"], "record has no channel 'zz'"),
])
def test_frequency_response_arguments(cli, flight_file, extra, expected):
    cli(["frequency-response", flight_file, "--input", "de", "--output", "q", *extra], 2,
        expected)


@pytest.mark.parametrize("extra, expected", [
    (["--method", "ee", "--option", "colored=maybe"], "accepted values: true or false"),
    (["--method", "ee", "--option", "foo=1"], "unknown option(s) foo for method ee"),
    (["--method", "oe", "--option", "max_iterations=abc"], "max_iterations"),
    (["--option", "colored"], "expected KEY=VALUE"),
    (["--format", "xml"], "--format 'xml' is not accepted; use one of table, json"),
    (["--method", "xx"], "--method 'xx' is not accepted; use one of ee"),
    (["--window", "5,2"], "START < END"),
    (["--window", "nan,3"], "must be finite"),
    (["--window", "abc"], "--window must be auto, none or START,END"),
    (["--model", "nonsense"], "nonsense"),
])
def test_identify_arguments(cli, flight_file, extra, expected):
    cli(["identify", flight_file, *extra], 2, expected)


@pytest.mark.parametrize("args, expected", [
    (["methods", "--format", "xml"], "use one of table, json"),
    (["methods", "nosuch"], "unknown method 'nosuch'"),
    (["trim", "navion", "--altitude", "300", "--speed", "50", "--format", "xml"],
     "--format 'xml' is not accepted; use one of table, json"),
    (["truth", "navion", "--altitude", "300", "--speed", "50", "--axes", "wind"],
     "unknown axes 'wind'"),
    (["trim", "navion", "--altitude", "nan", "--speed", "50"], "finite"),
    (["trim", "navion", "--altitude", "1e9", "--speed", "50"], "absurd"),
    (["trim", "navion", "--altitude", "300", "--speed", "-5"], "speed"),
    (["trim", "navion", "--altitude", "300", "--speed", "fast"], "--speed"),  # typer usage
    (["effects", "--format", "xml"], "use one of table, json, markdown"),
    (["effects", "--acts-on", "nothing"], "unknown 'nothing'"),
    (["identify", "x.parquet", "--no-such-option"], "no such option"),  # typer usage
    (["simulate", "navion-demo"], "give a CARD and -o/--output"),
    (["simulate", "navion-demo", "-o", "out.xml"], "unknown format '.xml'"),
    (["simulate", "navion-demo", "-o", "out.parquet", "--plot", "p.txt"],
     "unknown format '.txt'"),
    (["simulate", "navion-demo", "-o", "out.parquet", "--seed", "-1"], "--seed must be"),
    (["montecarlo", "navion-demo", "-n", "-3", "-o", "mc"], "-n must be 1..1000000, got -3"),
])
def test_other_command_arguments(cli, tmp_path, monkeypatch, args, expected):
    monkeypatch.chdir(tmp_path)
    cli(args, 2, expected)


@pytest.mark.parametrize("rate, duration, expected", [
    ("1e6", "50.0", "rate must be <= 10000 Hz"),  # the 5.6 GB conversion
    ("0.01", "50.0", "gives 1 sample(s) over 50 s"),  # the one-sample record
    ("5000.0", "3600.0", "would write about"),  # under the rate cap, over the size limit
])
def test_simulate_rates_and_size_refused_before_flying(cli, tmp_path, existing, rate,
                                                       duration, expected):
    card = tmp_path / "card.toml"
    card.write_text(CARD.format(name="big", duration=duration, rate=rate))
    result = cli(["simulate", card, "-o", existing], 2, expected, protect=[existing])
    if "would write" in expected:
        assert "--force" in result.output


@pytest.mark.parametrize("call, expected", [
    (lambda: checks.check_port("--udp", 99999), "port 99999 is not a port number"),
    (lambda: checks.check_port("--udp", 0), "use 1..65535"),
    (lambda: checks.check_udp("--udp", "localhost:abc"), "must be HOST:PORT"),
    (lambda: checks.check_udp("--udp", "localhost"), "must be HOST:PORT"),
    (lambda: checks.check_baud("--baud", -5), "--baud -5 is not a serial rate"),
    (lambda: checks.check_baud("--baud", 12345), "57600"),
    (lambda: checks.check_baud("--baud", 0, allow_unlimited=False), "is not a serial rate"),
    (lambda: checks.check_rate("--rate", 1e6), "must be <= 10000 Hz"),
    (lambda: checks.check_rate("--rate", 0.0), "must be > 0 Hz"),
    (lambda: checks.check_rate("--rate", 0.01, 100.0), "gives 2 sample(s)"),
    (lambda: checks.check_count("-n", 0), "-n must be >= 1"),
    (lambda: checks.check_count("-n", 2.5), "whole number"),
    (lambda: checks.check_choice("--format", "xml", ("table", "json")), "table, json"),
    (lambda: checks.check_size("convert", 5.6e9, force=False), "add --force"),
])
def test_argument_checks(call, expected):
    with pytest.raises(ValueError, match=None) as info:
        call()
    assert expected in str(info.value)


def test_checks_accept_good_values():
    assert checks.check_udp("--udp", "127.0.0.1:14550") == ("127.0.0.1", 14550)
    assert checks.check_baud("--baud", 57600) == 57600
    assert checks.check_rate("--rate", 50.0, 10.0) == 50.0
    assert checks.check_frequency_band(0.1, 10.0, 0.02) == (0.1, 10.0)
    checks.check_size("convert", 5.6e9, force=True)  # --force lifts the limit
