"""``flightid design-compare``: doublet, 2-1-1, 3211, sweep, multisine and designs of the
user's own (--design-file, a maneuver table) on the same aircraft and condition, each
over a Monte Carlo study with the same seeds; tables of each derivative's scatter and
bound by design, the designs' flight time and input energy, the 3211 / doublet ratios
with their intervals, and STUDY/design-compare.{png,html} (the work is
``flightid.api.design_compare``)."""

from __future__ import annotations

import json
import math
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.api import design_compare
from flightid.channels import CONTROLS
from flightid.cli import study_options as opts
from flightid.cli.checks import (
    Output,
    check_choice,
    check_number,
    check_paths,
    check_study,
    check_unique,
)
from flightid.cli.identify import parse_options
from flightid.cli.progress import count_progress
from flightid.cli.tables import add_columns, split_tables
from flightid.scenarios.cards import load_maneuvers
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.inputs import Maneuvers
from flightid.scenarios.montecarlo.card_file import card_with_overrides
from flightid.scenarios.montecarlo.design.comparison import Comparison
from flightid.scenarios.montecarlo.design.experiment import (
    DESIGNS,
    EQUAL,
    DesignSettings,
    check_own,
    make_design,
)
from flightid.scenarios.montecarlo.design.report import costs_rows, ratio_rows
from flightid.scenarios.montecarlo.intervals import LEVEL
from flightid.units import DEG

# COST_HEAD shortened to fit 80 columns
COST_SHORT = ("design", "flight (s)", "input (s)", "E (rad²s)", "peak (deg)", "n",
              "failed")
SURFACES = tuple(c for c in CONTROLS if c != "throttle")  # the designs move a surface (rad)


def _tables(comparison: Comparison, width: int = 80) -> list[Table]:
    """The designs' costs, the scatter and the mean bound by derivative and design (two
    tables, each split by designs where it is wider than ``width`` characters: no cell
    folded), and the 3211 / doublet scatter ratios with their intervals."""
    costs = add_columns(Table(title=f"designs (equal {comparison.equal}"
                              + (f": the energy of the {comparison.reference})"
                                 if comparison.equal == "energy" else ")"),
                              caption="E: input energy (rad² s); n: realizations"),
                        COST_SHORT,
                        rows=[[f"{v:.4g}" if isinstance(v, float) else str(v) for v in row]
                              for row in costs_rows(comparison)])
    level = f"{100 * LEVEL:.0f} %"
    best = comparison.best()
    kinds = [r.kind for r in comparison.results]
    out = [costs]
    for column, title in (
            ("scatter", f"scatter of the estimates by design; * smaller than every other "
                        f"design's ({level} interval of the ratio below 1)"),
            ("mean_bound", "mean reported bound by design")):
        wide = comparison.table(column)
        out += split_tables(title, ["derivative", *kinds], [
            [str(name), *("-" if not math.isfinite(float(wide.loc[name, k])) else
                          f"{float(wide.loc[name, k]):.4g}"
                          + ("*" if column == "scatter" and best.get(str(name)) == k else "")
                          for k in kinds)] for name in wide.index], width)
    if ratio_rows(comparison):
        out.append(add_columns(
            Table(title=f"scatter 3211 / doublet, {level} interval (paired bootstrap where "
                        "both n are 20 or more, else F)"),
            ["derivative", "ratio", f"{level} interval", "n 3211", "n doublet", "smaller"],
            rows=ratio_rows(comparison)))
    return out


def _verdict_line(verdict: dict) -> str:
    """The 3211-against-doublet verdict counted over the derivatives both estimated."""
    wins, losses = len(verdict["3211_smaller_scatter"]), len(verdict["doublet_smaller_scatter"])
    both, of = verdict["derivatives"], verdict["of"]
    return (f"3211 smaller scatter than the doublet for {wins} of {both} derivatives "
            f"estimated by both (of {of}; {100 * verdict['level']:.0f} % interval of the "
            f"ratio below 1); doublet smaller for {losses}; not clear for "
            f"{both - wins - losses}" + ("" if wins * 2 > both else
                                         " (NOT most: see docs/montecarlo.md for why)"))


def _own_design(path: str) -> tuple[str, InputDesign]:
    """(name, design) of a --design-file maneuver table; its name must not be taken."""
    name, parts = load_maneuvers(path)
    try:
        check_own({name: Maneuvers(parts=parts)})
    except ValueError as exc:
        raise ValueError(f"--design-file {path}: {exc}") from None
    return name, Maneuvers(parts=parts)


