"""``flightid study-compare A/ B/ ...``: finished Monte Carlo studies side by side (the
work is ``scenarios.montecarlo.study_compare``): each derivative's scatter and mean bound
by study, and each study against the first with intervals."""

from __future__ import annotations

import json
import math
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.cli import study_options as opts
from flightid.cli.checks import check_choice
from flightid.cli.tables import add_columns
from flightid.scenarios.montecarlo.intervals import LEVEL, interval_text
from flightid.scenarios.montecarlo.study_compare import against_first, compare_studies


def _cell(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{v:.4g}"


def study_compare_command(
    studies: Annotated[list[str], typer.Argument(help="two or more study folders")],
    format: opts.Format = "table",
) -> None:
    """Compare finished Monte Carlo studies: scatter and mean bound by study, and each
    study's scatter against the first's with 90 % intervals."""
    check_choice("--format", format, ("table", "json"))
    comparison = compare_studies(studies)
    versus = against_first(comparison)
    if format == "json":
        print(json.dumps({"studies": [r.study_dir for r in comparison.results],
                          "names": [r.kind for r in comparison.results],
                          "frame": comparison.frame().to_dict(orient="records"),
                          "against_first": {
                              k: {"ratios": json.loads(v["ratios"].to_json(orient="index")),
                                  "mean_relative_scatter": v["mean_relative_scatter"]}
                              for k, v in versus.items()}}, indent=2, default=str))
        return
    console = Console()
    kinds = [r.kind for r in comparison.results]
    legend = ", ".join(f"{chr(65 + i)} = {k}" for i, k in enumerate(kinds))
    short = [chr(65 + i) for i in range(len(kinds))]
    for column, title in (("scatter", "scatter of the estimates"),
                          ("mean_bound", "mean reported bound")):
        wide = comparison.table(column)
        console.print(add_columns(Table(title=f"{title} by study ({legend})"),
                                  ["derivative", *short], rows=[
            [str(n), *(_cell(float(wide.loc[n, k])) for k in kinds)] for n in wide.index]))
    level = f"{100 * LEVEL:.0f} %"
    for i, (k, v) in enumerate(versus.items(), start=1):
        r = v["ratios"]
        console.print(add_columns(
            Table(title=f"scatter {short[i]} / A ({k} / {kinds[0]}), {level} interval"),
            ["derivative", "ratio", "interval", "kind", "smaller"], rows=[
                [str(n), f"{row['ratio']:.3g}", interval_text(row['low'], row['high']),
                 row["interval"], {k: short[i], kinds[0]: "A"}.get(row["winner"],
                                                                    "not clear")]
                for n, row in r.iterrows()]))
        m = v["mean_relative_scatter"]
        console.print(f"{k}: mean scatter/|truth| {m['ratio']:.3f} times {kinds[0]}'s "
                      f"({level} paired interval {m['low']:.3f}-{m['high']:.3f}; "
                      f"{len(m['derivatives'])} derivatives with non-zero truth, "
                      f"{m['realizations']} realizations both estimated them all)")
