"""Argument checks of the command line, run before any work starts (docs/errors.md).

Every check raises ``ValueError`` (the error policy's exit 2) with a message saying what
was wrong, in which option, and what is accepted. Commands call them first, before a file
is read, an aircraft trimmed or a flight flown, so a bad argument never costs a flight and
never surfaces as a traceback after the work.
"""

from __future__ import annotations

import math
import os
import sys
import typing
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from flightid import files
from flightid.identification import nuisance
from flightid.identification.data import time_base
from flightid.identification.data.unit_sanity import check_units
from flightid.identification.engine import resources
from flightid.identification.engine.convergence import NotConvergedWarning
from flightid.identification.engine.structure_bias import StructureBiasWarning
from flightid.identification.methods import registry
from flightid.record import FlightRecord, read

# a command refuses to write more than this without --force (bytes)
SIZE_LIMIT = 1_000_000_000
BYTES_PER_VALUE = 8  # float64 samples
MAX_RATE_HZ = 10_000.0  # above this no flight-test recorder or JSBSim run makes sense
MIN_SAMPLES = 10  # an output rate must give at least this many samples
MAX_SEED = 2**32 - 1  # numpy's seeds are 32-bit words
BAUDS = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000,
         921600, 1000000, 1500000, 2000000)
_TRUE, _FALSE = ("true", "1", "yes", "on"), ("false", "0", "no", "off")


def check_choice(option: str, value: str, accepted: Sequence[str]) -> str:
    """``value`` if it is one of ``accepted``, else a ValueError naming them."""
    if value not in accepted:
        raise ValueError(f"{option} {value!r} is not accepted; use one of "
                         f"{', '.join(accepted)}")
    return value


def check_number(option: str, value: float, *, low: float | None = None,
                 high: float | None = None, low_open: bool = False, unit: str = "") -> float:
    """A finite number within [low, high] (``low_open``: strictly above low)."""
    u = f" {unit}" if unit else ""
    if not isinstance(value, int | float) or isinstance(value, bool) or not math.isfinite(value):
        raise ValueError(f"{option} must be a finite number{u}, got {value!r}")
    if low is not None and (value <= low if low_open else value < low):
        sign = ">" if low_open else ">="
        raise ValueError(f"{option} must be {sign} {low:g}{u}, got {value:g}")
    if high is not None and value > high:
        raise ValueError(f"{option} must be <= {high:g}{u}, got {value:g}")
    return float(value)


