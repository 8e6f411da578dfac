"""A measured driver on a short record: offered before a function of time, and named."""

from pathlib import Path

import pytest

from data_synth import make_scenario
from fosmodel.loop.closeloop import LoopConfig, close_loop
from fosmodel.loop.driver_forms import DriverForms, short_fit, slow_driver, time_like
from fosmodel.loop.record import LoopRecord

MPU = (Path(__file__).parents[2] / "shared" / "data" / "mpu6050_sunsided"
       / "unmoved-with-x-pointing-forward-10min.csv.gz")


def _loop(rec):
    y = rec.columns[rec.target]
    channels = {k: v for k, v in rec.columns.items() if k != rec.target}
    return close_loop(y, channels, LoopConfig(rate=rec.rate, sensor="gyro", units="deg/s"))


def test_the_short_record_limit_is_the_fitting_data_of_200_blocks_of_slow_s():
    assert short_fit((slice(0, 399_999),), 100.0, 20.0)
    assert not short_fit((slice(0, 400_000),), 100.0, 20.0)
    rec = make_scenario("short_driver", seed=0)
    record = LoopRecord.single(rec.columns["gyro_x"], {"temp_c": rec.columns["temp_c"]}, 100.0)
    assert time_like(record, (slice(0, 30_000),), "temp_c", 20.0)
    # at a slow_s of 1 s the same 300 s hold 200 blocks of it: long enough to tell the two
    assert not time_like(record, (slice(0, 30_000),), "temp_c", 1.0)


@pytest.mark.parametrize("seed", [0, 2, 7])
def test_a_driver_that_runs_as_time_does_on_ten_minutes_is_named(seed):
    res = _loop(make_scenario("short_driver", seed=seed))
    assert [s.effect.channel for s in res.steps if s.effect.kind == "driver"] == ["temp_c"]
    assert not any(s.effect.kind in ("drift", "step") for s in res.steps)
    assert res.after.bias_rms[30] <= 0.5 * res.before.bias_rms[30]
    (note,) = [n for n in res.notes if n.startswith("temp_c runs as time does")]
    assert "shorter than the 4000 s (200 blocks of 20 s)" in note and "8000 s" in note


@pytest.mark.parametrize("seed", range(5))
def test_its_control_names_no_driver(seed):
    res = _loop(make_scenario("short_driver_control", seed=seed))
    assert not [s for s in res.steps if s.effect.kind == "driver"]


@pytest.mark.skipif(not MPU.is_file(), reason="../shared/data/mpu6050_sunsided is not here "
                    "(a fresh clone has no ../shared)")
def test_the_mpu6050_die_temperature_is_named_on_ay_g():
    import pandas as pd

    frame = pd.read_csv(MPU)
    rate = (len(frame) - 1) / (frame.t_s.iloc[-1] - frame.t_s.iloc[0])  # bursty receive time
    y = frame.ay_g.to_numpy()
    channels = {c: frame[c].to_numpy() for c in frame.columns if c not in ("t_s", "ay_g")}
    res = close_loop(y, channels, LoopConfig(rate=rate, sensor="accel", units="g"))
    assert [s.effect.channel for s in res.steps if s.effect.kind == "driver"] == ["temp_c"]
    assert res.after.bias_rms[30] <= 0.5 * res.before.bias_rms[30]
    # beside a trend in time the die temperature is no evidence of itself over 327 s
    record = LoopRecord.single(y, {"temp_c": channels["temp_c"]}, rate)
    fit = (res.segments.train,)
    assert not slow_driver(y, "temp_c", DriverForms(record, fit, 20.0), 1e-3).fired
