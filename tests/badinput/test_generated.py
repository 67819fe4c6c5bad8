"""The generated bad-input suite (issue 38): every command's options driven with generated
bad values through the command line in-process (``CliRunner`` on ``flightid.cli.app``).

The cases are generated from a table: for each command a base invocation that would run,
and for each of its options the bad values that option can take (negative, zero, NaN,
infinities, huge numbers, wrong types, empty text), plus the bad files of each file
argument (missing, a folder, damaged, truncated, another format) and every output pointed
at an input, at another output, at a folder, or at an existing file of another kind.

Each result is classified by written rules (``classify``). It is OK when:

1. the exit code is 2 (bad input) or 3 (a physical failure);
2. the output names the offending option (with or without its dashes), file, column or
   port (one of the case's names; a file given to an option may be named instead of it);
3. there is no traceback;
4. no file in the work folder changed, disappeared or appeared (hashed before and after).

Anything else is a defect, and the suite asserts zero defects. A base invocation always
holds cheap settings (1 realization, 0.5 s timeouts) so that a value wrongly accepted is
caught as a defect in seconds rather than flying a study.
"""

from __future__ import annotations

import hashlib
import shutil
import socket
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flightid.cli.app import app

from .conftest import SHORT_CARD

NUMBERS = ("-1", "0", "nan", "inf", "-inf", "1e300", "abc", "")
POSITIVE = NUMBERS  # options that must be > 0
NON_NEGATIVE = ("-1", "-0.5", "nan", "inf", "1e300", "abc", "")  # 0 accepted
COUNTS = ("-1", "0", "1.5", "abc", "", "99999999999999999999")
SEEDS = ("-1", "1.5", "abc", "", "4294967296", "-99999999999999999999")
WORDS = ("zz", "", "NaN", "../x", "table;rm")


@dataclass(frozen=True)
class Case:
    """One bad invocation and the names of which one must appear in the message."""

    command: str
    args: tuple[str, ...]
    names: tuple[str, ...]

    @property
    def id(self) -> str:
        return " ".join(self.args)


def _values(command: str, base: list[str], option: str, values: tuple[str, ...],
            names: tuple[str, ...] | None = None) -> Iterator[Case]:
    """``base`` with ``option VALUE`` for each value."""
    for v in values:
        named = names or (option,)
        if v.startswith("{w}/"):  # a file: the message may name it instead of the option
            named = (*named, v.rsplit("/", 1)[-1])
        yield Case(command, (*base, option, v), named)


def _replace(command: str, base: list[str], at: int, values: dict[str, tuple[str, ...]]
             ) -> Iterator[Case]:
    """``base`` with its argument ``at`` replaced by each value (name -> names)."""
    for v, names in values.items():
        args = list(base)
        args[at] = v
        yield Case(command, tuple(args), names)


def _bad_files(kind: str) -> dict[str, tuple[str, ...]]:
    """Bad input files of a kind ('record', 'card', 'tlog'), each with the name the
    message must give."""
    common = {"{w}/missing.parquet": ("missing.parquet",),
              "{w}/adir": ("adir",),
              "{w}/adir.parquet": ("adir.parquet",)}
    if kind == "record":
        return {**common, "{w}/damaged.parquet": ("damaged.parquet",),
                "{w}/truncated.parquet": ("truncated.parquet",),
                "{w}/damaged.csv": ("damaged.csv",), "{w}/page.html": ("page.html",),
                "{w}/nan.csv": ("nan.csv", "'q'")}
    if kind == "card":
        return {"{w}/missing.toml": ("missing.toml",), "{w}/adir": ("adir",),
                "{w}/damaged.toml": ("damaged.toml",), "{w}/rec.parquet": ("rec.parquet",)}
    return {"{w}/missing.tlog": ("missing.tlog",), "{w}/adir": ("adir",),
            "{w}/damaged.tlog": ("damaged.tlog",), "{w}/rec.parquet": ("rec.parquet",)}


