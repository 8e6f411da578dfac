"""The unit of a time column: by its name, else by the spacing and magnitude of its integers."""

import numpy as np
import pytest

from fosmodel.io.time_units import TIME_COLUMNS, UNITS, is_imu_rate, time_unit

EPOCH_2024 = 1_704_067_200  # 2024-01-01 00:00 UTC, in seconds since 1970


@pytest.mark.parametrize("name, unit", [("time_ms", "ms"), ("t_us", "us"),
                                        ("timestamp_ns", "ns"), ("time_s", "s"), ("t_s", "s")])
def test_a_unit_in_the_name_is_the_unit(name, unit):
    read = time_unit(name, np.arange(0.0, 1.0, 0.01))  # whatever the values
    assert read.unit == unit and read.seconds == UNITS[unit]
    assert read.why == ("by its name" if unit != "s" else "")


@pytest.mark.parametrize("unit, rate, origin", [
    ("ms", 100.0, 0), ("ms", 500.0, 0), ("ms", 200.0, EPOCH_2024 * 1000),
    ("us", 400.0, 123_456), ("us", 50.0, EPOCH_2024 * 10**6), ("us", 2000.0, 0),
    ("ns", 100.0, 0), ("ns", 800.0, EPOCH_2024 * 10**9), ("ns", 12.5, 0),
])
def test_integer_counts_are_read_in_the_unit_their_spacing_gives(unit, rate, origin):
    step = round(1 / (rate * UNITS[unit]))
    time = (origin + step * np.arange(2000)).astype(float)  # ns since 1970: 256 ns resolution
    read = time_unit("time", time)
    assert read.unit == unit
    said = read.why.partition(" apart: ")[2].partition(" Hz")[0]
    assert float(said) == pytest.approx(rate, rel=1e-4), read.why
    assert read.why.startswith("integers ")
    assert ("; from 2024-01-01 00:00 UTC" in read.why) == (origin > 10**6)


def test_a_date_since_1970_tells_the_unit_before_the_spacing():
    """Every 500 counts: 2 kHz in us by the spacing, but from 2024 only in ms (2 Hz)."""
    time = EPOCH_2024 * 1000.0 + 500 * np.arange(100)
    read = time_unit("timestamp", time)
    assert read.unit == "ms" and read.why.endswith("; from 2024-01-01 00:00 UTC")
    assert time_unit("timestamp", 500.0 * np.arange(100)).unit == "us"  # from zero: 2 kHz
    seconds = EPOCH_2024 + np.arange(100.0)  # whole seconds from 1970 at 1 Hz
    assert time_unit("time", seconds).unit == "s" and time_unit("time", seconds - EPOCH_2024
                                                                 ).unit == "s"


def test_a_given_rate_tells_the_unit():
    time = np.arange(0.0, 100.0)  # whole counts: 1 Hz in s, 1 kHz in ms, 1 MHz in us
    # whole seconds from zero are a slow logger's (a day-long thermal test at 1 Hz)
    assert time_unit("time", time).unit == "s"
    assert time_unit("time", time, rate=1.0).unit == "s"
    assert time_unit("time", time, rate=1000.0).why == "integers 1 apart, rate=1000 Hz"
    assert time_unit("time", time, rate=33.0).unit == "s"  # none matches: the time base says so


@pytest.mark.parametrize("time", [np.arange(0, 5, 0.01), np.array([0.0]), np.array([3.0, 3.0]),
                                  np.array([5.0, 4.0, 3.0]), np.arange(0, 5, 0.5)])
def test_seconds_otherwise(time):
    assert time_unit("time", time) == ("s", 1.0, "")


def test_the_note_says_how_to_read_it_otherwise():
    read = time_unit("time", np.arange(0.0, 5000.0, 10.0))
    assert read.note("time") == ("column 'time' read in milliseconds (integers 10 apart: 100 Hz, "
                                 "where seconds would give 0.1 Hz); scale={'time': FACTOR} gives "
                                 "its seconds per count instead")


def test_time_column_names_and_imu_rates():
    assert TIME_COLUMNS[:3] == ("time", "time_s", "t_s")
    assert all(is_imu_rate(r) for r in (1.0, 0.9999, 100.0, 1e5))  # give or take 1 %
    assert not any(is_imu_rate(r) for r in (0.98, 0.1, 1.5e5))
