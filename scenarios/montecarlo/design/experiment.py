"""Input-design experiments: the same aircraft, condition, sensors and disturbances flown
with a doublet, a 2-1-1, a 3211, a frequency sweep and a phase-optimised multisine on one
surface, each over a Monte Carlo study (the same realization seeds for every design), so
that each derivative's scatter can be compared by design.

Designs are compared at equal peak amplitude (``equal="amplitude"``, the default) or at
equal input energy (``equal="energy"``: every design scaled, ``scale_to_energy``, to the
energy of the reference design, the 3211 by default). Each design's flight card is
written to ``STUDY/cards/<design>.toml`` and its study to ``STUDY/<design>/`` (continued
when rerun, as any Monte Carlo study). Classic expectation (Plaetschke & Schulz 1979;
Jategaonkar 2015, 2.5; Morelli & Klein 2016, 9.3): at equal amplitude a 3211 gives
smaller scatter than a doublet for most longitudinal derivatives, because its spectrum
is broader and it carries more energy (7 base times at full amplitude against 2).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from flightid.scenarios.cards import load_card
from flightid.scenarios.equal_energy import energy, scale_amplitude, scale_to_energy
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.inputs import (
    Doublet,
    Maneuvers,
    Sweep,
    ThreeTwoOneOne,
    TwoOneOne,
)
from flightid.scenarios.montecarlo import load
from flightid.scenarios.montecarlo import run as run_study
from flightid.scenarios.montecarlo.intervals import (
    LEVEL,
    PAIRED_MIN,
    paired_mean_relative_interval,
    paired_ratio_interval,
    scatter_ratio_interval,
)
from flightid.scenarios.montecarlo.summary import Summary
from flightid.scenarios.multisine import Multisine
from flightid.units import DEG

DESIGNS = ("doublet", "211", "3211", "sweep", "multisine")
EQUAL = ("amplitude", "energy")
START_S = 2.0  # s of trimmed flight before the input
GAP_S = 4.0  # s between one surface's input and the next one's (DesignSettings.then)
SETTLE_S = 8.0  # s of free response after it (the identification window keeps 8 s)
CARDS = "cards"


@dataclass(frozen=True)
class DesignSettings:
    """What the designs share: ``surface``, peak ``amplitude`` (rad), multi-step ``base``
    (s), the sweep's band (Hz) and duration (s), the multisine's band (Hz) and period (s),
    and ``then``: further surfaces each design is flown on in turn after ``surface``, the
    next GAP_S s after the previous input ends (as the library cards fly an aileron and a
    rudder input)."""

    surface: str = "de"
    amplitude: float = 3.0 * DEG
    base: float = 0.4
    sweep_band: tuple[float, float] = (0.2, 2.0)
    sweep_duration: float = 12.0
    multisine_band: tuple[float, float] = (0.2, 2.0)
    multisine_period: float = 10.0
    then: tuple[str, ...] = ()


def make_design(kind: str, settings: DesignSettings = DesignSettings(),
                start: float = START_S) -> InputDesign:
    """The input design ``kind`` (one of DESIGNS) at the settings' peak amplitude, on the
    settings' surface and then on each of ``settings.then`` in turn (a Maneuvers).

    Parameters
    ----------
    kind : str
        Design kind, one of ``DESIGNS``.
    settings : DesignSettings, optional
        Surface, amplitude (rad) and the other settings.
    start : float, optional
        Start time, s.

    Returns
    -------
    InputDesign
        The design (a ``Maneuvers`` with ``settings.then``).
    """
    if settings.then:
        parts = [make_design(kind, replace(settings, then=()), start)]
        for surface in settings.then:
            parts.append(make_design(kind, replace(settings, surface=surface, then=()),
                                     parts[-1].end + GAP_S))
        return Maneuvers(parts=tuple(parts))
    s = settings
    common = dict(surface=s.surface, amplitude=s.amplitude, start=start)
    if kind == "doublet":
        return Doublet(base=s.base, **common)
    if kind == "211":
        return TwoOneOne(base=s.base, **common)
    if kind == "3211":
        return ThreeTwoOneOne(base=s.base, **common)
    if kind == "sweep":
        return Sweep(f_start=s.sweep_band[0], f_end=s.sweep_band[1],
                     duration=s.sweep_duration, law="log", fade_in=1.0, fade_out=1.0,
                     **common)
    if kind == "multisine":
        return Multisine(f_min=s.multisine_band[0], f_max=s.multisine_band[1],
                         period=s.multisine_period, phases="optimized", **common)
    raise ValueError(f"unknown design {kind!r}; designs: {', '.join(DESIGNS)}")


def time_grid(design: InputDesign, rate: float) -> np.ndarray:
    """Sample times (s) from 0 to the end of ``design`` plus SETTLE_S at ``rate`` (Hz).

    Parameters
    ----------
    design : InputDesign
        The input design.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    numpy.ndarray
        Sample times, s.
    """
    duration = design.end + SETTLE_S
    return np.arange(int(round(duration * rate)) + 1) / rate


def input_energy(design: InputDesign, rate: float) -> float:
    """Integral of u^2 dt over the flight (rad^2 s), summed over the design's surfaces.

    Parameters
    ----------
    design : InputDesign
        The input design.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    float
        Input energy, rad^2 s.
    """
    t = time_grid(design, rate)
    return float(sum(energy(t, u) for u in design.signals(t).values()))


def peak(design: InputDesign, rate: float) -> float:
    """The largest |u| of the design (rad).

    Parameters
    ----------
    design : InputDesign
        The input design.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    float
        Peak |u| over its surfaces, rad.
    """
    t = time_grid(design, rate)
    return float(max(np.abs(u).max() for u in design.signals(t).values()))


def equalized_designs(kinds: Sequence[str], settings: DesignSettings, equal: str,
                      rate: float, reference: str = "3211",
                      own: Mapping[str, InputDesign] | None = None) -> dict[str, InputDesign]:
    """The built-in designs ``kinds`` and the user's ``own`` designs (name -> design, a
    ``Maneuvers`` for several surfaces at once) at equal peak amplitude (an own design
    scaled so that its largest |u| over its surfaces is the settings' amplitude), or all
    scaled to the input energy of ``reference`` (a built-in or own name) at that
    amplitude.

    Parameters
    ----------
    kinds : Sequence[str]
        Built-in design kinds (``DESIGNS``).
    settings : DesignSettings
        Surface, amplitude (rad) and the other settings.
    equal : str
        ``"amplitude"`` or ``"energy"``.
    rate : float
        Sample rate, Hz.
    reference : str, optional
        Design whose energy the others get with ``equal="energy"``.
    own : Mapping[str, InputDesign] or None, optional
        The user's designs by name.

    Returns
    -------
    dict[str, InputDesign]
        Name -> scaled design, built-in ones first.
    """
    if equal not in EQUAL:
        raise ValueError(f"equal must be one of {', '.join(EQUAL)}, got {equal!r}")
    designs = {k: make_design(k, settings) for k in kinds}
    for name, d in (own or {}).items():
        top = peak(d, rate)
        if not top > 0:
            raise ValueError(f"design {name!r} does not move any surface")
        designs[name] = scale_amplitude(d, settings.amplitude / top)
    if equal == "amplitude":
        return designs
    ref = designs[reference] if reference in designs else make_design(reference, settings)
    target = input_energy(ref, rate)
    out = {}
    for k, d in designs.items():
        t = time_grid(d, rate)
        out[k] = scale_to_energy(d, t, target)
    return out


def toml_value(v: Any) -> str:
    """A plain value (str, number, bool, list, dict) as an inline TOML value.

    Parameters
    ----------
    v : Any
        The value.

    Returns
    -------
    str
        Inline TOML text.
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        x = float(v)
        return "nan" if math.isnan(x) else ("inf" if x == math.inf else
                                             "-inf" if x == -math.inf else repr(x))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_value(x)}"
                               for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} to TOML: {v!r}")