def generate(busy_port: int) -> list[Case]:
    """Every generated case."""
    cases: list[Case] = []
    rec, card = "{w}/rec.parquet", "{w}/card.toml"

    # identify
    base = ["identify", rec, "--method", "ee"]
    cases += _replace("identify", base, 1, _bad_files("record"))
    cases += _values("identify", base, "--method", WORDS)
    cases += _values("identify", base, "--model", ("zz", "", "Cn=", "lat;lon"))
    cases += _values("identify", base, "--format", WORDS)
    cases += _values("identify", base, "--compare", WORDS)
    cases += _values("identify", base, "--window", ("-1,0", "5,1", "nan,1", "abc", "",
                                                    "0,inf", "1,1"))
    cases += _values("identify", base, "--option", ("foo=1", "=1", "x", "max_iterations=abc"),
                     ("--option",))
    cases += _values("identify", base, "--truth", ("{w}/missing.json", "{w}/adir",
                                                   "{w}/damaged.parquet"),
                     ("missing.json", "adir", "damaged.parquet"))
    cases += _values("identify", base, "--report", (rec, "{w}/adir", "{w}/nofolder/r.html",
                                                    "{w}/note.json", ""),
                     ("--report",))
    cases += [Case("identify", (*base, "--coefficient", "Cz"), ("Cz",)),
              Case("identify", ("identify", rec, "--method", "oe", "--multistep-input",
                                "zz"), ("zz",))]

    # frequency-response
    base = ["frequency-response", rec, "--input", "de", "--output", "q"]
    cases += _replace("frequency-response", base, 1, _bad_files("record"))
    cases += _values("frequency-response", base, "--window", POSITIVE + ("1e6",))
    cases += _values("frequency-response", base, "--f-min", POSITIVE)
    cases += _values("frequency-response", base, "--f-max", POSITIVE + ("1000",))
    cases += _values("frequency-response", base, "--plot", (rec, "{w}/adir", "{w}/x.xml",
                                                            "{w}/shot.png", ""),
                     ("--plot",))
    cases += _values("frequency-response", base, "--condition-on", ("zz", ""), ("'", "--"))
    cases += [Case("frequency-response", ("frequency-response", rec, "--input", "zz",
                                          "--output", "q"), ("zz",)),
              Case("frequency-response", ("frequency-response", rec, "--input", "de",
                                          "--output", "zz"), ("zz",))]

    # compatibility
    base = ["compatibility", rec]
    cases += _replace("compatibility", base, 1, _bad_files("record"))
    cases += _values("compatibility", base, "--format", WORDS)
    cases += _values("compatibility", base, "-o", (rec, "{w}/adir", "{w}/out.xml",
                                                   "{w}/nofolder/o.parquet", "{w}/page.csv",
                                                   ""), ("--output", "-o"))

    # simulate
    base = ["simulate", card, "-o", "{w}/out.parquet"]
    cases += _replace("simulate", base, 1, _bad_files("card"))
    cases += _values("simulate", base, "--seed", SEEDS)
    cases += _values("simulate", base, "--truth", ("{w}/out.parquet", card, rec + "x",
                                                   "{w}/adir", "{w}/page.html"), ("--truth",))
    cases += _values("simulate", base, "--plot", ("{w}/out.parquet", "{w}/p.txt", "{w}/adir"),
                     ("--plot",))
    cases += [Case("simulate", ("simulate", card, "-o", o), ("--output", "-o"))
              for o in (card, "{w}/adir", "{w}/page.parquet", "{w}/out.txt", "")]

    # demo
    base = ["demo", "--card", card, "--report", "{w}/demo.html"]
    cases += _values("demo", base, "--seed", SEEDS)
    cases += _values("demo", base, "--report", (card, "{w}/adir", "{w}/note.json",
                                                "{w}/nofolder/d.html", ""), ("--report",))
    cases += _values("demo", ["demo", "--report", "{w}/demo.html"], "--card",
                     ("{w}/missing.toml", "{w}/damaged.toml", "zz-card"),
                     ("missing.toml", "damaged.toml", "zz-card"))

    # trim, truth
    for command in ("trim", "truth"):
        base = [command, "navion", "--altitude", "1000", "--speed", "50"]
        cases += _values(command, base, "--altitude", ("-1", "nan", "inf", "1e300", "abc",
                                                       ""))
        cases += _values(command, base, "--speed", POSITIVE + ("1e6",))
        cases += _values(command, base, "--flaps", ("nan", "-90", "1e300", "abc"))
        cases += _values(command, base, "--format", WORDS)
        cases += _replace(command, base, 1, {"zz-aircraft": ("zz-aircraft",),
                                             "{w}/missing.xml": ("missing.xml",),
                                             "{w}/page.xml": ("page.xml",)})
    base = ["trim", "navion", "--altitude", "1000", "--speed", "50"]
    cases += _values("trim", base, "--gamma", ("nan", "inf", "95", "abc"))
    cases += _values("trim", base, "--bank", ("nan", "inf", "95", "abc"))
    cases += _values("truth", ["truth", "navion", "--altitude", "1000", "--speed", "50"],
                     "--axes", WORDS)

    # methods, effects
    cases += _values("methods", ["methods"], "--format", WORDS)
    cases += _values("effects", ["effects"], "--format", WORDS)
    cases += _values("effects", ["effects"], "--acts-on", WORDS)

    # gap
    base = ["gap", rec, "--model", "navion"]
    cases += _values("gap", base, "--format", WORDS)
    cases += _values("gap", base, "--report", (rec, "{w}/adir", "{w}/note.json"),
                     ("--report",))
    cases += _values("gap", base, "--write-aircraft", (rec, "{w}/page.html"),
                     ("--write-aircraft",))
    cases += _replace("gap", base, 1, {k: v for k, v in _bad_files("record").items()
                                       if "nan" not in k})

    # gap-benchmark
    base = ["gap-benchmark", "-n", "1", "-o", "{w}/gb", "--quiet"]
    cases += _values("gap-benchmark", ["gap-benchmark", "-o", "{w}/gb", "--quiet"], "-n",
                     COUNTS, ("--n", "-n"))
    cases += _values("gap-benchmark", base, "--seed", SEEDS)
    cases += _values("gap-benchmark", base, "--format", WORDS)
    cases += [Case("gap-benchmark", ("gap-benchmark", "-n", "1", "-o", o, "--quiet"),
                   ("--output", "-o")) for o in (rec, "{w}/page.html")]

    # montecarlo, montecarlo-report
    base = ["montecarlo", card, "-n", "1", "-o", "{w}/mc", "--workers", "1", "--quiet"]
    short = ["montecarlo", card, "-o", "{w}/mc", "--workers", "1", "--quiet"]
    cases += _values("montecarlo", short, "-n", COUNTS, ("-n",))
    cases += _replace("montecarlo", base, 1, _bad_files("card"))
    cases += _values("montecarlo", base, "--seed", SEEDS)
    cases += _values("montecarlo", base, "--method", WORDS)
    cases += _values("montecarlo", base, "--model", WORDS)
    cases += _values("montecarlo", base, "--option", ("foo=1", "x", "max_iterations=abc",
                                                      "colored=maybe"), ("--option",))
    cases += _values("montecarlo", base, "--workers", COUNTS[:-1] + ("100000",))
    cases += _values("montecarlo", base, "--format", WORDS)
    cases += _values("montecarlo", base, "--disperse", ("zz:0.1", "mass_scale:abc",
                                                        "mass_scale:-1", ""),
                     ("disperse", "zz", "mass_scale", "spec"))
    cases += _values("montecarlo", base, "--disperse-file", ("{w}/missing.toml",
                                                             "{w}/damaged.toml",
                                                             "{w}/baddisperse.toml"),
                     ("missing.toml", "damaged.toml", "baddisperse.toml"))
    cases += _values("montecarlo", base, "--dask", ("nonsense::x", "tcp://127.0.0.1:notaport"),
                     ("--dask",))
    cases += [Case("montecarlo", ("montecarlo", card, "-n", "1", "-o", o, "--quiet"),
                   ("--output", "-o")) for o in (card, rec, "{w}/page.html", "")]
    cases += [Case("montecarlo-report", ("montecarlo-report", s), (n,))
              for s, n in (("{w}/badstudy", "study.json"), ("{w}/badresults",
                                                            "realization-000000"),
                           ("{w}/adir", "adir"), ("{w}/missing", "missing"),
                           ("{w}/page.html", "page.html"))]
    cases += _values("montecarlo-report", ["montecarlo-report", "{w}/badstudy"], "--format",
                     WORDS)

    # design-compare
    base = ["design-compare", "--card", card, "-n", "1", "-o", "{w}/dc", "--design",
            "doublet", "--workers", "1", "--quiet"]
    cases += _values("design-compare", base, "--method", WORDS)
    cases += _values("design-compare", base, "--model", WORDS)
    cases += _values("design-compare", base, "--seed", SEEDS)
    cases += _values("design-compare", base, "--surface", WORDS + ("throttle",))
    cases += _values("design-compare", base, "--amplitude-deg", POSITIVE)
    cases += _values("design-compare", base, "--base", POSITIVE)
    cases += _values("design-compare", base, "--design", WORDS)
    cases += _values("design-compare", base, "--equal", WORDS)
    cases += _values("design-compare", base, "--reference", WORDS)
    cases += _values("design-compare", base, "--workers", ("0", "-1", "abc"))
    cases += _values("design-compare", base, "--format", WORDS)
    cases += _values("design-compare", ["design-compare", "--card", card, "-o", "{w}/dc",
                                        "--quiet"], "-n", COUNTS, ("-n",))
    cases += [Case("design-compare", ("design-compare", "--card", card, "-n", "1", "-o", o,
                                      "--quiet"), ("--output", "-o"))
              for o in (card, "{w}/page.html")]
    cases += _values("design-compare", ["design-compare", "-n", "1", "-o", "{w}/dc",
                                        "--quiet"], "--card",
                     ("{w}/missing.toml", "{w}/damaged.toml"), ("missing.toml",
                                                                 "damaged.toml"))

    # bridge serve, record, fly; convert
    udp = "127.0.0.1:9"
    base = ["bridge", "serve", rec, "--udp", udp, "--baud", "0"]
    cases += _replace("bridge serve", base, 2, {k: v for k, v in _bad_files("record").items()
                                                if "nan" not in k})
    cases += _values("bridge serve", base, "--udp", ("127.0.0.1:0", "127.0.0.1:99999", "abc",
                                                     "", "8.8.8.8:14550"), ("--udp",))
    cases += _values("bridge serve", ["bridge", "serve", rec, "--udp", udp], "--baud",
                     ("-1", "-5", "abc", "1e300"))
    cases += _values("bridge serve", base, "--faults", ("drop=2", "zz=1", "drop=nan", "x"))
    cases += _values("bridge serve", base, "--profile", WORDS)
    cases += _values("bridge serve", base, "--start-delay", ("-1", "nan", "inf", "abc"))
    cases += _values("bridge serve", base, "--report", (rec, "{w}/adir", "{w}/page.html"),
                     ("--report",))
    cases += _values("bridge serve", base, "--seed", ("abc", "1.5"))
    base = ["bridge", "record", "-o", "{w}/out.tlog", "--udp", "127.0.0.1:1",
            "--first-timeout", "0.5"]
    cases += _values("bridge record", base, "--udp", ("127.0.0.1:0", "abc", "",
                                                      f"127.0.0.1:{busy_port}"),
                     ("--udp", str(busy_port)))
    cases += _values("bridge record", base, "--duration", POSITIVE)
    cases += _values("bridge record", base, "--idle-timeout", POSITIVE)
    cases += _values("bridge record", base, "--first-timeout", POSITIVE)
    cases += _values("bridge record", base, "--baud", ("0", "-1", "abc"))
    cases += [Case("bridge record", ("bridge", "record", "-o", o, "--udp", "127.0.0.1:1",
                                     "--first-timeout", "0.5"), ("--output", "-o", name))
              for o, name in ((rec, "rec.parquet"), ("{w}/page.html", "page.html"),
                              ("{w}/adir", "adir"), ("{w}/nofolder/x.tlog", "nofolder"))]
    base = ["bridge", "fly", "navion", "--altitude", "1000", "--speed", "50", "--udp",
            "127.0.0.1:1", "--timeout", "0.5", "--duration", "1"]
    cases += _values("bridge fly", base, "--rate", POSITIVE)
    cases += _values("bridge fly", base, "--duration", POSITIVE)
    cases += _values("bridge fly", base, "--timeout", POSITIVE)
    cases += _values("bridge fly", base, "--profile", WORDS)
    cases += _values("bridge fly", base, "--ground-system", ("0", "-1", "256", "abc"))
    cases += _values("bridge fly", base, "--ground-component", ("-1", "256", "abc"))
    cases += _values("bridge fly", base, "--baud", ("-1", "abc"))
    cases += _values("bridge fly", base, "--udp", ("127.0.0.1:0", "abc", ""), ("--udp",))
    cases += _values("bridge fly", base, "--signing-key", ("{w}/short.key", "{w}/missing.key",
                                                           "{w}/adir"),
                     ("short.key", "missing.key", "adir"))
    cases += _values("bridge fly", base, "--output", (rec.replace("rec", "page"),
                                                      "{w}/page.html", "{w}/adir",
                                                      "{w}/nofolder/f.parquet"),
                     ("--output",))
    cases += _values("bridge fly", base, "--altitude", ("nan", "-1", "abc"))
    cases += _values("bridge fly", base, "--speed", ("nan", "0", "abc"))
    base = ["convert", "{w}/damaged.tlog", "{w}/conv.parquet"]
    cases += _replace("convert", base, 1, _bad_files("tlog"))
    cases += _values("convert", base, "--rate", POSITIVE + ("1e6",))
    cases += _values("convert", base, "--align", WORDS)
    cases += _values("convert", base, "--reference", ("zz", "1/x", "300/300/1"))
    cases += _values("convert", base, "--max-gap", ("-1", "abc", "1.5"))
    cases += _values("convert", base, "--segment", WORDS)
    cases += [Case("convert", ("convert", "{w}/damaged.tlog", o), (o.rsplit("/", 1)[-1],
                                                                   "OUTPUT"))
              for o in ("{w}/damaged.tlog", "{w}/page.csv", "{w}/adir", "{w}/x.txt")]
    return cases


