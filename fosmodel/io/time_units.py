"""The unit of a time column: seconds, or counts of milliseconds, microseconds or nanoseconds.

Loggers write time as integer counts as often as in seconds: milliseconds since boot (an
Arduino's ``millis()``), microseconds (PX4), nanoseconds (ROS stamps), often since 1970.
Read as seconds such a column makes a 100 Hz record a 0.1 Hz one.  :func:`time_unit` tells
the unit, from (in this order):

* the column's name: ``time_ms``, ``t_us``, ``timestamp_ns`` (``_s``: seconds);
* for a column of integers (a column in seconds shows fractions): the given rate
  (``--rate``), the unit in which the median interval gives it; else the magnitude, the unit
  in which the first value is a date of 2000-2100 since 1970 and the median interval a rate an
  IMU has (1 Hz to 100 kHz); else the spacing, the unit in which the median interval gives a
  rate from 10 Hz to 10 kHz, the rates IMUs are read at (units are a thousand apart: exactly
  one does).

Otherwise the column is in seconds.  Whole seconds from 1970 at 1 Hz stay seconds, but whole
seconds from zero at 1 Hz are read as milliseconds at 1 kHz: ``--rate 1`` or ``--scale
time=1`` says otherwise.  The caller says the unit in a note.
"""

from __future__ import annotations

import re
from datetime import datetime, timezone
from typing import NamedTuple

import numpy as np

from ..core.median import median

#: Seconds per count of each unit.
UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
_WORDS = {"s": "seconds", "ms": "milliseconds", "us": "microseconds", "ns": "nanoseconds"}
#: The names of a time column, seconds first; the suffix is the unit.
TIME_COLUMNS = ("time", "time_s", "t_s", "timestamp", "timestamp_s", "time_ms", "time_us",
                "time_ns", "t_ms", "t_us", "t_ns", "timestamp_ms", "timestamp_us",
                "timestamp_ns")
_SUFFIX = re.compile(r"_(s|ms|us|ns)$")
#: The sample rates (Hz) of an IMU: a record outside is refused unless rate= confirms it.
IMU_RATES = (1.0, 1e5)
#: The rates an IMU is most often read at: the spacing of integer counts in this range (from
#: 10 Hz, below 10 kHz: a factor of a thousand, the step between units) tells their unit.
_USUAL_RATES = (10.0, 1e4)
#: 2000-01-01 and 2100-01-01 in seconds since 1970: the dates a timestamp since 1970 has.
_EPOCH = (946_684_800.0, 4_102_444_800.0)
_HEAD = 1000  # rows looked at first for a fraction
_TOLERANCE = 0.01  # of a given rate, as the time base allows


class TimeUnit(NamedTuple):
    """A time column's unit, its seconds per count, and why (empty for seconds by default)."""

    unit: str
    seconds: float
    why: str

    def note(self, name: str) -> str:
        """Say how the column is read, for the record's notes."""
        return (f"column {name!r} read in {_WORDS[self.unit]} ({self.why}); scale={{{name!r}: "
                "FACTOR} gives its seconds per count instead")


def time_unit(name: str, time: np.ndarray, rate: float | None = None) -> TimeUnit:
    """Return the unit of the time column ``name`` holding ``time``.

    Parameters
    ----------
    name : str
        The column's name (one of ``TIME_COLUMNS``).
    time : ndarray
        Its values, as read.
    rate : float, optional
        The sample rate the user gave: a unit in which the spacing does not give it is not
        the column's.

    Returns
    -------
    TimeUnit
        ``("s", 1.0, "")`` unless the name or the integers tell another unit.

    Examples
    --------
    >>> time_unit("time", np.arange(0, 5000, 10.0)).unit  # every 10 ms: 100 Hz
    'ms'
    >>> time_unit("time", np.arange(0, 5, 0.01)).unit
    's'
    >>> time_unit("t_us", np.arange(0, 5000, 10.0)).why
    'by its name'
    """
    suffix = _SUFFIX.search(name)
    if suffix and suffix.group(1) != "s":
        return TimeUnit(suffix.group(1), UNITS[suffix.group(1)], "by its name")
    seconds = TimeUnit("s", 1.0, "")
    if suffix or len(time) < 2 or not _integers(time):
        return seconds
    step = median(np.diff(time))
    if not step > 0:
        return seconds  # the time base says what is wrong with the column
    rates = {unit: 1.0 / (step * per_count) for unit, per_count in UNITS.items()}
    said = f"integers {step:g} apart"
    given = [u for u in UNITS if rate is not None and abs(rates[u] - rate) <= _TOLERANCE * rate]
    if given:
        return seconds if given[0] == "s" else TimeUnit(given[0], UNITS[given[0]],
                                                        f"{said}, rate={rate:g} Hz")
    dates = [u for u in UNITS if is_imu_rate(rates[u])
             and _EPOCH[0] <= time[0] * UNITS[u] <= _EPOCH[1]]
    if not dates and is_imu_rate(rates["s"]):
        # whole seconds at 1 Hz or more: a slow logger (a day-long thermal test at 1 Hz), not
        # milliseconds at 1 kHz, which loggers that count milliseconds seldom reach exactly
        return seconds
    usual = [u for u in UNITS if _USUAL_RATES[0] <= rates[u] < _USUAL_RATES[1]]
    unit = dates[0] if dates else usual[0] if usual else "s"
    if unit == "s":
        return seconds
    why = f"{said}: {rates[unit]:.6g} Hz, where seconds would give {rates['s']:.6g} Hz"
    if _EPOCH[0] <= time[0] * UNITS[unit] <= _EPOCH[1]:
        day = datetime.fromtimestamp(time[0] * UNITS[unit], timezone.utc)
        why += f"; from {day:%Y-%m-%d %H:%M} UTC"
    return TimeUnit(unit, UNITS[unit], why)


def _integers(x: np.ndarray) -> bool:
    head = x[:_HEAD]  # a time in seconds shows a fraction within its first rows
    return bool(np.array_equal(head, np.rint(head)) and np.array_equal(x, np.rint(x)))


def is_imu_rate(rate: float) -> bool:
    """Whether ``rate`` (Hz) is one an IMU samples at (``IMU_RATES``, give or take 1 %).

    A logger's clock moves its rate: a 1 Hz topic may time out at 0.9999 Hz.
    """
    return IMU_RATES[0] * (1 - _TOLERANCE) <= rate <= IMU_RATES[1] * (1 + _TOLERANCE)