def card_text(data: Mapping[str, Any]) -> str:
    """A flight card (plain dict) as TOML text, one key per line with inline tables.

    Parameters
    ----------
    data : Mapping[str, Any]
        The card's data.

    Returns
    -------
    str
        TOML text.
    """
    return "".join(f"{json.dumps(str(k))} = {toml_value(v)}\n" for k, v in data.items())


def design_card(base: Mapping[str, Any], kind: str, design: InputDesign,
                rate: float) -> dict[str, Any]:
    """The base card's data with its maneuvers replaced by ``design`` and its duration
    set to the input plus SETTLE_S.

    Parameters
    ----------
    base : Mapping[str, Any]
        The base card's data.
    kind : str
        Design name, for the card's name.
    design : InputDesign
        The design flown.
    rate : float
        Sample rate, Hz.

    Returns
    -------
    dict[str, Any]
        The new card's data.
    """
    data = {k: v for k, v in base.items() if k != "maneuver"}
    data["name"] = f"{base.get('name', 'card')}-{kind}"
    data["description"] = f"design-compare: {kind} on {', '.join(design.surfaces())}"
    data["duration"] = float(time_grid(design, rate)[-1])
    data["maneuver"] = maneuver_dicts(design)
    return data


def maneuver_dicts(design: InputDesign) -> list[dict[str, Any]]:
    """The card's ``[[maneuver]]`` tables of a design (one per part of a Maneuvers).

    Parameters
    ----------
    design : InputDesign
        The design.

    Returns
    -------
    list[dict[str, Any]]
        One table per part.
    """
    parts = design.parts if isinstance(design, Maneuvers) else (design,)
    return [d.to_dict() for d in parts]


