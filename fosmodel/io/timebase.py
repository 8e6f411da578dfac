"""A record's time base: its rate, and the checks and repairs of its time column.

The rate is given, read from a CSV's preamble (:func:`fosmodel.io.csv_reader.preamble_rate`)
or measured from the time column, which must go forwards (:func:`check_order`), without gaps
unless asked (``gaps``: ``GAP_MODES``) and at a steady rate.  A host's bursty receive time is
detected and, on request, replaced by uniform sample times; gaps are filled by linear
interpolation or kept as contiguous segments (:func:`handle_gaps`).
"""

from __future__ import annotations

import numpy as np

from ..core.exceptions import InputError
from ..core.median import median
from .positions import where
from .time_units import IMU_RATES, TIME_COLUMNS, is_imu_rate

__all__ = ["GAP_MODES", "IMU_RATES", "RATE_RANGE", "REFUSING", "STILL_ROWS", "TIME_COLUMNS",
           "check_imu_rate", "check_order", "handle_gaps", "time_base"]

GAP_MODES = ("refuse", "contiguous", "fill", "segments")
REFUSING = ("refuse", "contiguous")  # the gap modes that refuse a record with gaps
RATE_TOLERANCE = 0.01
_BURSTY_MIN_SAMPLES = 100
#: A time column that stands still over this many rows of a block is no sensor's.
STILL_ROWS = 1000
#: Sample rates outside this range (Hz) are a unit mistake, not a sensor.
RATE_RANGE = (1e-6, 1e9)


def time_base(time: np.ndarray, rate: float | None, given_by: str, uniform: bool, src: str,
               name: str, first_line: int, notes: list[str],
               gaps: str = "refuse",
               counts: tuple[np.ndarray, int] | None = None) -> tuple[float, np.ndarray]:
    """Return the rate and time of a record with a time column, after checking the column.

    With ``gaps`` that do not refuse, the gap check is left to :func:`handle_gaps`
    and the rate is the median interval's.  A rate no IMU has is refused unless ``--rate``
    gave it (:func:`check_imu_rate`).  ``counts``, the column's integers and their counts per
    second (1000 for milliseconds), give the rate from integer differences: int64
    milliseconds 10 apart are exactly 100 Hz, whatever their epoch.
    """
    if len(time) < 2:
        if rate is None:
            raise InputError(f"{src}: a single sample cannot give a rate; pass rate=")
        return rate, time
    dt = np.diff(time)
    step = median(dt)
    bursty = _is_bursty(time, dt, step)
    check_order(time, dt, src, name, first_line, repeats_allowed=bursty)
    if not (bursty or uniform or gaps not in REFUSING):
        _check_gaps(dt, step, src, name, first_line, segments=gaps == "refuse")
    with np.errstate(over="ignore"):  # a span of a few subnormal seconds: checked below
        measured = (len(time) - 1) / (time[-1] - time[0])  # uniform: the span is the best one
        if gaps not in REFUSING and not (bursty or uniform):
            measured = 1.0 / step  # with gaps, the span would count them
    if counts is not None and counts[0][-1] > counts[0][0]:  # in exact integer arithmetic
        ticks, per_second = counts
        span = int(ticks[-1]) - int(ticks[0])
        measured = (len(ticks) - 1) * per_second / span
        if gaps not in REFUSING and not (bursty or uniform):
            measured = per_second / int(median(np.diff(ticks)))
    if not RATE_RANGE[0] <= measured <= RATE_RANGE[1]:
        raise InputError(f"{src}: column {name!r} gives a sample rate of {measured:.6g} Hz, "
                         f"outside {RATE_RANGE[0]:g} to {RATE_RANGE[1]:g} Hz; is it in seconds? "
                         f"(scale={{{name!r}: 0.001}} turns milliseconds into seconds)")
    kind = "the effective rate of the bursty time column" if bursty else "the time column"
    if rate is not None and abs(measured - rate) > RATE_TOLERANCE * rate:
        raise InputError(f"{src}: {given_by} disagrees with {kind} ({measured:.6g} Hz)")
    check_imu_rate(measured, given_by, f"column {name!r} gives", src, name)
    rate = rate if rate is not None else measured
    if bursty:
        n = len(time)
        lines = f"lines {first_line}-{first_line + n - 1}" if first_line else f"rows 0-{n - 1}"
        said = (f"column {name!r} ({lines}) looks like a host's bursty receive time (median "
                f"interval {step:.3g} s, mean {np.mean(dt):.3g} s); effective rate "
                f"{measured:.6g} Hz ((N - 1) / span)")
        if not (uniform or given_by):
            raise InputError(f"{src}: {said}: pass uniform=True to take the samples as uniformly "
                             "spaced at that rate, or rate=HZ")
        notes.append(f"{said}: samples taken as uniformly spaced at {rate:.6g} Hz; time is "
                     "sample number / rate")
    elif uniform:
        n_gaps = int(np.count_nonzero(dt > 1.5 * step))
        notes.append(f"uniform=True: samples taken as uniformly spaced at {rate:.6g} Hz, the rate "
                     f"of column {name!r} ({n_gaps} gap(s) in it ignored); time is sample number "
                     "/ rate")
    if bursty or uniform:
        time = np.arange(len(time)) / rate
    return rate, time


