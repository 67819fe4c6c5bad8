"""Rich tables of estimates and scores, shared by ``identify`` and ``demo``, and
``add_columns``: columns that fold a cell too wide for the terminal onto a second line
instead of cutting it with an ellipsis, so no digit is ever lost (80 columns, piped)."""

from __future__ import annotations

from collections.abc import Sequence

from rich.console import Console
from rich.table import Table

from flightid.identification.engine import convergence
from flightid.identification.estimate import Estimate
from flightid.identification.evaluation.scoring import STATUS_ESTIMATED, Score


def add_columns(table: Table, heads: Sequence[str], left: int = 1,
                rows: Sequence[Sequence[str]] = ()) -> Table:
    """Add ``heads`` as columns of ``table`` (the first ``left`` left-justified, the rest
    right-justified), every one folding an overlong cell onto a second line rather than
    truncating it (a table too wide for the terminal loses no digit); then ``rows``."""
    for i, head in enumerate(heads):
        table.add_column(head, justify="left" if i < left else "right", overflow="fold")
    for r in rows:
        table.add_row(*r)
    return table


def estimate_table(est: Estimate) -> Table:
    """Parameter, value, standard error and |value|/std of one estimate; unidentifiable
    parameters as text, never as numbers."""
    window = est.fit.get("window")
    span = f"  window {window[0]:g}-{window[1]:g} s" if window else ""
    table = Table(title=f"{est.method} {est.fit.get('model', '')}{span}  "
                        f"std: {est.std_kind.value}",
                  caption=convergence.verdict_line(est) or None, caption_style="bold red")
    add_columns(table, ("parameter", "value", "std", "|value|/std"))
    for name, value, std in zip(est.names, est.values, est.std, strict=True):
        ratio = abs(value) / std if std > 0 else float("inf")
        table.add_row(name, f"{value:.5g}", f"{std:.3g}", f"{ratio:.1f}")
    for name, reason in est.unidentifiable.items():
        table.add_row(name, "unidentifiable", reason, "", style="yellow")
    for name, held in (est.fit.get("a_priori") or {}).items():
        table.add_row(name, f"{held['value']:.5g}", "held", f"a priori: {held['source']}",
                      style="dim")
    return table


def score_table(scored: Score) -> Table:
    """Truth, estimate, std, error and error/std per derivative; the verdict as caption."""
    title = f"{scored.method} vs truth" if scored.method else "estimate vs truth"
    table = Table(title=title, caption=scored.verdict)
    add_columns(table, ("derivative", "truth", "estimate", "std", "error", "error/std"))
    for r in scored.rows:
        if r.status == STATUS_ESTIMATED:
            style = "" if abs(r.sigmas) <= scored.n_sigma else "red"
            table.add_row(r.name, f"{r.truth:.5g}", f"{r.estimate:.5g}", f"{r.std:.3g}",
                          f"{r.error:+.3g}", f"{r.sigmas:+.2f}", style=style)
        else:
            label = r.status + (f": {r.reason}" if r.reason else "")
            table.add_row(r.name, f"{r.truth:.5g}", label, "", "", "", style="yellow")
    return table


def print_score(scored: Score, console: Console | None = None) -> None:
    """The score table, then its one-line verdict."""
    console = console or Console()
    console.print(score_table(scored))