def check_own(own: Mapping[str, InputDesign]) -> None:
    """Raise ValueError unless every own design's name is a usable folder name that is
    not a built-in design's.

    Parameters
    ----------
    own : Mapping[str, InputDesign]
        The user's designs by name.
    """
    for name in own:
        if name in DESIGNS:
            raise ValueError(f"design name {name!r} is a built-in design's; name it "
                             "otherwise (the maneuver table's name = \"...\")")
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", name) or name in (CARDS, ".", ".."):
            raise ValueError(f"design name {name!r}: use letters, digits, '_', '.', '-' "
                             f"(not {CARDS!r})")


@dataclass
class DesignResult:
    """One design's cost and its study: flight time (s, the card's duration), input time
    (s), input energy (rad^2 s), peak |u| (rad) and the Monte Carlo summary."""

    kind: str
    flight_time: float
    input_time: float
    energy: float
    peak: float
    summary: Summary
    study_dir: str
    maneuvers: list[dict[str, Any]] = field(default_factory=list)  # as flown (SI)

    def as_dict(self) -> dict[str, Any]:
        d = {k: v for k, v in asdict(self).items() if k != "summary"}
        d["summary"] = self.summary.as_dict()
        return d


@dataclass
class Comparison:
    """The results of every design, and how they were made comparable."""

    card: str
    aircraft: str
    method: str
    model: str
    n: int
    equal: str
    reference: str
    settings: DesignSettings
    results: list[DesignResult] = field(default_factory=list)
    _errors: dict[tuple[str, str], pd.DataFrame] = field(default_factory=dict, repr=False,
                                                         compare=False)

    def errors(self, kind: str, column: str = "error") -> pd.DataFrame:
        """Design ``kind``'s estimated errors (estimate - truth; ``column="std"``: the
        reported standard errors), realization index (rows) by derivative (columns), from
        its study's stored rows."""
        if (kind, column) not in self._errors:
            study = next(r.study_dir for r in self.results if r.kind == kind)
            rows = load(study, ["index", "name", column, "status"])
            rows = rows[rows["status"] == "estimated"]
            self._errors[kind, column] = rows.pivot_table(index="index", columns="name",
                                                          values=column, observed=True)
        return self._errors[kind, column]

    def paired_interval(self, a: str, b: str, name: str, level: float = LEVEL
                        ) -> tuple[float, float, int]:
        """The paired-bootstrap ``level`` interval of design ``a``'s scatter over ``b``'s
        for derivative ``name`` over the realizations both estimated (the same seeds):
        (low, high, pairs); NaN bounds under ``intervals.PAIRED_MIN`` pairs."""
        ea, eb = self.errors(a), self.errors(b)
        if name not in ea.columns or name not in eb.columns:
            return math.nan, math.nan, 0
        both = pd.concat([ea[name], eb[name]], axis=1, join="inner").dropna()
        low, high = paired_ratio_interval(both.iloc[:, 0].to_numpy(),
                                          both.iloc[:, 1].to_numpy(), level)
        return low, high, len(both)

    def frame(self) -> pd.DataFrame:
        """One row per (derivative, design): truth, bias, scatter, mean_bound, ratio,
        coverage, estimated, unidentifiable."""
        rows = []
        for r in self.results:
            for s in r.summary.rows:
                rows.append({"derivative": s.name, "design": r.kind, "truth": s.truth,
                             "bias": s.bias, "scatter": s.scatter,
                             "mean_bound": s.mean_bound, "ratio": s.ratio,
                             "coverage": s.coverage, "estimated": s.estimated,
                             "unidentifiable": s.unidentifiable})
        return pd.DataFrame(rows)

    def table(self, column: str = "scatter") -> pd.DataFrame:
        """``column`` by derivative (rows) and design (columns, in DESIGNS order)."""
        df = self.frame()
        if df.empty:
            return df
        wide = df.pivot(index="derivative", columns="design", values=column)
        return wide[[r.kind for r in self.results if r.kind in wide.columns]]

    def mean_relative_scatter(self, a: str, b: str, level: float = LEVEL,
                              column: str = "error") -> dict[str, Any]:
        """Design ``a`` against ``b`` over every derivative with a non-zero truth that both
        estimated in every shared realization: the ratio of their mean scatter / |truth|
        and its paired-bootstrap ``level`` interval (``intervals.
        paired_mean_relative_interval``), the derivatives and realizations used, and the
        winner ("" when the interval contains 1). ``column="std"``: the same for the
        mean reported bound / |truth| (``mean_relative_bound``)."""
        truth = self.frame().drop_duplicates("derivative").set_index("derivative")["truth"]
        ea, eb = self.errors(a, column), self.errors(b, column)
        names = [n for n in ea.columns if n in eb.columns and truth.get(n, 0.0) != 0.0]
        both = pd.concat([ea[names], eb[names]], axis=1, keys=["a", "b"],
                         join="inner").dropna()
        xa, xb = both["a"].to_numpy(), both["b"].to_numpy()
        ratio, low, high = paired_mean_relative_interval(
            xa, xb, truth[names].to_numpy(float), level,
            statistic="mean" if column == "std" else "scatter")
        return {"ratio": ratio, "low": low, "high": high, "level": level,
                "derivatives": names, "realizations": len(both),
                "winner": a if high < 1 else b if low > 1 else ""}

    def mean_relative_bound(self, a: str, b: str, level: float = LEVEL) -> dict[str, Any]:
        """``mean_relative_scatter`` of the reported bounds: the ratio of design ``a``'s
        mean over the derivatives of mean bound / |truth| to ``b``'s, with its
        paired-bootstrap interval over the realizations."""
        return self.mean_relative_scatter(a, b, level, column="std")

    def scatter_ratios(self, a: str, b: str, level: float = LEVEL) -> pd.DataFrame:
        """Per derivative estimated (twice or more) by both designs ``a`` and ``b``: the
        ratio of their scatters a / b, its ``level`` interval, the realizations that
        estimated it with each (n_a, n_b), the interval's kind (``paired``: the paired
        bootstrap over the realizations both estimated, ``paired_interval``, when there
        are ``intervals.PAIRED_MIN`` pairs or more; else ``F``: ``intervals.
        scatter_ratio_interval``, conservative for the same seeds) and the winner: ``a``
        when the interval lies below 1, ``b`` when above, "" when it contains 1 (the data
        do not tell them apart)."""
        df = self.frame()
        cols = ["ratio", "low", "high", "n_a", "n_b", "interval", "winner"]
        if df.empty:
            return pd.DataFrame(columns=cols)
        scatter = df.pivot(index="derivative", columns="design", values="scatter")
        count = df.pivot(index="derivative", columns="design", values="estimated")
        rows = {}
        for name in scatter.index:
            sa, sb = float(scatter.loc[name, a]), float(scatter.loc[name, b])
            if not (math.isfinite(sa) and math.isfinite(sb)) or sb <= 0:
                continue
            na, nb = int(count.loc[name, a]), int(count.loc[name, b])
            low, high = scatter_ratio_interval(sa / sb, na, nb, level)
            kind = "F"
            if min(na, nb) >= PAIRED_MIN:
                plow, phigh, _ = self.paired_interval(a, b, str(name), level)
                if math.isfinite(plow):
                    low, high, kind = plow, phigh, "paired"
            rows[str(name)] = {"ratio": sa / sb, "low": low, "high": high, "n_a": na,
                               "n_b": nb, "interval": kind,
                               "winner": a if high < 1 else b if low > 1 else ""}
        return pd.DataFrame.from_dict(rows, orient="index", columns=cols)

    def best(self, level: float = LEVEL) -> dict[str, str]:
        """Per derivative, the design whose scatter is smaller than every other design's
        that estimated it, each ratio's ``level`` interval below 1; "" where no design
        is smaller than all others with that confidence."""
        kinds = [r.kind for r in self.results]
        out = {}
        for name in self.table().index:
            out[str(name)] = ""
            for a in kinds:
                others = [b for b in kinds if b != a]
                ratios = [self.scatter_ratios(a, b, level) for b in others]
                if others and all(name in r.index and r.loc[name, "winner"] == a
                                  for r in ratios):
                    out[str(name)] = a
        return out

    def as_dict(self) -> dict[str, Any]:
        """Plain data, JSON-ready (NaN as None)."""
        return {"card": self.card, "aircraft": self.aircraft, "method": self.method,
                "model": self.model, "n": self.n, "equal": self.equal,
                "reference": self.reference, "settings": asdict(self.settings),
                "designs": [r.as_dict() for r in self.results],
                "3211_beats_doublet": self.verdict("3211", "doublet"),
                "smallest_scatter": self.best()}

    def verdict(self, a: str, b: str, level: float = LEVEL) -> dict[str, Any] | None:
        """Design ``a`` against ``b``: of the derivatives in the study (``of``), how many
        both estimated (``derivatives``), where ``a``'s scatter is smaller with the
        ``level`` interval of the ratio below 1 (``<a>_smaller_scatter``), where ``b``'s
        is (``<b>_smaller_scatter``), where the interval contains 1 (``undecided``), and
        each ratio with its interval; None when either design is not in the comparison."""
        kinds = [r.kind for r in self.results]
        if a not in kinds or b not in kinds:
            return None
        ratios = self.scatter_ratios(a, b, level)
        return {"of": len(self.table().index), "derivatives": len(ratios),
                "level": level,
                f"{a}_smaller_scatter": [n for n in ratios.index
                                         if ratios.loc[n, "winner"] == a],
                f"{b}_smaller_scatter": [n for n in ratios.index
                                         if ratios.loc[n, "winner"] == b],
                "undecided": [n for n in ratios.index if ratios.loc[n, "winner"] == ""],
                "ratios": {n: {k: (v.item() if hasattr(v, "item") else v)
                               for k, v in ratios.loc[n].items() if k != "winner"}
                           for n in ratios.index}}


