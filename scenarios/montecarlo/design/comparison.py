"""The input-design comparison: ``compare`` flies every design of ``experiment`` over a
Monte Carlo study (the same realization seeds for every design); ``Comparison`` holds the
results and compares the designs' scatter with paired-bootstrap or F intervals
(``intervals``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from flightid.scenarios.cards import load_card
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.montecarlo import load
from flightid.scenarios.montecarlo import run as run_study
from flightid.scenarios.montecarlo.design.experiment import (
    CARDS,
    DESIGNS,
    DesignSettings,
    card_text,
    check_own,
    design_card,
    equalized_designs,
    input_energy,
    maneuver_dicts,
    peak,
    time_grid,
)
from flightid.scenarios.montecarlo.intervals import (
    LEVEL,
    PAIRED_MIN,
    paired_mean_relative_interval,
    paired_ratio_interval,
    scatter_ratio_interval,
)
from flightid.scenarios.montecarlo.summary import Summary


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
