"""``flightid design-optimize``: a multisine whose amplitudes are optimised for the
predicted output-error bounds of a card's derivatives, at the energy and input time of a
built-in design flown on each surface in turn; checked against the envelope by flying it
in JSBSim, written as a maneuver table (``design-compare --design-file``) and, with
``-n``, compared with the built-ins by Monte Carlo (the work is
``scenarios.montecarlo.design.optimize``)."""

from __future__ import annotations

import json
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from flightid.api import design_compare
from flightid.channels import LATERAL_INPUTS
from flightid.cli import study_options as opts
from flightid.cli.checks import Output, check_choice, check_number, check_paths, check_unique
from flightid.cli.design_compare import SURFACES
from flightid.cli.progress import count_progress
from flightid.cli.tables import add_columns
from flightid.scenarios.input_optimization import CRITERIA
from flightid.scenarios.montecarlo.design.experiment import DESIGNS, DesignSettings
from flightid.scenarios.montecarlo.design.optimize import (
    Envelope,
    envelope_excursions,
    envelope_violations,
    optimize,
)
from flightid.scenarios.montecarlo.intervals import LEVEL, interval_text
from flightid.scenarios.peak_limit import PeakLimitError
from flightid.units import DEG


def _rows_table(result) -> Table:
    heads = ("design", "b/|truth|", "E (rad²s)", "input (s)", "flight (s)", "peak (deg)")
    return add_columns(Table(
        title=f"predicted output-error bounds (criterion {result.multisine.criterion})",
        caption="b/|truth|: mean of bound/|truth| over the derivatives with non-zero truth; "
                "E: input energy; peak: largest deflection"), heads, rows=[
        [r["design"], f"{r['mean_relative_bound']:.4f}", f"{r['energy']:.5f}",
         f"{r['input_time']:.1f}", f"{r['flight_time']:.1f}",
         f"{np.rad2deg(r['peak']):.2f}"] for r in result.rows])


def _bounds_table(result) -> Table:
    kinds = list(result.predicted)
    return add_columns(Table(title="predicted bound by derivative and design"),
                       ["derivative", *kinds], rows=[
        [n, *(f"{result.predicted[k][n]:.3g}" for k in kinds)] for n in result.problem.names])


def _monte_carlo_table(comparison, names: dict[str, str]) -> Table:
    """Optimised against each built-in flown (``names``: study name -> built-in): the
    ratio of the mean bound / |truth| and of the mean scatter / |truth| with their
    paired-bootstrap intervals, and which design the interval calls smaller."""
    level = f"{100 * LEVEL:.0f} %"
    rows = []
    for study, kind in names.items():
        b = comparison.mean_relative_bound("optimized", study)
        s = comparison.mean_relative_scatter("optimized", study)
        rows.append([kind, f"{b['ratio']:.3f}", interval_text(b["low"], b["high"]),
                     f"{s['ratio']:.3f}", interval_text(s["low"], s["high"]),
                     {"optimized": "optimised", study: kind}.get(s["winner"], "not clear"),
                     str(s["realizations"])])
    return add_columns(Table(
        title=f"Monte Carlo: optimised / built-in, {level} paired intervals",
        caption="b, s: mean over the derivatives with non-zero truth of mean bound/|truth|, "
                "of scatter/|truth|; n: realizations both estimated"),
        ["built-in", "b ratio", "interval", "s ratio", "interval", "smaller s", "n"],
        rows=rows)