def compare(card: str | Path = "navion-demo", n: int = 50, method: str = "oe",
            model: str = "lon", study_dir: str | Path = "design-compare",
            designs: Sequence[str] = DESIGNS, equal: str = "amplitude",
            settings: DesignSettings = DesignSettings(), reference: str = "3211",
            workers: int | None = None, dask_address: str | None = None,
            seed: int | None = None, options: Mapping[str, Any] | None = None,
            progress: Callable[[str, int, int], None] | None = None,
            own: Mapping[str, InputDesign] | None = None) -> Comparison:
    """Fly every design in ``designs`` and the user's ``own`` designs (name -> design;
    ``Maneuvers`` for several surfaces at once; ``cards.load_maneuvers`` reads one from
    a maneuver table) on ``card``'s aircraft, condition, sensors and disturbances (its
    maneuvers are replaced), ``n`` realizations each with the same seeds, identify with
    ``method`` and ``model``, and return the Comparison.
    ``progress(design, done, total)`` after each realization.

    Parameters
    ----------
    card : str or Path, optional
        Base flight card, path or library name.
    n : int, optional
        Realizations per design.
    method : str, optional
        Identification method id.
    model : str, optional
        Model of the method.
    study_dir : str or Path, optional
        Output folder: one study per design, their cards in ``CARDS``.
    designs : Sequence[str], optional
        Built-in designs (``DESIGNS``).
    equal : str, optional
        ``"amplitude"`` or ``"energy"``, as in :func:`equalized_designs`.
    settings : DesignSettings, optional
        Surface, amplitude (rad) and the other settings.
    reference : str, optional
        Energy reference design.
    workers : int or None, optional
        Local worker processes; None uses one per CPU.
    dask_address : str or None, optional
        Dask scheduler address; None runs locally.
    seed : int or None, optional
        Base seed; None uses the card's.
    options : Mapping[str, Any] or None, optional
        The method's options.
    progress : callable or None, optional
        ``progress(design, done, total)``.
    own : Mapping[str, InputDesign] or None, optional
        The user's designs by name.

    Returns
    -------
    Comparison
        Every design's result (flight and input time, s; energy, rad^2 s; peak, rad; the
        study summary).
    """
    own = dict(own or {})
    check_own(own)
    unknown = [d for d in designs if d not in DESIGNS]
    if unknown:
        raise ValueError(f"unknown design(s) {', '.join(unknown)}; designs: "
                         f"{', '.join(DESIGNS)}")
    if not designs and not own:
        raise ValueError("no design to compare")
    if reference not in DESIGNS and reference not in own:
        raise ValueError(f"unknown reference design {reference!r}; designs: "
                         f"{', '.join([*DESIGNS, *own])}")
    base = load_card(card)
    root = Path(study_dir)
    (root / CARDS).mkdir(parents=True, exist_ok=True)
    built = equalized_designs(designs, settings, equal, base.rate, reference, own)
    result = Comparison(str(card), base.aircraft, method, model, int(n), equal, reference,
                        settings)
    for kind, design in built.items():
        path = root / CARDS / f"{kind}.toml"
        text = card_text(design_card(base.to_dict(), kind, design, base.rate))
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
        report = None if progress is None else \
            (lambda done, total, kind=kind: progress(kind, done, total))
        summary = run_study(str(path), n, method, model, options, root / kind, workers,
                            dask_address, report, seed=base.seed if seed is None else seed)
        t = time_grid(design, base.rate)
        result.results.append(DesignResult(
            kind=kind, flight_time=float(t[-1]), input_time=float(design.end - design.start),
            energy=input_energy(design, base.rate), peak=peak(design, base.rate),
            summary=summary, study_dir=str(root / kind),
            maneuvers=maneuver_dicts(design)))
    return result
