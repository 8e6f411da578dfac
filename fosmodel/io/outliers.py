"""Outliers of a record's columns: found per column, then refused, kept, clipped or dropped.

An outlier is farther than ``OUTLIER_K`` robust standard deviations from its column's
median (:func:`find_outliers`); ``OUTLIER_MODES`` say what becomes of them
(:func:`handle_outliers`), and every one is reported in the record's notes.

The default, ``"refuse"``, refuses a record when a column's outliers carry more than
``OUTLIER_SHARE`` (1 %) of its mean square about its median, and keeps them (noted) when
they carry less.  A sensor record's error model and noise terms are second moments: the
variance a fit explains, the Allan deviation at short averaging times, the white-noise
level.  Outliers that carry 1 % of the mean square move those by as much (a single spike of
1000 robust sigmas does so in any record under 100 million samples), and the user, not the
loader, knows whether they are the sensor's (``keep``), a glitch to bound (``clip``) or
samples to remove (``drop``).  Fewer cannot move the results beyond their own uncertainty:
refusing them would refuse clean records (a 13-sigma sample or six in a million).  Only
spikes count towards the share: runs of at most ``SPIKE_RUN`` outlying samples.  A longer
run is an event of the record (the sensor moved, a step, a shock), which the checks that
need a static record and the residual loop's effects name for what it is; it is noted.
A slow excursion beyond the bounds (a die temperature's warm-up, a drift), where the median
of the samples about an outlier lies beyond them too, is the signal, not outliers: it is noted
as such and left alone.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core.exceptions import InputError
from ..core.median import median
from .positions import positions
from .record import Record

OUTLIER_MODES = ("refuse", "keep", "clip", "drop")
#: What becomes of outliers unless the user says.
DEFAULT_OUTLIERS = "refuse"
#: An outlier is farther than ``OUTLIER_K`` robust standard deviations from the column median.
OUTLIER_K = 10.0
#: "refuse" refuses the outliers of a column that carry more than this share of its mean
#: square about its median.
OUTLIER_SHARE = 0.01
#: The longest run of consecutive outlying samples that counts as a spike (a glitch).
SPIKE_RUN = 3
#: Samples about an outlier whose median tells a slow excursion (beyond the bounds too) from
#: a glitch or a knock (back where the rest of the record is).
SLOW_WINDOW = 101
_MAD_TO_SIGMA = 1.4826


class Outliers(NamedTuple):
    """A column's outliers: where they are, the bounds they lie outside, their share.

    ``share`` is the share of the column's mean square about its median that its spikes
    (runs of at most ``SPIKE_RUN`` samples) carry; ``samples`` leaves out ``slow``, the
    samples of a slow excursion beyond the bounds (the signal itself).
    """

    samples: np.ndarray
    low: float
    high: float
    share: float
    spikes: np.ndarray
    slow: np.ndarray


def _window_medians(x: np.ndarray, index: np.ndarray, half: int) -> np.ndarray:
    """Return the median of the ``2 half + 1`` samples about each of ``index``.

    The window is moved, not clipped, at the record's ends: a clipped one repeats the end
    sample, so a glitch in the first samples would be its own neighbourhood.  Taken in chunks,
    so that a column with many outliers does not build one large array.
    """
    width = min(2 * half + 1, len(x))
    first = np.clip(index - half, 0, len(x) - width)
    out = np.empty(index.size)
    for start in range(0, index.size, 8192):
        around = first[start:start + 8192, None] + np.arange(width)
        out[start:start + 8192] = np.median(x[around], axis=1)
    return out


def _slow_and_spikes(x: np.ndarray, index: np.ndarray,
                     limit: float) -> tuple[np.ndarray, np.ndarray]:
    """Mark the sorted outlying indices of a slow excursion, and those that are spikes.

    A sample is part of a slow excursion (a warm-up, a drift: the signal itself, not a
    fault) where the median of the ``SLOW_WINDOW`` samples about it lies beyond half the
    bounds (half, so that the noise about the excursion where it crosses a bound is part of
    it); a glitch or a knock leaves that median where the rest of the record is.  A spike
    is an outlier in a run of at most ``SPIKE_RUN`` in a row that is not part of such an
    excursion.
    """
    x = np.asarray(x, dtype=float)
    slow = np.abs(_window_medians(x, index, SLOW_WINDOW // 2) - median(x)) > limit / 2
    starts = np.flatnonzero(np.diff(index, prepend=index[0] - 2) != 1)
    lengths = np.diff(starts, append=index.size)
    return slow, np.repeat(lengths <= SPIKE_RUN, lengths) & ~slow


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
            slow, spike = _slow_and_spikes(x, index, OUTLIER_K * sigma)
            spikes = index[spike]
            share = float(deviation[spikes] @ deviation[spikes]) / float(deviation @ deviation)
            found[name] = Outliers(index[~slow], center - OUTLIER_K * sigma,
                                   center + OUTLIER_K * sigma, share, spikes, index[slow])
    return found


def handle_outliers(record: Record, found: dict[str, Outliers], mode: str,
                     first_line: int, hold: bool = False) -> None:
    """Note each column's outliers in the record; refuse, keep, clip or drop them (``mode``).

    With ``hold``, a column that "refuse" would refuse the record for is put in
    ``record.held`` with its refusal instead (refused if it is analysed, else left out).

    Raises
    ------
    InputError
        ``mode`` "refuse" and a column whose outliers carry more than ``OUTLIER_SHARE`` of its
        mean square about its median (not with ``hold``); "drop" from a record without a
        time column.
    """
    rule = f"|x - median| > {OUTLIER_K:g} x 1.4826 MAD"
    if not found:
        if mode not in ("keep", "refuse"):
            record.notes.append(f"outliers={mode!r}: no outliers found ({rule})")
        return
    if mode == "refuse" and hold:
        for name, out in list(found.items()):
            if out.share > OUTLIER_SHARE:
                record.held[name] = _refusal(record, name, out, rule, first_line)
                del found[name]
    elif mode == "refuse":
        _refuse(record, found, rule, first_line)
    for name, out in found.items():
        bounds = f"[{out.low:.6g}, {out.high:.6g}]"
        if out.slow.size:  # a warm-up or a drift: the signal itself
            record.notes.append(
                f"column {name!r}: {out.slow.size} sample(s) outside {bounds} where the "
                f"median of the {SLOW_WINDOW} samples about them is far out too, a slow excursion "
                "(a warm-up, a drift): not counted as outliers, kept")
            if not out.samples.size:
                continue
        done = {"keep": "kept (outliers='clip' or 'drop' handles them)",
                "refuse": (f"kept: they carry {_percent(out.share)} of its mean square about its "
                           f"median, under the {_percent(OUTLIER_SHARE)} at which the record is "
                           "refused (outliers='keep' or 'clip' or 'drop' says otherwise)"),
                "clip": f"clipped to {bounds}", "drop": "dropped"}[mode]
        record.notes.append(
            f"column {name!r}: {out.samples.size} outlier(s) ({rule}, outside {bounds}) at "
            f"{positions(out.samples, first_line)}; {done}")
        if mode == "clip":  # the outliers only: a slow excursion beside them is the signal
            x = np.array(record.data[name], dtype=float)
            x[out.samples] = np.clip(x[out.samples], out.low, out.high)
            record.data[name] = x
    if mode == "drop":
        _drop_rows(record, np.unique(np.concatenate([o.samples for o in found.values()])))


def _refuse(record: Record, found: dict[str, Outliers], rule: str, first_line: int) -> None:
    """Refuse the record if a column's outliers carry over ``OUTLIER_SHARE`` of its mean square."""
    name, out = max(found.items(), key=lambda item: item[1].share)
    if out.share <= OUTLIER_SHARE:
        return
    raise InputError(_refusal(record, name, out, rule, first_line))