def check_count(option: str, value: int, low: int = 1, high: int | None = None) -> int:
    """An integer count within [low, high]."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{option} must be a whole number, got {value!r}")
    if value < low or (high is not None and value > high):
        span = f"{low}..{high}" if high is not None else f">= {low}"
        raise ValueError(f"{option} must be {span}, got {value}")
    return value


def check_rate(option: str, rate_hz: float, duration_s: float | None = None,
               max_hz: float = MAX_RATE_HZ, min_samples: int = MIN_SAMPLES) -> float:
    """A sample rate (Hz): positive, at most ``max_hz``, and, over ``duration_s``, giving at
    least ``min_samples`` samples."""
    check_number(option, rate_hz, low=0.0, low_open=True, high=max_hz, unit="Hz")
    if duration_s is not None and duration_s * rate_hz + 1 < min_samples:
        raise ValueError(
            f"{option} {rate_hz:g} Hz gives {int(duration_s * rate_hz) + 1} sample(s) over "
            f"{duration_s:g} s; use at least {min_samples / max(duration_s, 1e-9):.3g} Hz")
    return float(rate_hz)


def check_frequency_band(f_min: float | None, f_max: float | None, sample_interval_s: float
                         ) -> tuple[float | None, float | None]:
    """--f-min and --f-max (Hz): positive, f_min < f_max, f_max at most the Nyquist
    frequency 1 / (2 dt) of the record."""
    nyquist = 0.5 / sample_interval_s if sample_interval_s > 0 else math.inf
    for name, f in (("--f-min", f_min), ("--f-max", f_max)):
        if f is not None:
            check_number(name, f, low=0.0, low_open=True, unit="Hz")
            if f > nyquist:
                raise ValueError(
                    f"{name} {f:g} Hz is above the Nyquist frequency {nyquist:g} Hz of the "
                    f"record (sampled every {sample_interval_s:g} s); use at most "
                    f"{nyquist:g} Hz")
    if f_min is not None and f_max is not None and not f_min < f_max:
        raise ValueError(f"--f-min {f_min:g} Hz must be below --f-max {f_max:g} Hz")
    return f_min, f_max


def check_port(option: str, port: int) -> int:
    """A TCP/UDP port number, 1..65535."""
    if isinstance(port, bool) or not isinstance(port, int) or not 1 <= port <= 65535:
        raise ValueError(f"{option} port {port!r} is not a port number; use 1..65535")
    return port


def check_udp(option: str, text: str) -> tuple[str, int]:
    """'HOST:PORT' or ':PORT' into (host, port)."""
    host, sep, port = text.rpartition(":")
    if not sep or not port.strip().isdigit():
        raise ValueError(f"{option} {text!r} must be HOST:PORT with PORT in 1..65535")
    return host, check_port(option, int(port))


def check_baud(option: str, baud: int, allow_unlimited: bool = True) -> int:
    """A serial rate (bits/s): one of the standard rates, or 0 for unlimited."""
    if allow_unlimited and baud == 0:
        return 0
    if baud not in BAUDS:
        extra = "0 (unlimited) or " if allow_unlimited else ""
        raise ValueError(f"{option} {baud!r} is not a serial rate; use {extra}one of "
                         f"{', '.join(map(str, BAUDS))} bits/s")
    return baud


def check_writable(option: str, path: str | os.PathLike[str] | None) -> None:
    """The output ``path`` can be written (its folder exists and takes a new file, it is
    not a folder): checked before the work, so a flight is not flown for an output that
    cannot be written (the write itself stays atomic: ``flightid.files``)."""
    if path is None:
        return
    if str(path).strip() == "":
        raise ValueError(f"{option}: an empty path; give a file name")
    files.check_writable(path)


def check_suffix(option: str, path: str | None, accepted: Sequence[str]) -> None:
    """An output path whose suffix is one of ``accepted`` (e.g. '.parquet', '.csv')."""
    if path is None:
        return
    suffix = Path(path).suffix.lower()
    if suffix not in accepted:
        raise ValueError(f"{option} {path}: unknown format {suffix or '(no suffix)'!r}; use "
                         f"{' or '.join(accepted)}")


def estimated_bytes(samples: float, channels: int) -> float:
    """Bytes of a record of ``samples`` x ``channels`` float64 values (plus time)."""
    return float(samples) * (channels + 1) * BYTES_PER_VALUE


def check_size(what: str, n_bytes: float, force: bool, limit: float = SIZE_LIMIT) -> None:
    """Refuse to write more than ``limit`` bytes unless ``force``."""
    if n_bytes > limit and not force:
        raise ValueError(f"{what} would write about {n_bytes / 1e9:.3g} GB (limit "
                         f"{limit / 1e9:g} GB); lower the rate or the duration, or add "
                         "--force")


MAX_WORKERS = 1024
MAX_REALIZATIONS = 1_000_000  # a study's -n (docs/montecarlo.md measures 10,000)


def check_model(option: str, method: str, model: str) -> str:
    """--model against the models --method takes (``registry.check_model``); the canonical
    name."""
    try:
        return registry.check_model(method, model)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None


def check_study(n: int, method: str, model: str, options: Mapping[str, str],
                seed: int | None, workers: int | None) -> dict[str, object]:
    """The options of a Monte Carlo study (``montecarlo``, ``design-compare``), each named:
    -n, --method, --model, --option, --seed, --workers; the options read as the method
    takes them. (The study's own dry run, one trim, follows in the library.)"""
    check_count("-n", n, low=1, high=MAX_REALIZATIONS)
    if seed is not None:
        check_count("--seed", seed, low=0, high=MAX_SEED)
    if workers is not None:
        check_count("--workers", workers, low=1, high=MAX_WORKERS)
    check_choice("--method", method, list(registry.methods()))
    check_model("--model", method, model)
    return read_options(method, options)


def check_method_options(method: str, texts: Mapping[str, str]) -> None:
    """--method and --option KEY=VALUE against the method's declared options: unknown
    methods and keys are refused naming the valid ones, a value that does not read as the
    option's type names the accepted values (true or false for a switch)."""
    check_choice("--method", method, list(registry.methods()))
    spec = registry.get(method)
    hints = typing.get_type_hints(spec.options)
    for key, text in texts.items():
        hint = hints.get(key)
        if hint is bool and str(text).strip().lower() not in _TRUE + _FALSE:
            raise ValueError(f"--option {key}={text}: option {key} of method {spec.id} is a "
                             f"switch; accepted values: true or false")
    try:
        spec.make_options(_read_switches(hints, texts))
    except ValueError as exc:
        text = str(exc)
        raise ValueError(text if text.startswith("--option") else f"--option: {text}") from None


def _read_switches(hints: Mapping[str, object], texts: Mapping[str, str]) -> dict[str, object]:
    return {k: (v.strip().lower() in _TRUE if hints.get(k) is bool and isinstance(v, str)
                else v) for k, v in texts.items()}


def read_options(method: str, texts: Mapping[str, str]) -> dict[str, object]:
    """The checked option texts with switches read as booleans (what ``identify`` takes)."""
    check_method_options(method, texts)
    return _read_switches(typing.get_type_hints(registry.get(method).options), texts)


def check_unique(option: str, values: Iterable[str]) -> None:
    """No value given twice."""
    seen: set[str] = set()
    for v in values:
        if v in seen:
            raise ValueError(f"{option} {v!r} is given twice")
        seen.add(v)


def check_aircraft_xml(aircraft: str) -> None:
    """An aircraft given as a JSBSim XML path: a readable XML file whose root is
    ``<fdm_config>`` with an ``<aerodynamics>`` section that has at least one ``<axis>``
    (JSBSim itself only prints a warning and then fails deep inside a trim). Project and
    stock aircraft names pass unchecked."""
    path = Path(aircraft)
    if path.suffix.lower() != ".xml":
        return
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such aircraft file")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ValueError(f"{path}: not a well-formed JSBSim XML file ({exc})") from None
    if root.tag != "fdm_config":
        raise ValueError(f"{path}: not a JSBSim aircraft: its root element is <{root.tag}>, "
                         "expected <fdm_config>")
    aero = root.find("aerodynamics")
    if aero is None or aero.find("axis") is None:
        raise ValueError(f"{path}: the aircraft has no <aerodynamics> section with an "
                         "<axis>: JSBSim cannot compute its forces; add the aerodynamics")


# warnings of the data a command prints as "flightid <command>: warning: ..." lines
DATA_WARNINGS = (NotConvergedWarning, time_base.RegriddedWarning,
                 nuisance.ImplausibleBiasWarning, StructureBiasWarning)


@contextmanager
def printed_warnings(command: str) -> Iterator[None]:
    """Print the data warnings raised inside (``DATA_WARNINGS``) as one
    ``flightid <command>: warning: <message>`` line each on stderr, after the work;
    other warnings pass on."""
    with warnings.catch_warnings(record=True) as caught:
        for category in DATA_WARNINGS:
            warnings.simplefilter("always", category)
        yield
    for w in caught:
        if issubclass(w.category, DATA_WARNINGS):
            print(f"flightid {command}: warning: {w.message}", file=sys.stderr)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def read_record(path: str, work: str, *, force: bool = False) -> FlightRecord:
    """Read a record for ``work`` (a method id or a command) the way every command does:
    the resource guard on its sample count before reading (``resources.check_memory``;
    ``force`` overrides), then the reader's own checks, the unit check
    (``unit_sanity.check_units``: "units look wrong: ...") and time jitter below 1 %
    of the step re-gridded (``time_base``, with a warning)."""
    samples = resources.samples_in_file(path)
    if samples is not None:
        resources.check_memory(samples, work, str(path), force)
    record = read(path)
    resources.check_memory(len(record), work, str(path), force)
    check_units(record, None, f"{work} ({path})")
    return time_base.regrid_jitter(record)
PathText = str | os.PathLike[str]


@dataclass(frozen=True)
class Output:
    """One output of a command: the option that names it, its path (None: not asked for),
    the kind of file it writes (``flightid.files.SUFFIX_KINDS`` values; None: judged by
    the suffix) or ``folder=True`` for a folder the command fills."""

    option: str
    path: PathText | None
    kind: str | None = None
    folder: bool = False


def _same(a: Path, b: Path) -> bool:
    """Whether two paths name one file: equal once resolved, or the same inode (a hard
    link, a bind mount)."""
    if a.resolve() == b.resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _inputs(inputs: Mapping[str, PathText | Sequence[PathText] | None]
            ) -> list[tuple[str, Path]]:
    out = []
    for option, value in inputs.items():
        values = [value] if isinstance(value, str | os.PathLike) else list(value or [])
        out += [(option, Path(v)) for v in values  # (a name that is not a file: no input)
                if v is not None and str(v).strip() and os.path.exists(v)]
    return out


def check_paths(inputs: Mapping[str, PathText | Sequence[PathText] | None],
                outputs: Sequence[Output], force: bool | None = None) -> None:
    """Every output of a command, checked once before its work: it can be written
    (:func:`check_writable`; a folder output: an existing folder or a new one in a
    writable folder), it is none of the ``inputs`` ({option or argument: path or paths}),
    no two outputs share a path (paths compared resolved, hard links included), and it
    does not replace an existing file of another kind (judged by the content:
    ``flightid.files.content_kind``) unless ``force`` (None: the command has no
    --force). Raises ValueError or the OSError of :func:`check_writable` (exit 2),
    naming the option and the path."""
    given = [o for o in outputs if o.path is not None]
    read = _inputs(inputs)
    for k, out in enumerate(given):
        path = Path(out.path)  # type: ignore[arg-type]
        if str(out.path).strip() == "":
            raise ValueError(f"{out.option}: an empty path; give a "
                             f"{'folder' if out.folder else 'file'} name")
        for option, source in read:
            if _same(path, source):
                raise ValueError(f"{out.option} {path} is the input {option} {source}: an "
                                 "output never replaces an input; write it elsewhere")
        for other in given[:k]:
            if _same(path, Path(other.path)):  # type: ignore[arg-type]
                raise ValueError(f"{out.option} {path} and {other.option} {other.path} are "
                                 "one file: give each output its own path")
        if out.folder:
            _check_folder(out.option, path)
            continue
        check_writable(out.option, path)
        _check_kind(out, path, force)


def _check_folder(option: str, path: Path) -> None:
    """A folder output: an existing folder that takes new files, or a new one whose parent
    does."""
    if path.exists() and not path.is_dir():
        raise NotADirectoryError(f"{option} {path}: a file is there, not a folder; give a "
                                 "folder for the study (it is created when missing)")
    if path.is_dir():
        files.check_writable(path / ".flightid-check")
        return
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise NotADirectoryError(f"{option} {path}: cannot write there, a part of the path "
                                 "is not a folder")
    files.check_writable(parent / f".{path.name}.flightid-check")


def _check_kind(out: Output, path: Path, force: bool | None) -> None:
    """Refuse an output that would replace an existing file of another kind."""
    if not path.is_file() or force:
        return
    writes = out.kind or files.suffix_kind(path)
    there = files.content_kind(path)
    if writes is None or there in (None, "empty", writes):
        return
    how = "add --force to replace it" if force is not None else "remove it first to replace it"
    raise ValueError(f"{out.option} {path}: the file there is {_A.get(there, there)}, and this "
                     f"would write {_A.get(writes, writes)} over it; give another path, or "
                     f"{how}")


_A = {"parquet": "a Parquet record", "csv": "a CSV table", "html": "an HTML page",
      "tlog": "a MAVLink tlog", "json": "a JSON file", "png": "a PNG image",
      "pdf": "a PDF document", "svg": "an SVG image", "xml": "an XML file",
      "mat": "a MATLAB .mat file"}
