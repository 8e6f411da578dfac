"""Where a sample is in its file, as the messages and notes name it.

A CSV's samples are named by their file line (the first line being line 1), the rows of a
``.npy`` or Parquet file (or the messages of a log) by their row number from 0.
"""

from __future__ import annotations

import numpy as np

_SHOWN = 5  # positions listed in a note


def where(i: int, first_line: int) -> str:
    """Sample ``i`` as a file line (CSV) or a row number (``.npy``, Parquet)."""
    return f"line {i + first_line}" if first_line else f"row {i}"


def positions(index: np.ndarray, first_line: int) -> str:
    """List the first samples of ``index`` as a note names them, with their file lines if any."""
    shown = [int(i) for i in index[:_SHOWN]]
    more = ", ..." if index.size > _SHOWN else ""
    text = "sample(s) " + ", ".join(map(str, shown)) + more
    if first_line:
        text += " (line(s) " + ", ".join(str(i + first_line) for i in shown) + more + ")"
    return text
