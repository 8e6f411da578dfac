"""Outliers of a record's columns: found per column, then kept, clipped or dropped.

An outlier is farther than ``OUTLIER_K`` robust standard deviations from its column's
median (:func:`find_outliers`); ``OUTLIER_MODES`` say what becomes of them
(:func:`handle_outliers`), and every one is reported in the record's notes.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core.exceptions import InputError
from ..core.median import median
from .positions import positions
from .record import Record

OUTLIER_MODES = ("keep", "clip", "drop")
#: An outlier is farther than ``OUTLIER_K`` robust standard deviations from the column median.
OUTLIER_K = 10.0
_MAD_TO_SIGMA = 1.4826


class Outliers(NamedTuple):
    """A column's outliers: their sample numbers, and the bounds outside which they lie."""

    samples: np.ndarray
    low: float
    high: float


def find_outliers(data: dict[str, np.ndarray]) -> dict[str, Outliers]:
    """Find samples farther than ``OUTLIER_K`` robust standard deviations from the median.

    The robust standard deviation is 1.4826 times the median absolute
    deviation; when more than half the column sits on its median (MAD = 0, as
    for a die temperature on 0.09 C steps) it is the column's resolution, the
    smallest step between its values.  A constant column has no outliers.
    """
    found = {}
    buffer = np.empty(max(len(x) for x in data.values()))  # one for every column's deviations
    for name, x in data.items():
        center = median(x)
        deviation = np.abs(np.subtract(x, center, out=buffer[: len(x)]), out=buffer[: len(x)])
        sigma = _MAD_TO_SIGMA * median(deviation)
        if sigma == 0:
            steps = np.diff(np.unique(x))
            sigma = float(steps.min()) if steps.size else 0.0
        index = np.flatnonzero(deviation > OUTLIER_K * sigma)
        if sigma > 0 and index.size:
            found[name] = Outliers(index, center - OUTLIER_K * sigma, center + OUTLIER_K * sigma)
    return found


def handle_outliers(record: Record, found: dict[str, Outliers], mode: str,
                     first_line: int) -> None:
    """Note each column's outliers in the record, and keep, clip or drop them (``mode``)."""
    rule = f"|x - median| > {OUTLIER_K:g} x 1.4826 MAD"
    if not found:
        if mode != "keep":
            record.notes.append(f"--outliers {mode}: no outliers found ({rule})")
        return
    done = {"keep": "kept (--outliers clip or drop handles them)", "clip": "clipped to",
            "drop": "dropped"}[mode]
    for name, out in found.items():
        bounds = f"[{out.low:.6g}, {out.high:.6g}]"
        record.notes.append(
            f"column {name!r}: {out.samples.size} outlier(s) ({rule}, outside {bounds}) at "
            f"{positions(out.samples, first_line)}; "
            f"{done}{' ' + bounds if mode == 'clip' else ''}")
        if mode == "clip":
            record.data[name] = np.clip(record.data[name], out.low, out.high)
    if mode == "drop":
        _drop_rows(record, np.unique(np.concatenate([o.samples for o in found.values()])))


def _drop_rows(record: Record, rows: np.ndarray) -> None:
    if record.time is None:
        raise InputError(
            f"{record.source}: --outliers drop would remove {rows.size} sample(s) from a record "
            "without a time column, which breaks the uniform sample spacing the models assume; "
            "use --outliers clip (or keep)")
    keep = np.ones(record.n_samples, dtype=bool)
    keep[rows] = False
    record.data = {name: x[keep] for name, x in record.data.items()}
    record.time = record.time[keep]
    record.notes.append(
        f"dropped {rows.size} row(s) with an outlier in any column: the record is no longer "
        "uniformly spaced; its time column keeps the gaps")
