"""Records checked before they are trusted: at rest, in the units they claim, every column named."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.noise.axes import resolve_axes
from fosmodel.noise.checks import check_units, static_part, stillness, unused_columns
from fosmodel.noise.imu_noise import imu_noise

RATE = 100.0
SHARED = Path(__file__).parents[2] / "shared" / "data"
COLUMNS = ["gx_dps", "gy_dps", "gz_dps", "ax_g", "ay_g", "az_g"]


def _static(n: int, rng: np.random.Generator, gravity=(0.0, 0.0, -1.0)) -> pd.DataFrame:
    """Six axes at rest: white noise and a slow walk, the accelerometers reading gravity."""
    frame = {}
    for i, column in enumerate(COLUMNS):
        gyro = column.startswith("g")
        white, walk = (0.05, 1e-4) if gyro else (2e-3, 1e-6)
        level = 0.3 if gyro else gravity[i - 3]
        frame[column] = (level + white * rng.standard_normal(n)
                         + np.cumsum(walk * rng.standard_normal(n)))
    return pd.DataFrame(frame)


def _turned(frame: pd.DataFrame, start_s: float, length_s: float) -> pd.DataFrame:
    """Turn about x at 30 deg/s for ``length_s``, then back: the gyro and gravity move."""
    out = frame.copy()
    n = int(length_s * RATE)
    first = int(start_s * RATE)
    rate = np.r_[np.full(n // 2, 30.0), np.full(n - n // 2, -30.0)]
    angle = np.radians(np.cumsum(rate) / RATE)
    out.loc[first:first + n - 1, "gx_dps"] += rate
    out.loc[first:first + n - 1, "ay_g"] += -np.sin(angle)
    out.loc[first:first + n - 1, "az_g"] += 1.0 - np.cos(angle)
    return out


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    rng = np.random.default_rng(3)
    folder = tmp_path_factory.mktemp("checks")
    static = _static(60_000, rng)  # 600 s
    moving = _turned(static, 200.0, 6.0)
    paths = {"static": folder / "static.csv", "moving": folder / "moving.csv"}
    static.to_csv(paths["static"], index=False, float_format="%.8g")
    moving.to_csv(paths["moving"], index=False, float_format="%.8g")
    return paths, static, moving


def _axes():
    return resolve_axes(COLUMNS)


def _run(args, capsys):
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_record_at_rest_passes_and_one_that_turns_is_found_where_it_turns(records):
    _, static, moving = records
    assert stillness({c: static[c].to_numpy() for c in COLUMNS}, _axes(), RATE).still.all()
    found = stillness({c: moving[c].to_numpy() for c in COLUMNS}, _axes(), RATE)
    assert found.stretches() == [(0, 20_000), (20_600, 60_000)]
    assert found.longest() == (20_600, 60_000) and found.moving_s == 6.0
    assert math.degrees(found.rotation) > 10.0 and found.force > 0.3 * 9.80665


def test_a_lone_spike_is_not_motion(records):
    _, static, _ = records
    spiked = static.copy()
    spiked.loc[30_000, "gx_dps"] += 17.0  # as in ADIS16405 session imu4
    assert stillness({c: spiked[c].to_numpy() for c in COLUMNS}, _axes(), RATE).still.all()


def test_a_slow_drift_of_the_bias_is_not_motion():
    rng = np.random.default_rng(8)
    n = 360_000  # an hour warming up: 0.3 deg/s of gyro bias drift, 5 mg on the accelerometers
    drift = 1.0 - np.exp(-np.arange(n) / (RATE * 900.0))
    frame = _static(n, rng)
    frame["gx_dps"] += 0.3 * drift
    frame["ax_g"] += 0.005 * drift
    assert stillness({c: frame[c].to_numpy() for c in COLUMNS}, _axes(), RATE).still.all()


def test_the_command_refuses_a_record_that_moves_in_one_line(records, tmp_path, capsys):
    paths, *_ = records
    out = tmp_path / "noise"
    code, _, err = _run(["allan", paths["moving"], "--rate", RATE, "--columns", ",".join(COLUMNS),
                         "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert err == (f"fosmodel: error: {paths['moving']}: the record is not static: it moves for "
                   "6 s of its 600 s (first at 200 s), where its rate departs from rest by up "
                   "to 30 deg/s and its specific force by up to 1.22 g (1 s medians); an Allan "
                   "analysis needs the sensor at rest: pass --static-only to analyse its longest "
                   "static stretch (206-600 s)\n")


@pytest.mark.slow
def test_static_only_analyses_the_longest_static_stretch_and_says_which(records, tmp_path,
                                                                         capsys):
    paths, *_ = records
    out, js = tmp_path / "noise", tmp_path / "noise.json"
    code, _, err = _run(["allan", paths["moving"], "--rate", RATE, "--columns",
                         ",".join(COLUMNS), "--static-only", "--out", out, "--json", js], capsys)
    assert code == 0, err
    assert err.splitlines()[0] == (
        f"fosmodel: note: {paths['moving']}: analysing its longest static stretch, 206-600 s "
        "from its start (39400 of 60000 samples): it moves for 6 s of its 600 s (first at "
        "200 s), where its rate departs from rest by up to 30 deg/s and its specific force by "
        "up to 1.22 g (1 s medians)")
    stretch = pd.read_csv(paths["moving"]).iloc[20_600:]  # as written, to its last digit
    alone = imu_noise({c: stretch[c].to_numpy() for c in COLUMNS}, _axes(), RATE,
                      str(paths["moving"]))
    assert pd.read_csv(out / "noise.csv").equals(
        pd.read_csv(pd.io.common.StringIO(alone.table().to_csv(index=False))))


@pytest.mark.skipif(not (SHARED / "px4_ulog" / "sample.ulg").is_file(),
                    reason="../shared/data/px4_ulog/sample.ulg is not here (a fresh clone has "
                           "no ../shared)")
def test_a_px4_log_picked_up_and_put_down_is_refused_not_called_outliers(tmp_path, capsys):
    log = SHARED / "px4_ulog" / "sample.ulg"
    out = tmp_path / "noise"
    code, _, err = _run(["allan", log, "--fill", "--columns", "gx,gy,gz,ax,ay,az", "--out", out],
                        capsys)
    assert code == 2 and not out.exists()
    assert err == (f"fosmodel: error: {log}: the record is not static: it moves for 4 s of its "
                   "68.88 s (first at 2 s), where its rate departs from rest by up to 14.8 "
                   "deg/s and its specific force by up to 0.161 g (1 s medians); an Allan "
                   "analysis needs the sensor at rest: pass --static-only to analyse its "
                   "longest static stretch (6-68.88 s)\n")


def test_a_record_that_never_rests_is_refused_even_with_static_only():
    """Turning about x at a steady 20 deg/s: the gyro alone reads it as a bias, gravity does not."""
    rng = np.random.default_rng(5)
    angle = np.radians(20.0 * np.arange(30_000) / RATE)
    frame = _static(30_000, rng)
    frame["gx_dps"] += 20.0
    frame["ay_g"] += -np.sin(angle)
    frame["az_g"] += 1.0 - np.cos(angle)
    with pytest.raises(InputError) as err:
        static_part({c: frame[c].to_numpy() for c in COLUMNS}, _axes(), RATE, "spin.csv",
                    static_only=True)
    assert str(err.value).startswith("spin.csv: the record is not static: it moves for 300 s "
                                     "of its 300 s (first at 0 s)")
    assert str(err.value).endswith("; it is never at rest for a whole second, too short for an "
                                   "Allan analysis (at least 1000 samples, 10 s)")


def _means(values, units):
    columns = {c: v + 1e-3 * np.random.default_rng(1).standard_normal(1000)
               for c, v in zip(("ax", "ay", "az"), values)}
    axes = resolve_axes(list(columns), {"accel": units})
    return columns, axes


@pytest.mark.parametrize(("values", "units"), [
    ((0.02, -0.03, -0.92), "g"),  # an uncalibrated MPU-6050 triad: 0.92 g
    ((0.1, 0.2, -9.7), "m/s^2"),
    ((1e-3, -2e-3, 4e-3), "m/s^2"),  # gravity removed: an error series
])
def test_accelerometers_that_read_gravity_in_their_units_pass(values, units):
    check_units(*_means(values, units), "imu.csv")


@pytest.mark.parametrize(("values", "units", "message"), [
    ((0.0, 0.02, 1.01), "m/s^2",
     "imu.csv: the mean specific force of ax, ay, az is 0.103 g in m/s^2, where an accelerometer "
     "triad at rest reads 1 g (or about 0 with gravity removed); in g it would be 1.01 g; check "
     "the units of these columns"),
    ((0.0, 0.0, 9.81), "g",
     "imu.csv: the mean specific force of ax, ay, az is 9.81 g in g, where an accelerometer triad "
     "at rest reads 1 g (or about 0 with gravity removed); in m/s^2 it would be 1 g; check the "
     "units of these columns"),
    ((0.0, 0.0, 1000.0), "g",
     "imu.csv: the mean specific force of ax, ay, az is 1e+03 g in g, where an accelerometer "
     "triad at rest reads 1 g (or about 0 with gravity removed); in mg it would be 1 g; check the "
     "units of these columns"),
])
def test_accelerometers_whose_mean_contradicts_gravity_are_refused(values, units, message):
    with pytest.raises(InputError) as err:
        check_units(*_means(values, units), "imu.csv")
    assert str(err.value) == message


def test_one_accelerometer_reading_more_than_gravity_is_refused():
    columns = {"az": np.full(500, -9.78) + 1e-3 * np.random.default_rng(2).standard_normal(500)}
    with pytest.raises(InputError) as err:
        check_units(columns, resolve_axes(["az"], {"accel": "g"}), "imu.csv")
    assert str(err.value) == ("imu.csv: the mean of az is 9.78 g in g, more than the 1 g an "
                              "accelerometer at rest can read; in m/s^2 it would be 0.997 g; "
                              "check the units of the column")


def test_units_given_against_a_name_and_gravity_are_refused_in_one_line(records, tmp_path,
                                                                        capsys):
    paths, *_ = records
    out = tmp_path / "noise"
    code, _, err = _run(["allan", paths["static"], "--rate", RATE, "--columns", "gx_dps,az_g",
                         "--units", "gx_dps=rad/s,az_g=m/s^2", "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert err == ("fosmodel: error: column 'gx_dps': its name says deg/s, but the units given "
                   "for it are rad/s; correct the units or rename the column\n")
    renamed = tmp_path / "renamed.csv"
    pd.read_csv(paths["static"]).rename(columns=lambda c: c.split("_")[0]).to_csv(renamed,
                                                                                 index=False)
    code, _, err = _run(["allan", renamed, "--rate", RATE, "--columns", "gx,gy,gz,ax,ay,az",
                         "--units", "gx=deg/s,gy=deg/s,gz=deg/s,ax=m/s^2,ay=m/s^2,az=m/s^2",
                         "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert err == (f"fosmodel: error: {renamed}: the mean specific force of ax, ay, az is 0.102 g "
                   "in m/s^2, where an accelerometer triad at rest reads 1 g (or about 0 with "
                   "gravity removed); in g it would be 1 g; check the units of these columns\n")


def test_every_column_not_analysed_is_named_with_why():
    names = ["gx_dps", "gy_dps", "zg_dps", "ax_g", "ay_g", "az_g", "temp_c", "status"]
    used = ["gx_dps", "gy_dps", "ax_g", "ay_g", "az_g", "temp_c"]
    assert unused_columns(names, used, named=False) == [
        ("zg_dps", "its name tells neither a gyro nor an accelerometer (is it gz_dps?); give its "
                   "units (units={'zg_dps': UNITS}) or name it in columns= to use it"),
        ("status", "its name tells neither a gyro nor an accelerometer; give its units (units="
                   "{'status': UNITS}) or name it in columns= to use it")]
    assert unused_columns(names, used, named=True) == [("zg_dps", "not among columns="),
                                                       ("status", "not among columns=")]


@pytest.mark.slow
def test_imu_names_the_column_it_skips(records, tmp_path, capsys):
    paths, static, _ = records
    typo = tmp_path / "typo.csv"
    static.iloc[:30_000].rename(columns={"gz_dps": "zg_dps"}).to_csv(typo, index=False)
    out = tmp_path / "report"
    code, stdout, err = _run(["imu", typo, "--rate", RATE, "--orders", "1", "--methods",
                              "fos,burg", "--jobs", "2", "--split", "60s,60s", "--out", out],
                             capsys)
    assert code == 0, err
    assert ("fosmodel: note: column 'zg_dps' skipped: its name tells neither a gyro nor an "
            "accelerometer (is it gz_dps?); give its units (--units zg_dps=UNITS) or name it in "
            "--columns to use it") in err.splitlines()
    assert f"six-axis report of 5 axes written to {out.resolve()}/" in stdout
