"""A thermal calibration judged out of sample, against PX4's procedure; its range checks."""

import numpy as np
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.workflows.tempcal import AxisGroup, TempcalConfig, TempSession, run_tempcal


@pytest.fixture(scope="module")
def lagged(thermal_group):
    """Three sweeps whose biases follow the die 5 min late, calibrated."""
    group, truth = thermal_group(0, lag_s=300.0)
    return run_tempcal([group]), truth


def test_with_a_five_minute_lag_the_held_out_bias_is_at_most_half_px4_s(lagged):
    result, _ = lagged
    for cal in result.axes:
        rms = cal.held.rms
        assert cal.model.lag_s == pytest.approx(300.0, rel=0.05), cal.axis.column
        assert rms["model"] <= 0.5 * rms["px4"], (cal.axis.column, rms)
        assert cal.held.ratios["model/px4"].verdict == "better", cal.axis.column
        assert cal.held.how == "leave one session out"
        assert len(cal.held.folds) == 3 and cal.held.ratios["model/before"].high < 0.1


def test_the_firmware_polynomial_says_what_the_lag_costs_and_reads_as_hysteresis(lagged):
    result, _ = lagged
    for cal in result.axes:
        assert cal.firmware.firmware_form and not cal.model.firmware_form
        assert cal.held.rms["firmware"] > 2 * cal.held.rms["model"], cal.axis.column
        assert cal.hysteresis["firmware"].found and not cal.hysteresis["model"].found
        assert cal.hysteresis["firmware"].sessions == 3


def test_without_a_lag_the_model_is_the_firmware_s_and_no_worse_than_px4(thermal_group):
    group, _ = thermal_group(1)
    for cal in run_tempcal([group]).axes:
        assert cal.model is cal.firmware, cal.axis.column
        assert cal.held.ratios["model/px4"].verdict != "worse", cal.axis.column
        assert cal.held.rms["model"] < 0.05 * cal.held.rms["before"], cal.axis.column


def test_one_session_is_judged_on_the_later_part_of_its_sweep(thermal_group):
    group, _ = thermal_group(2, sessions=1, columns=["gx_dps"])
    cal = run_tempcal([group], TempcalConfig(train=0.6)).axes[0]
    assert cal.held.how == "the later part of the sweep (fitted on its first 60%)"
    first = np.min(cal.held.times)
    assert first == pytest.approx(0.6 * 7200 + 15, abs=1)
    assert cal.held.ratios["model/before"].verdict == "better"
    assert cal.hysteresis["model"].sessions == 1 and np.isnan(cal.hysteresis["model"].low)


def _group(spans, rate=1.0, name="rec.csv"):
    rng = np.random.default_rng(0)
    sessions = []
    for k, (low, high) in enumerate(spans):
        t = np.linspace(low, high, 3600)
        sessions.append(TempSession(f"{name}{k}", {"gx": 0.01 * t + 0.001 * rng.standard_normal(
            3600)}, t, rate))
    from fosmodel.noise.axes import resolve_axes

    return AxisGroup("imu", tuple(resolve_axes(["gx"], given=None, sensor="gyro",
                                               units={"gyro": "rad/s"})), "temp", tuple(sessions))


def test_a_span_of_less_than_a_few_degrees_is_refused():
    with pytest.raises(InputError) as err:
        run_tempcal([_group([(25.1, 25.6)])])
    assert str(err.value) == ("rec.csv0: temp spans only 0.5 C; a thermal calibration needs at "
                              "least 5 C (min_span_c=...)")


def test_a_degree_the_span_cannot_support_is_refused_and_the_default_is_narrowed():
    with pytest.raises(InputError) as err:
        run_tempcal([_group([(10, 22), (11, 21)])], TempcalConfig(degree=3))
    assert str(err.value) == ("rec.csv0 and 1 more: temp spans 12 C, too narrow for degree=3 (5 C "
                              "per power); it supports degree=2")
    result = run_tempcal([_group([(10, 22), (11, 21)])])
    assert result.notes == ["rec.csv0 and 1 more: temp spans 12 C: powers up to 2 offered (5 C "
                            "per power), not the firmware's 3"]
    assert result.axes[0].model.degree == 1  # the truth is a line


def test_sessions_of_other_rates_are_refused():
    group = _group([(0, 40), (0, 40)])
    other = TempSession("fast.csv", group.sessions[1].columns, group.sessions[1].temperature,
                        2.0)
    with pytest.raises(InputError, match="the sessions' rates differ: rec.csv0 1 Hz, fast.csv "
                                         "2 Hz"):
        run_tempcal([AxisGroup("imu", group.axes, "temp", (group.sessions[0], other))])


def test_settings_out_of_range_are_refused():
    with pytest.raises(InputError, match="degree=4: PX4's and ArduPilot's firmware evaluate a "
                                         "polynomial of degree 3 at most"):
        TempcalConfig(degree=4)
    with pytest.raises(InputError, match="train must lie between 0 and 1"):
        TempcalConfig(train=1.0)
