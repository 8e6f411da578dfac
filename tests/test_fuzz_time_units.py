"""Fuzzing the time unit of integer timestamps (hypothesis): a drawn logger's counts come back
in the unit they were written in, and nothing else is taken for counts.

Beside the record fuzzer (``tests/test_fuzz_cli.py``) and the model schema's
(``tests/test_fuzz_schema.py``).  A logger is drawn as a unit, an interval in that unit and an
origin (from boot, or a date of 2000-2100 since 1970); its timestamps are the integer counts.
Derandomized and few examples: a few seconds in CI.
"""

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from fosmodel.io.time_units import UNITS, is_imu_rate, time_unit

SETTINGS = settings(max_examples=100, deadline=None, derandomize=True)
COUNTS = ("ms", "us", "ns")
YEAR_2000, YEAR_2100 = 946_684_800, 4_102_444_800


def _stamps(unit, step, origin, n):
    return origin + step * np.arange(n, dtype=float)


@st.composite
def loggers(draw, rates=(10.0, 1e4)):
    """A unit, an integer interval in it giving a rate in ``rates`` (Hz), a length."""
    unit = draw(st.sampled_from(COUNTS))
    per_second = round(1 / UNITS[unit])  # counts in a second, exactly
    low = per_second // int(rates[1]) + 1  # the rate below rates[1]
    high = per_second // int(rates[0])  # the rate from rates[0]
    return unit, draw(st.integers(max(low, 1), high)), draw(st.integers(20, 2000))


@SETTINGS
@given(logger=loggers(), origin=st.integers(0, 900_000_000))
def test_counts_from_boot_come_back_in_their_unit(logger, origin):
    unit, step, n = logger
    # whole counts 1 apart are read as seconds at 1 Hz (a slow logger), not as 1 kHz in ms
    assume(not (unit == "ms" and step == 1))
    read = time_unit("time", _stamps(unit, step, origin, n))
    assert read.unit == unit and read.seconds == UNITS[unit]
    assert f"integers {step:g} apart" in read.why


@SETTINGS
@given(logger=loggers(rates=(1.0, 1e5)), date=st.integers(YEAR_2000, YEAR_2100 - 10**6))
def test_counts_from_a_date_come_back_in_their_unit_at_any_imu_rate(logger, date):
    unit, step, n = logger
    time = _stamps(unit, step, round(date / UNITS[unit]), n)
    rate = 1 / (np.median(np.diff(time)) * UNITS[unit])  # as float64 holds the counts
    read = time_unit("timestamp", time)
    assert read.unit == unit or not is_imu_rate(rate), read


@SETTINGS
@given(logger=loggers(rates=(1.0, 1e5)), origin=st.integers(0, 10**9))
def test_a_given_rate_picks_the_unit(logger, origin):
    unit, step, n = logger
    rate = 1 / (step * UNITS[unit])
    assert time_unit("time", _stamps(unit, step, origin, n), rate=rate).unit == unit


@SETTINGS
@given(rate=st.floats(1.0, 1e5), start=st.floats(0, 1e6), n=st.integers(2, 500))
def test_a_time_in_seconds_with_fractions_stays_seconds(rate, start, n):
    time = start + np.arange(n) / rate
    read = time_unit("time", time)
    assert read.unit == "s" or np.array_equal(time, np.rint(time))


@SETTINGS
@given(time=arrays(np.float64, st.integers(0, 50), elements=st.floats(-1e30, 1e30)),
       name=st.sampled_from(["time", "timestamp", "time_s", "t_ms"]),
       rate=st.none() | st.floats(1e-6, 1e9))
def test_any_column_gets_a_unit(time, name, rate):
    read = time_unit(name, time, rate)
    assert read.unit in UNITS and read.seconds == UNITS[read.unit]
    assert read.unit == "s" or read.why
