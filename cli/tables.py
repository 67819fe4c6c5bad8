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


def split_tables(title: str, heads: Sequence[str], rows: Sequence[Sequence[str]],
                 width: int, keep: int = 1) -> list[Table]:
    """``rows`` under ``heads`` as one table, or, when it is wider than ``width``
    (characters), as the fewest tables that fit, each repeating the first ``keep``
    columns and taking an even share of the others, so that no cell is folded and no
    header broken (a comparison of many designs at 80 columns). The later tables are
    titled ``(continued)``."""
    def need(i: int) -> int:  # a column's width: its widest cell, padding and a border
        return max(len(str(c)) for c in [heads[i], *(r[i] for r in rows)]) + 3

    base = 1 + sum(need(i) for i in range(keep))
    rest = list(range(keep, len(heads)))

    def fits(chunk: list[int]) -> bool:
        return base + sum(need(i) for i in chunk) <= width

    chunks = [rest]
    for parts in range(2, len(rest) + 1):
        if all(fits(c) for c in chunks):
            break
        size = -(-len(rest) // parts)
        chunks = [rest[k:k + size] for k in range(0, len(rest), size)]
    out = []
    for k, chunk in enumerate(chunks):
        cols = [*range(keep), *chunk]
        out.append(add_columns(Table(title=title if k == 0 else "(continued)"),
                               [heads[i] for i in cols], left=keep,
                               rows=[[r[i] for i in cols] for r in rows]))
    return out