def check_imu_rate(rate: float, given_by: str, said: str, src: str, name: str = "") -> None:
    """Refuse a rate no IMU samples at (``IMU_RATES``) unless the user gave it (``rate=``).

    ``said`` says what gave the rate (``"column 'time' gives"``), ``name`` the time column.
    """
    if is_imu_rate(rate) or given_by.startswith("rate="):
        return
    scale = (f"; if column {name!r} counts milliseconds, scale={{{name!r}: 0.001}} gives seconds"
             if name else "")
    raise InputError(f"{src}: {said} a sample rate of {rate:.6g} Hz, outside the "
                     f"{IMU_RATES[0]:g} Hz to {IMU_RATES[1] / 1e3:g} kHz an IMU samples at; if "
                     f"that is the record's rate, confirm it with rate={rate:.6g}{scale}")


def handle_gaps(data: dict[str, np.ndarray], time: np.ndarray, gaps: str, src: str, name: str,
                 first_line: int, notes: list[str]) -> tuple[np.ndarray, list[slice] | None]:
    """Fill the gaps of a regular time column, or list its contiguous segments."""
    dt = np.diff(time)
    step = median(dt)
    at = np.flatnonzero(dt > 1.5 * step)
    if not at.size:
        return time, None
    first = f"first at {where(int(at[0]) + 1, first_line)}"
    if gaps == "segments":
        bounds = [0, *(at + 1).tolist(), len(time)]
        segments = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
        notes.append(f"column {name!r}: {at.size} gap(s), {first}; kept as {len(segments)} "
                     f"contiguous segments of {', '.join(str(s.stop - s.start) for s in segments)}"
                     " samples")
        return time, segments
    grid = time[0] + step * np.arange(int(round((time[-1] - time[0]) / step)) + 1)
    for key in data:
        data[key] = np.interp(grid, time, data[key])
    notes.append(f"column {name!r}: {at.size} gap(s), {first}; filled by linear interpolation "
                 f"({len(grid) - len(time)} samples added onto the {step:.6g} s grid)")
    return grid, None


def _is_bursty(time: np.ndarray, dt: np.ndarray, step: float) -> bool:
    """Whether time is a host's receive time: most intervals far below the mean, a steady rate.

    Bursty when the record has at least ``_BURSTY_MIN_SAMPLES`` samples, the
    median interval is under half the mean interval (samples arrive in bursts
    separated by long waits), and every tenth of the time span holds within
    25 % of a tenth of the samples (unlike a record with a long gap).
    """
    if len(time) < _BURSTY_MIN_SAMPLES or not time[-1] > time[0] or np.any(dt < 0):
        return False
    if step >= 0.5 * np.mean(dt):
        return False
    counts = _tenths(time)
    return bool(np.all(np.abs(counts - len(time) / 10) <= 0.25 * len(time) / 10))


def _tenths(time: np.ndarray) -> np.ndarray:
    """Count the samples in each tenth of the span, as ``np.histogram(time, 10)`` does (sorted).

    Counted by bisection at the bin edges rather than by a pass over the record.
    """
    edges = np.linspace(time[0], time[-1], 11)
    return np.diff([*np.searchsorted(time, edges[:-1]), len(time)])


def check_order(time: np.ndarray, dt: np.ndarray, src: str, name: str, first_line: int, *,
                 repeats_allowed: bool, offset: int = 0) -> None:
    """Refuse time that goes backwards (or repeats, unless allowed).

    ``offset`` is the sample number of ``time[0]`` in the record.
    """
    bad = np.flatnonzero(dt < 0 if repeats_allowed else dt <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        kind = "repeats" if dt[bad[0]] == 0 else "goes backwards"
        raise InputError(f"{src}: column {name!r}, {where(offset + i, first_line)}: time {kind} "
                         f"({float(time[i - 1])!r} then {float(time[i])!r})")


def _check_gaps(dt: np.ndarray, step: float, src: str, name: str, first_line: int,
                segments: bool) -> None:
    """Refuse gaps; the message offers filling them, and fitting on the pieces if ``segments``."""
    gaps = np.flatnonzero(dt > 1.5 * step)
    if gaps.size:
        i = int(gaps[0]) + 1
        raise InputError(
            f"{src}: column {name!r}, {where(i, first_line)}: a gap of {dt[gaps[0]]:.6g} s "
            f"where the sample interval is {step:.6g} s ({gaps.size} gap(s) in the record); "
            "pass gaps='fill' to interpolate across them"
            + (" or gaps='segments' to fit on the pieces" if segments else "")
        )
