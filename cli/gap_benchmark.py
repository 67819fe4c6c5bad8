"""``flightid gap-benchmark``: the blind check of the gap diagnosis (cases drawn, flown,
diagnosed without being told, scored) with a progress bar, printed as a table or JSON (the
work is ``flightid.api.gap_benchmark``)."""

from __future__ import annotations

import json
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.api import gap_benchmark
from flightid.cli.checks import MAX_SEED, Output, check_choice, check_count, check_paths
from flightid.cli.progress import count_progress
from flightid.scenarios.gap_benchmark import Benchmark


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def _print(bench: Benchmark) -> None:
    console = Console()
    t = Table(title=f"gap blind check: {bench.n} cases, seed {bench.seed}")
    for c in ("#", "case (injected)", "named", "top-1", "top-3", "held-out shrink",
              "magnitude error"):
        t.add_column(c, justify="left" if c in ("case (injected)", "named") else "right")
    for r in bench.results:
        named = r.error or ((", ".join(r.named) + (" (partly unexplained)" if r.partly else ""))
                           if r.named else "unexplained")
        ok = "" if not r.case.in_catalogue else ("yes" if r.top1 else "no")
        t.add_row(str(r.case.index), r.case.label, named, ok,
                  "" if not r.case.in_catalogue else ("yes" if r.top3 else "no"),
                  "-" if r.shrink != r.shrink else f"{r.shrink:.0%}",
                  "-" if r.magnitude_error != r.magnitude_error else f"{r.magnitude_error:.0%}")
    console.print(t)
    s = bench.summary()
    console.print(
        f"in the catalogue ({s['in_catalogue']} cases): top-1 {_pct(s['top1'])}, top-3 "
        f"{_pct(s['top3'])}, median held-out shrink {_pct(s['shrinkage'])} (of the gap above "
        f"the noise: {_pct(s['excess_shrinkage'])}), median magnitude error "
        f"{_pct(s['magnitude_error_median'])}; reported unexplained "
        f"{_pct(s['false_unexplained'])}")
    console.print(f"outside the catalogue ({s['outside']} cases): reported unexplained or "
                  f"partly unexplained {_pct(s['unexplained_correct'])}; right attributions "
                  f"reported partly unexplained {_pct(s['false_partly_unexplained'])}")


MAX_CASES = 10_000  # each case is a flight and a diagnosis (seconds each)


def gap_benchmark_command(
    n: Annotated[int, typer.Option("--n", "-n", help="number of cases")] = 10,
    seed: Annotated[int, typer.Option(help="seed of the draw")] = 0,
    output: Annotated[str | None, typer.Option(
        "-o", "--output", help="folder: cases.jsonl (each case as it finishes), "
                               "summary.json")] = None,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
    quiet: Annotated[bool, typer.Option(help="no progress bar")] = False,
) -> None:
    """The gap diagnosis's blind check: N cases (an aircraft, an effect in or outside the
    catalogue, a moderate magnitude) flown, diagnosed without being told, and scored: top-1
    and top-3 attribution, held-out shrink, magnitude error, unexplained when outside."""
    check_choice("--format", format, ("table", "json"))
    check_count("--n", n, low=1, high=MAX_CASES)
    check_count("--seed", seed, low=0, high=MAX_SEED)
    check_paths({}, [Output("--output", output, folder=True)])
    with count_progress("gap blind check", show=not quiet) as update:
        bench = gap_benchmark(n, seed, output, update)
    if format == "json":
        print(json.dumps(bench.to_json(), indent=2))
    else:
        _print(bench)
