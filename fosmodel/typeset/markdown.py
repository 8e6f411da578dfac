"""Markdown pipe tables: the tables of the reports and of the docs pages."""

from __future__ import annotations

import pandas as pd


def markdown_table(frame: pd.DataFrame, digits: int = 6) -> str:
    """Write a pipe table; floats with ``digits`` significant digits, NaN as an empty cell."""
    cols = [str(c) for c in frame.columns]
    rows = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for rec in frame.itertuples(index=False):
        rows.append("| " + " | ".join(_cell(v, digits) for v in rec) + " |")
    return "\n".join(rows)


def _cell(v: object, digits: int = 6) -> str:
    if isinstance(v, float):
        return "" if v != v else f"{v:.{digits}g}"
    return str(v)