def _refusal(record: Record, name: str, out: Outliers, rule: str, first_line: int) -> str:
    """Return the refusal of a record for the outliers ``out`` of its column ``name``."""
    return (
        f"{record.source}: column {name!r}: {out.spikes.size} outlier(s) ({rule}) at "
        f"{positions(out.spikes, first_line)} carry {_percent(out.share)} of its mean square "
        f"about its median: the fit's error, the variance and the Allan deviation would move "
        f"as much; say what they are with outliers='keep' (if they are the sensor's), or "
        f"outliers='clip' or 'drop'")


def _percent(share: float) -> str:
    return f"{100 * share:.2g} %"


def _drop_rows(record: Record, rows: np.ndarray) -> None:
    if record.time is None:
        raise InputError(
            f"{record.source}: outliers='drop' would remove {rows.size} sample(s) from a record "
            "without a time column, which breaks the uniform sample spacing the models assume; "
            "use outliers='clip' (or 'keep')")
    keep = np.ones(record.n_samples, dtype=bool)
    keep[rows] = False
    record.data = {name: x[keep] for name, x in record.data.items()}
    record.time = record.time[keep]
    record.notes.append(
        f"dropped {rows.size} row(s) with an outlier in any column: the record is no longer "
        "uniformly spaced; its time column keeps the gaps")
