"""Synthetic records of effects that begin inside the record, a short record with a measured
driver, and knocks on a companion column."""

import numpy as np
import pytest

from data_synth import Drift, Knocks, make_scenario
from data_synth.record import source_rng


def test_a_late_warm_up_is_zero_before_its_start_and_settles_after():
    drift = Drift(0.0, 0.2, 60.0, start_s=300.0)
    out = drift.generate(90_000, 100.0, source_rng(0, "drift"))
    assert np.all(out[:30_001] == 0.0)
    assert out[30_000 + 6000] == pytest.approx(0.2 * (1 - np.exp(-1.0)))
    assert drift.params(100.0, "deg/s", out)["start_s"] == 300.0
    with pytest.raises(ValueError, match="start_s"):
        Drift(0.0, 0.2, 60.0, start_s=-1.0)


def test_knocks_are_where_the_truth_says_and_nowhere_else():
    knocks = Knocks(39, 5.0, 0.05)
    out = knocks.generate(180_000, 100.0, source_rng(0, "knocks"))
    times = knocks.params(100.0, "m/s^2", out)["times_s"]
    assert len(times) == 39 and times == sorted(times)
    hit = np.zeros(len(out), bool)
    for t in times:
        i = round(t * 100)
        hit[i:i + 5] = True
        assert out[i] == pytest.approx(5.0)
    assert not np.any(out[~hit]) and np.all(out[hit] != 0)
    with pytest.raises(ValueError, match="do not fit"):
        Knocks(10, 1.0, 50.0).generate(10_000, 100.0, source_rng(0, "knocks"))


def test_the_step_a_third_of_the_way_in():
    rec = make_scenario("slow_step_third", seed=0)
    (step,) = [s for s in rec.truth["sources"] if s["kind"] == "bias_step"]
    assert len(rec.columns["gyro_x"]) == 90_000 and step["params"]["steps"][0]["time_s"] == 300.0
    assert not step["declared"]


def test_the_late_warm_up_starts_a_third_of_the_way_in():
    rec = make_scenario("slow_late_warmup", seed=0, tau_s=30.0)
    (drift,) = [s for s in rec.truth["sources"] if s["kind"] == "drift"]
    assert drift["params"]["start_s"] == 300.0 and drift["params"]["warmup_tau_s"] == 30.0


def test_the_short_record_with_a_driver_and_its_control_draw_the_same_noise():
    rec = make_scenario("short_driver", seed=3)
    control = make_scenario("short_driver_control", seed=3)
    assert len(rec.columns["temp_c"]) == 60_000 and set(rec.columns) == {"gyro_x", "temp_c"}
    temp = rec.columns["temp_c"]
    np.testing.assert_array_equal(temp, control.columns["temp_c"])
    # read in an MPU-6050's steps, cooling by about 2 C over the ten minutes
    np.testing.assert_allclose(temp * 340, np.round(temp * 340), atol=1e-9)
    assert 1.8 < temp[:1000].mean() - temp[-1000:].mean() < 2.2
    # the bias follows the temperature at 0.03 deg/s/C (its read-out noise aside)
    slope = np.polyfit(temp, rec.columns["gyro_x"] - control.columns["gyro_x"], 1)[0]
    assert slope == pytest.approx(0.03, rel=0.02)
    assert "temperature_bias" not in {s["kind"] for s in control.truth["sources"]}


def test_knocks_on_a_companion_column_of_a_static_imu():
    rec = make_scenario("companion_knocks", seed=0)
    (knocks,) = [s for s in rec.truth["sources"] if s["kind"] == "knocks"]
    assert knocks["channel"] == "az_mps2" and len(knocks["params"]["times_s"]) == 39
    az, ay = rec.columns["az_mps2"], rec.columns["ay_mps2"]
    assert np.abs(az).max() > 4.0 > 10 * np.abs(ay).max()
    one = make_scenario("companion_knocks", seed=0, column="gz_dps", count=1, knock_s=50.0,
                        amplitude=2.0)
    (knock,) = [s for s in one.truth["sources"] if s["kind"] == "knocks"]
    assert knock["channel"] == "gz_dps" and len(knock["params"]["times_s"]) == 1
