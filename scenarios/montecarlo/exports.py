"""A study's tables as files for a paper: Markdown and LaTeX beside the CSV, numbers to
four significant digits, NaN as an empty cell (LaTeX through pandas' ``to_latex``,
booktabs rules)."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd


def _text(v: object) -> str:
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.4g}"
    return str(v)


def markdown_table(df: pd.DataFrame, index: bool = True) -> str:
    """``df`` as a Markdown table (the index as the first column when ``index``).

    Parameters
    ----------
    df : pandas.DataFrame
        The table.
    index : bool, optional
        Include the index. Default True.

    Returns
    -------
    str
        Markdown text.
    """
    frame = df.reset_index() if index else df
    head = [str(c) for c in frame.columns]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(_text(v) for v in row) + " |"
              for row in frame.itertuples(index=False)]
    return "\n".join(lines) + "\n"


def latex_table(df: pd.DataFrame, index: bool = True) -> str:
    """``df`` as a LaTeX ``tabular`` (booktabs), underscores and percent signs escaped.

    Parameters
    ----------
    df : pandas.DataFrame
        The table.
    index : bool, optional
        Include the index. Default True.

    Returns
    -------
    str
        LaTeX text.
    """
    frame = df.reset_index() if index else df
    frame = frame.map(_text)
    return frame.to_latex(index=False, escape=True)


def write_tables(df: pd.DataFrame, stem: str | Path, index: bool = True) -> list[Path]:
    """Write ``stem``.md and ``stem``.tex (``markdown_table``, ``latex_table``); their paths.

    Parameters
    ----------
    df : pandas.DataFrame
        The table.
    stem : str or Path
        Output path; its suffix is replaced.
    index : bool, optional
        Include the index. Default True.

    Returns
    -------
    list[Path]
        The .md and .tex paths.
    """
    stem = Path(stem)
    md, tex = stem.with_suffix(".md"), stem.with_suffix(".tex")
    md.write_text(markdown_table(df, index), encoding="utf-8")
    tex.write_text(latex_table(df, index), encoding="utf-8")
    return [md, tex]