# -- the work folder and the classification -------------------------------------------------


def _damage(data: bytes) -> bytes:
    out = bytearray(data)
    for k in range(len(out) // 3, len(out) // 3 + 200):
        out[k] ^= 0x5A
    return bytes(out)


@pytest.fixture(scope="module")
def work(flight_file, tmp_path_factory) -> Path:
    """The files every case may name: a record, a card, damaged and foreign files."""
    w = tmp_path_factory.mktemp("generated")
    rec = w / "rec.parquet"
    shutil.copy(flight_file, rec)
    data = rec.read_bytes()
    (w / "damaged.parquet").write_bytes(_damage(data))
    (w / "truncated.parquet").write_bytes(data[: len(data) // 2])
    (w / "damaged.csv").write_text("time,q\n0.0,1.0\n0.1,abc\n")
    (w / "nan.csv").write_text("time,q,de\n" + "".join(
        f"{k * 0.1:.1f},{'nan' if k == 5 else 0.1},0.0\n" for k in range(30)))
    (w / "card.toml").write_text(SHORT_CARD)
    (w / "damaged.toml").write_text("name = \"x\"\nduration = [[[\n")
    (w / "baddisperse.toml").write_text("disperse = 5\n")
    (w / "page.html").write_text("<!doctype html><html><body>a report</body></html>\n")
    (w / "page.csv").write_bytes(b"PAR1" + data[4:])  # a Parquet record named .csv
    (w / "page.parquet").write_text("<!doctype html><html></html>\n")  # HTML named .parquet
    (w / "page.xml").write_text("<html/>\n")
    (w / "shot.png").write_text("<!doctype html><html></html>\n")  # HTML named .png
    (w / "note.json").write_text("{\"a\": 1}\n")
    (w / "short.key").write_bytes(b"secret")
    (w / "damaged.tlog").write_bytes(bytes(range(256)) * 4)
    (w / "adir").mkdir()
    (w / "adir.parquet").mkdir()
    bad = w / "badstudy"
    bad.mkdir()
    (bad / "study.json").write_text("{\"identity\": ")
    res = w / "badresults"
    (res / "results").mkdir(parents=True)
    (res / "study.json").write_text(
        '{"identity": {}, "description": {"card": "x", "n": 1, "method": "oe", '
        '"model": "lat"}}\n')
    (res / "results" / "realization-000000.parquet").write_bytes(b"PAR1 not really")
    return w


@pytest.fixture(scope="module")
def busy_port() -> Iterator[int]:
    """A UDP port on 127.0.0.1 that is in use."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        yield s.getsockname()[1]


def _snapshot(folder: Path) -> dict[str, str]:
    """{relative path: sha256} of every file under ``folder`` (folders as 'dir')."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = str(p.relative_to(folder))
        out[rel] = "dir" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def classify(case: Case, code: int, output: str, before: dict[str, str],
             after: dict[str, str]) -> str | None:
    """None when the case is handled as the rules say, else what is wrong (a defect)."""
    problems = []
    if code not in (2, 3):
        problems.append(f"exit {code}")
    if "Traceback" in output:
        problems.append("a traceback")
    low = output.lower()
    # an option is named with or without its dashes ("altitude must be >= 0 m")
    names = {n.lower() for n in case.names} | {n.lstrip("-").lower() for n in case.names
                                                 if n.startswith("--")}
    if not any(n in low for n in names):
        problems.append(f"the message names none of {', '.join(case.names)}")
    changed = sorted(k for k in before if after.get(k) != before[k])
    new = sorted(set(after) - set(before))
    if changed:
        problems.append(f"changed or removed: {', '.join(changed)}")
    if new:
        problems.append(f"written: {', '.join(new)}")
    return "; ".join(problems) or None


def _restore(folder: Path, before: dict[str, str], pristine: Path) -> None:
    """Put the work folder back as it was (a defect must not spoil the next case)."""
    after = _snapshot(folder)
    for rel in sorted(set(after) - set(before), key=len, reverse=True):
        p = folder / rel
        shutil.rmtree(p) if p.is_dir() else p.unlink()
    for rel, digest in before.items():
        if after.get(rel) != digest and digest != "dir":
            shutil.copy(pristine / rel, folder / rel)


COMMANDS = ("identify", "frequency-response", "compatibility", "simulate", "demo", "trim",
            "truth", "methods", "effects", "gap", "gap-benchmark", "montecarlo",
            "montecarlo-report", "design-compare", "bridge serve", "bridge record",
            "bridge fly", "convert")


def test_every_command_is_covered():
    cases = generate(1)
    assert {c.command for c in cases} == set(COMMANDS)
    assert len(cases) >= 400, len(cases)


@pytest.mark.parametrize("command", COMMANDS)
def test_generated_bad_inputs(command, work, busy_port, tmp_path, monkeypatch):
    monkeypatch.chdir(work)  # a default output (e.g. the demo's report) lands here, counted
    pristine = tmp_path / "pristine"
    shutil.copytree(work, pristine)
    runner = CliRunner()
    defects = []
    cases = [c for c in generate(busy_port) if c.command == command]
    for case in cases:
        args = [a.format(w=work) for a in case.args]
        before = _snapshot(work)
        result = runner.invoke(app, args)
        after = _snapshot(work)
        why = classify(case, result.exit_code, result.output, before, after)
        if why:
            defects.append(f"{' '.join(case.args)}: {why}\n    {result.output.strip()[:300]}")
            _restore(work, before, pristine)
    assert not defects, f"{len(defects)} defect(s) in {len(cases)} cases:\n" + "\n".join(
        defects)