def design_optimize_command(
    card: Annotated[str, typer.Option(
        help="card giving aircraft, condition, sensors, turbulence")] = "navion-demo",
    model: opts.Model = "lat",
    surface: Annotated[list[str] | None, typer.Option(
        help="surfaces the multisine moves, and the built-ins in turn (repeatable; "
             "default da, dr)")] = None,
    criterion: Annotated[str, typer.Option(
        help="A (sum of variance/truth²), D (log det) or mean (mean bound/|truth|)")] = "A",
    band: Annotated[tuple[float, float], typer.Option(
        help="harmonics in F_MIN F_MAX (Hz)")] = (0.1, 2.0),
    reference: Annotated[str, typer.Option(
        help="built-in design whose energy and input time the multisine gets")] = "3211",
    equal_duration: Annotated[bool, typer.Option(
        "--equal-duration", help="every built-in stretched or compressed to the "
                                 "reference's input time too")] = False,
    against: Annotated[list[str] | None, typer.Option(
        help="built-in designs flown in the Monte Carlo (repeatable; default every one; "
             "the reference always)")] = None,
    amplitude_deg: Annotated[float, typer.Option(
        help="peak amplitude (deg) of the reference on each surface")] = 4.0,
    max_amplitude_deg: Annotated[float, typer.Option(
        help="limit of the optimised design's peak deflection on any surface (deg), a "
             "constraint of the optimisation")] = 10.0,
    max_bank_deg: Annotated[float, typer.Option(help="bank limit (deg)")] = 30.0,
    max_alpha_deg: Annotated[float, typer.Option(help="angle-of-attack limit (deg)")] = 15.0,
    max_speed_change: Annotated[float, typer.Option(
        help="limit of |V - V0| / V0 (fraction)")] = 0.10,
    output: Annotated[str, typer.Option(
        "-o", "--output", help="the maneuver table written (TOML)")] = "optimized.toml",
    n: Annotated[int, typer.Option(
        "-n", help="realizations per design of a Monte Carlo against the reference (0: "
                   "none)")] = 0,
    study: Annotated[str, typer.Option(
        help="study folder of the Monte Carlo (with -n)")] = "design-optimize",
    seed: opts.Seed = None,
    workers: opts.Workers = None,
    format: opts.Format = "table",
    quiet: opts.Quiet = False,
) -> None:
    """Optimise a multisine for the predicted bounds of the card's derivatives at the
    energy and input time of a built-in design; write it as a maneuver table."""
    surfaces = tuple(surface or LATERAL_INPUTS)
    for s in surfaces:
        check_choice("--surface", s, SURFACES)
    check_unique("--surface", surfaces)
    check_choice("--format", format, ("table", "json"))
    check_choice("--criterion", criterion, CRITERIA)
    check_choice("--reference", reference, DESIGNS)
    for kind in against or ():
        check_choice("--against", kind, DESIGNS)
    check_unique("--against", tuple(against or ()))
    check_number("--amplitude-deg", amplitude_deg, low=0.0, low_open=True, high=30.0,
                 unit="deg")
    check_number("--band F_MIN", band[0], low=0.0, low_open=True, unit="Hz")
    check_number("--band F_MAX", band[1], low=band[0], low_open=True, unit="Hz")
    check_number("--max-amplitude-deg", max_amplitude_deg, low=0.0, low_open=True,
                 high=30.0, unit="deg")
    check_number("--max-bank-deg", max_bank_deg, low=0.0, low_open=True, high=90.0, unit="deg")
    check_number("--max-alpha-deg", max_alpha_deg, low=0.0, low_open=True, high=90.0,
                 unit="deg")
    check_number("--max-speed-change", max_speed_change, low=0.0, low_open=True, high=1.0)
    check_number("-n", n, low=0)
    outputs = [Output("--output", output)]
    if n:
        outputs.append(Output("--study", study, folder=True))
    check_paths({"--card": card}, outputs)
    settings = DesignSettings(amplitude=amplitude_deg * DEG)
    try:
        result = optimize(card, model, surfaces, criterion, tuple(band), reference, settings,
                          equal_duration=equal_duration, max_amplitude=max_amplitude_deg * DEG)
    except PeakLimitError as e:
        typer.echo(f"error: --max-amplitude-deg {max_amplitude_deg:g}: no multisine at the "
                   f"energy of the {reference} at --amplitude-deg {amplitude_deg:g} "
                   f"({e.energy:.5f} rad²s) keeps every surface within "
                   f"{max_amplitude_deg:g} deg: the smallest peak found at that energy is "
                   f"{e.peak / DEG:.2f} deg, and at most {e.fits:.5f} rad²s fits under "
                   f"the limit; lower --amplitude-deg or raise the limit (nothing written)",
                   err=True)
        raise typer.Exit(3) from None
    excursions = envelope_excursions(card, result.designs["optimized"])
    violations = envelope_violations(excursions, Envelope(
        max_bank_deg * DEG, max_alpha_deg * DEG, max_speed_change))
    top = next(r["peak"] for r in result.rows if r["design"] == "optimized")
    if top > max_amplitude_deg * DEG:
        violations.append(f"peak deflection {top / DEG:.2f} deg exceeds --max-amplitude-deg "
                          f"{max_amplitude_deg:g} deg")
    if violations:
        typer.echo(f"error: the optimised design flown in JSBSim leaves the envelope: "
                   f"{'; '.join(violations)}; lower --amplitude-deg or raise the limit "
                   f"(nothing written)", err=True)
        raise typer.Exit(3)
    with open(output, "w", encoding="utf-8") as fh:
        fh.write(result.maneuver_table())
    comparison = None
    flown = {f"{k}-{'-'.join(surfaces)}": k for k in DESIGNS
             if k == reference or k in (against or DESIGNS)}
    if n:
        with count_progress("design-optimize", show=not quiet) as update:
            progress = ((lambda kind, done, total: update(done, total, f"monte carlo {kind}"))
                        if update else None)
            own = {name: result.designs[k] for name, k in flown.items()}
            comparison, _, _ = design_compare(
                study, card=card, n=n, method="oe", model=model, designs=(),
                equal="energy", reference=f"{reference}-{'-'.join(surfaces)}",
                settings=settings, workers=workers, seed=seed,
                own={**own, "optimized": result.designs["optimized"]}, progress=progress)
    if format == "json":
        print(json.dumps({"rows": result.rows, "predicted": result.predicted,
                          "gain": result.gain(), "best_builtin": result.best_builtin(),
                          "envelope": excursions, "output": output,
                          "comparison": comparison.as_dict() if comparison else None,
                          "monte_carlo": {k: {
                              "mean_relative_bound": comparison.mean_relative_bound(
                                  "optimized", name),
                              "mean_relative_scatter": comparison.mean_relative_scatter(
                                  "optimized", name)} for name, k in flown.items()}
                          if comparison else None},
                         indent=2, default=str))
        return
    console = Console()
    console.print(_rows_table(result))
    console.print(_bounds_table(result))
    console.print(f"optimised: {100 * result.gain():.1f} % below the best built-in "
                  f"({result.best_builtin()}) on the predicted mean bound/|truth|; flown "
                  f"in JSBSim: bank {np.rad2deg(excursions['bank']):.1f} deg, alpha "
                  f"{np.rad2deg(excursions['alpha']):.1f} deg, airspeed "
                  f"{100 * excursions['speed']:.1f} %")
    if comparison is not None:
        console.print(_monte_carlo_table(comparison, flown))
        console.print(f"study in {study}")
    typer.echo(f"wrote {output}")
