"""``flightid gap-benchmark``: the blind check of the gap diagnosis (cases drawn, flown,
diagnosed without being told, scored per kind) with a progress bar, on local processes or
a Dask cluster, resumable in its output folder; printed as a per-kind table (80 columns)
or JSON (the work is ``flightid.api.gap_benchmark``)."""

from __future__ import annotations

import json
from typing import Annotated, Any

import typer
from rich import box
from rich.console import Console
from rich.table import Table

from flightid.api import gap_benchmark
from flightid.cli import study_options as opts
from flightid.cli.checks import MAX_SEED, Output, check_choice, check_count, check_paths
from flightid.cli.progress import count_progress
from flightid.scenarios.gap_benchmark import AIRCRAFT, TARGETS, Benchmark, check

# the per-kind table's columns: (heading, figure)
COLUMNS = (("right", "right_first"), ("mag", "magnitude_error"), ("both", "both_named"),
           ("unexp", "unexplained"), ("nogap", "no_gap"), ("shrink", "excess_shrink"))
SHORT_AXES = {"/lateral": "/lat", "/longitudinal": "/lon"}


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f}%"


def _kind(name: str) -> str:
    for long, short in SHORT_AXES.items():
        name = name.replace(long, short)
    return name


def kind_table(summary: dict[str, Any], title: str) -> Table:
    """The figures per kind and overall, 78 columns wide at most: the kind (entry/axis,
    "pair", "null"), the cases flown, and each figure that counts for it."""
    t = Table(title=title, title_justify="left", box=box.SIMPLE_HEAD, pad_edge=False,
              collapse_padding=True)
    t.add_column("kind", no_wrap=True)
    t.add_column("n", justify="right", no_wrap=True)
    for head, _ in COLUMNS:  # whole headings: never cut to "shri…"
        t.add_column(head, justify="right", no_wrap=True, min_width=max(len(head), 5))

    def row(name: str, f: dict[str, Any], style: str | None = None) -> None:
        t.add_row(name, str(f["cases"] - f["failed"]), *(_pct(f[key]) for _, key in COLUMNS),
                  style=style)

    for kind, f in summary["by_kind"].items():
        row(_kind(kind), f)
    row("all", summary, "bold")
    targets = {k: (">=" if higher else "<=") + _pct(v) for k, (v, higher) in TARGETS.items()}
    t.add_row("target", "", *(targets[key] for _, key in COLUMNS), style="dim")
    return t


def _print(bench: Benchmark) -> None:
    console = Console(width=80)
    s = bench.summary()
    console.print(kind_table(s, f"gap blind check: seed {bench.seed}, {s['single']} single, "
                                f"{s['pair']} pairs, {s['outside']} outside, {s['null']} null; "
                                + ("calm air" if bench.turbulence == "calm"
                                   else f"{bench.turbulence} turbulence")))
    console.print("n: cases flown (failed ones listed below); right: the first named effect "
                  "on its axis is in the injected one's class; mag: median relative "
                  "magnitude error; both: both effects of a pair named; unexp: outside the "
                  "catalogue answered unexplained or partly unexplained; nogap: null cases "
                  "answered no_gap on every axis; shrink: median held-out shrink of the gap "
                  "above the null level where something is named.")
    for line in s["failed_cases"]:
        console.print(f"failed: {line}", overflow="fold")


def _aircraft(text: str) -> tuple[str, ...]:
    return tuple(a.strip() for a in text.split(",") if a.strip())


MAX_CASES = 10_000  # each case is a flight and a diagnosis (seconds each)


def gap_benchmark_command(
    n: Annotated[int, typer.Option("--n", "-n", help="number of drawn cases")] = 10,
    seed: Annotated[int, typer.Option(help="seed of the draw (0: development, "
                                           "1: held out, docs/gap_benchmark.md)")] = 0,
    nulls: Annotated[int, typer.Option(help="null cases (nothing injected)")] = 100,
    turbulence: Annotated[str, typer.Option(help="calm, light or moderate")] = "light",
    aircraft: Annotated[str, typer.Option(help="comma-separated aircraft drawn from")] =
        ",".join(AIRCRAFT),
    output: Annotated[str | None, typer.Option(
        "-o", "--output", help="folder: study.json, cases.jsonl (each case as it finishes; "
                               "a rerun skips them), summary.json")] = None,
    workers: opts.Workers = None,
    dask: opts.Dask = None,
    format: opts.Format = "table",
    quiet: opts.Quiet = False,
) -> None:
    """The gap diagnosis's blind check: N drawn cases (an aircraft and an effect of the
    catalogue, a pair, or an effect outside it) and NULLS null cases, flown in turbulence,
    diagnosed without being told, and scored per kind against the targets."""
    check_choice("--format", format, ("table", "json"))
    check_count("--n", n, low=1, high=MAX_CASES)
    check_count("--nulls", nulls, low=0, high=MAX_CASES)
    check_count("--seed", seed, low=0, high=MAX_SEED)
    check_paths({}, [Output("--output", output, folder=True)])
    names = _aircraft(aircraft)
    check(n, seed, nulls, turbulence, names, output, workers)
    with count_progress("gap blind check", show=not quiet) as update:
        progress = (lambda done, total: update(done, total)) if update else None
        bench = gap_benchmark(n, seed, nulls, turbulence, output, progress,
                              workers=workers, dask_address=dask, aircraft=names)
    if format == "json":
        print(json.dumps(bench.to_json(), indent=2))
    else:
        _print(bench)