def design_compare_command(
    card: Annotated[str, typer.Option(
        help="card giving aircraft, condition, sensors, disturbances (its maneuvers are "
             "replaced by each design)")] = "navion-demo",
    n: Annotated[int, typer.Option("-n", help="realizations per design")] = 30,
    output: Annotated[str, typer.Option(
        "-o", "--output", help="study folder (continued when it exists)")] = "design-compare",
    method: opts.Method = "oe",
    model: opts.Model = "lon",
    surface: Annotated[list[str] | None, typer.Option(
        help="the surface every built-in design moves (default de); repeated: each is "
             "flown on every surface given, one after another (da, then dr)")] = None,
    amplitude_deg: Annotated[float, typer.Option(
        help="peak amplitude (deg) of every design (equal amplitude) or of the reference "
             "(equal energy)")] = 3.0,
    base: Annotated[float, typer.Option(help="pulse base time (s) of the multi-steps")] = 0.4,
    design: Annotated[list[str] | None, typer.Option(
        help=f"design to fly (repeatable; default all: {', '.join(DESIGNS)})")] = None,
    design_file: Annotated[list[str] | None, typer.Option(
        help="a design of your own: a TOML maneuver table ([[maneuver]] tables in the "
             "card's syntax, several surfaces at once; optional name = \"...\"), scaled "
             "like the built-ins (repeatable)")] = None,
    multisine_band: Annotated[tuple[float, float], typer.Option(
        help="the multisine's band F_MIN F_MAX (Hz)")] = DesignSettings().multisine_band,
    equal: Annotated[str, typer.Option(help="amplitude or energy")] = "amplitude",
    reference: Annotated[str, typer.Option(
        help="with --equal energy: the design whose energy all get")] = "3211",
    option: opts.MethodOptions = None,
    seed: opts.Seed = None,
    workers: opts.Workers = None,
    dask: opts.Dask = None,
    format: opts.Format = "table",
    quiet: opts.Quiet = False,
    set_: opts.Set = None,
    turbulence: opts.Turbulence = None,
    sensors: opts.Sensors = None,
) -> None:
    """Compare input designs by the scatter of the derivatives they give over a Monte
    Carlo (the same seeds for every design), at equal amplitude or equal input energy."""
    check_choice("--format", format, ("table", "json"))
    check_choice("--equal", equal, EQUAL)
    own: dict[str, InputDesign] = {}
    for path in design_file or ():
        name, made = _own_design(path)
        if name in own:
            raise ValueError(f"--design-file {path}: the name {name!r} is taken by another "
                             "--design-file; set name = \"...\" in one of them")
        own[name] = made
    check_choice("--reference", reference, (*DESIGNS, *own))
    for d in design or ():
        check_choice("--design", d, DESIGNS)
    surfaces = tuple(surface or ("de",))
    for s in surfaces:
        check_choice("--surface", s, SURFACES)
    check_unique("--surface", surfaces)
    check_number("--amplitude-deg", amplitude_deg, low=0.0, low_open=True, high=90.0,
                 unit="deg")
    check_number("--base", base, low=0.0, low_open=True, high=60.0, unit="s")
    check_number("--multisine-band F_MIN", multisine_band[0], low=0.0, low_open=True,
                 unit="Hz")
    check_number("--multisine-band F_MAX", multisine_band[1], low=multisine_band[0],
                 low_open=True, unit="Hz")
    options = parse_options(option or [])
    check_study(n, method, model, options, seed, workers)
    check_paths({"--card": card, "--design-file": design_file},
                [Output("--output", output, folder=True)])
    card = card_with_overrides(card, output, set_ or (), turbulence, sensors)
    settings = DesignSettings(surface=surfaces[0], amplitude=amplitude_deg * DEG, base=base,
                              multisine_band=tuple(multisine_band), then=surfaces[1:])
    kinds = tuple(design or DESIGNS)
    if "multisine" in kinds:  # a band without harmonics fails here, before any study
        try:
            make_design("multisine", settings)
        except ValueError as exc:
            raise ValueError(f"--multisine-band: {exc}") from None
    kwargs = dict(card=card, n=n, method=method, model=model,
                  designs=kinds, equal=equal, settings=settings,
                  reference=reference, workers=workers, dask_address=dask, seed=seed,
                  options=options, own=own)
    with count_progress("design-compare", show=not quiet) as update:
        progress = ((lambda kind, done, total: update(done, total, f"design-compare {kind}"))
                    if update else None)
        comparison, png, page = design_compare(output, progress=progress, **kwargs)
    if format == "json":
        print(json.dumps(comparison.as_dict(), indent=2, default=str))
        return
    console = Console()
    for table in _tables(comparison, console.width):
        console.print(table)
    verdict = comparison.as_dict()["3211_beats_doublet"]
    if verdict is not None:
        console.print(_verdict_line(verdict))
    typer.echo(f"wrote {png} and {page}")
