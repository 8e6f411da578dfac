"""Six-axis IMU records: temperature sweeps, sessions of one sensor, companion axes with shared
noise (data_synth.imu through its scenarios); each truth recovered by simple means."""

import math

import numpy as np
import pytest

from data_synth import make_scenario, make_sessions
from data_synth.effects import TemperatureBias
from data_synth.imu import ACCELS, GYROS, SENSITIVITY
from data_synth.units import STANDARD_GRAVITY

Z = 4.5
AXES = (*GYROS, *ACCELS)
LSB = {**dict.fromkeys(GYROS, 0.01), **dict.fromkeys(ACCELS, 0.002), "temp_c": 0.1}
UNQUANTIZED = {"gyro_lsb": 0.0, "accel_lsb": 0.0, "temp_lsb": 0.0}


def sources(rec):
    return {s["name"]: s for s in rec.truth["sources"]}


def pooled_fit(records, column, degree):
    """Least squares of ``column`` on one constant per session and the powers 1..degree of
    ``temp_c - 15``: the shared sensitivity with free turn-on biases."""
    rows, ys = [], []
    for i, rec in enumerate(records):
        t = rec.columns["temp_c"] - 15.0
        dummies = np.zeros((len(t), len(records)))
        dummies[:, i] = 1.0
        rows.append(np.column_stack([dummies, *(t**k for k in range(1, degree + 1))]))
        ys.append(rec.columns[column])
    coef = np.linalg.lstsq(np.vstack(rows), np.concatenate(ys), rcond=None)[0]
    return coef[: len(records)], coef[len(records):]


@pytest.fixture(scope="module")
def sessions():
    return make_sessions("temperature_sessions", seed=7)


@pytest.fixture(scope="module")
def controls():
    return make_sessions("temperature_sessions_control", seed=7)


def test_sessions_are_day_long_1_hz_six_axis_records_with_temperature(sessions):
    assert len(sessions) == 3
    for k, rec in enumerate(sessions, start=1):
        assert rec.rate == 1.0 and rec.n_samples == 86_400
        assert list(rec.columns) == [*AXES, "temp_c"] and rec.target == "gx_dps"
        assert rec.truth["session"] == {"index": k, "count": 3, "label": f"s{k}",
                                        "group_seed": 7}
        undeclared = sorted(s["name"] for s in rec.truth["sources"] if not s["declared"])
        assert undeclared == ["ax_mps2_temperature_bias", "gx_dps_temperature_bias"]
        assert sorted(rec.truth["columns"]["temp_c"]["used_by"]) == undeclared


def test_every_column_is_quantized_at_its_coarse_lsb(sessions):
    for column, values in sessions[1].columns.items():
        steps = values / LSB[column]
        np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
        assert sessions[1].truth["columns"][column]["lsb"] == LSB[column]
    # coarse: the white noise of a gyro spans a few LSB, not hundreds
    gyro = sessions[1].columns["gx_dps"]
    white = sources(sessions[1])["gx_dps_white"]["params"]["sigma_per_sample"]
    steps = np.round(np.diff(gyro) / LSB["gx_dps"])
    assert white < LSB["gx_dps"] and np.abs(steps).max() <= 8


def test_sweeps_from_5_c_with_a_flat_first_half_in_the_first_session(sessions):
    tops = [16.0, 24.0, 20.0]
    for rec, top in zip(sessions, tops):
        temp = rec.columns["temp_c"]
        assert abs(temp[:600].mean() - 5.0) < 0.3 and abs(temp[-600:].mean() - top) < 0.3
    temp = sessions[0].columns["temp_c"]
    first, second = temp[:43_200], temp[43_200:]
    # the first half only wanders (0.05 C, read in 0.1 C steps): nothing to learn a slope from
    assert np.ptp(first) <= 0.5 and first.std() < 0.1
    assert second.std() > 3.0 and np.ptp(second) > 10.0


def test_the_record_is_its_control_plus_the_temperature_polynomial():
    driven = make_sessions("temperature_sessions", seed=3, duration=7200.0, **UNQUANTIZED)
    control = make_sessions("temperature_sessions_control", seed=3, duration=7200.0,
                            **UNQUANTIZED)
    for rec, ctl in zip(driven, control):
        temp = rec.columns["temp_c"] - 15.0  # unquantized: the temperature the bias reads
        np.testing.assert_array_equal(temp, ctl.columns["temp_c"] - 15.0)
        for column in AXES:
            coefs = SENSITIVITY.get(column, ())
            expected = sum(c * temp**k for k, c in enumerate(coefs))
            np.testing.assert_allclose(rec.columns[column] - ctl.columns[column], expected,
                                       atol=1e-12)
        assert "constants" in ctl.truth and ctl.truth["constants"] == rec.truth["constants"]


def test_least_squares_on_temperature_recovers_the_shared_sensitivity(sessions, controls):
    # Tolerances: 5 standard deviations of each estimate over seeds 0-19 (5.6e-5 and 7.9e-6
    # deg/s per C^k on gx_dps, 1.7e-5 m/s^2/C on ax_mps2), set by the slow stochastic bias.
    shared = sessions[0].truth["shared"]["temperature_bias"]
    assert set(shared) == {"gx_dps", "ax_mps2"}
    assert shared["gx_dps"]["coefs"] == [0.0, 0.005, 1e-4] and shared["gx_dps"]["t_ref_c"] == 15
    tol = {"gx_dps": [3e-4, 4e-5], "ax_mps2": [1e-4]}
    for column, entry in shared.items():
        slope = entry["coefs"][1:]
        _, fitted = pooled_fit(sessions, column, len(slope))
        assert np.all(np.abs(fitted - slope) < tol[column])
        _, null = pooled_fit(controls, column, len(slope))
        assert np.all(np.abs(null) < tol[column])
    assert controls[0].truth["shared"] == {"temperature_bias": {}}


def test_per_session_constants_turn_on_bias_and_orientation(sessions):
    constants, _ = pooled_fit(sessions, "gx_dps", 2)
    truth = [rec.truth["constants"]["gx_dps"]["value"] for rec in sessions]
    # 5 standard deviations over seeds 0-19 (9e-4 deg/s: the day's slow stochastic bias)
    assert np.all(np.abs(constants - truth) < 5e-3)
    assert np.ptp(truth) > 0.02  # the turn-on biases (0.1 deg/s) set the sessions apart
    for rec in sessions:
        parts = rec.truth["constants"]["gx_dps"]["sources"]
        assert parts == ["gx_dps_turn_on", "gx_dps_earth_rate"]
    # gravity on z, then x, then -y: the accelerometer means say which axis was up
    up = [("az_mps2", 1), ("ax_mps2", 1), ("ay_mps2", -1)]
    for rec, (column, sign) in zip(sessions, up):
        means = {c: rec.columns[c].mean() for c in ACCELS}
        assert means[column] == pytest.approx(sign * STANDARD_GRAVITY, abs=0.1)
        assert all(abs(m) < 0.1 for c, m in means.items() if c != column)
        assert rec.truth["orientation"]["up"][1] == column[1]


def test_ten_minute_means_follow_the_temperature_as_in_the_held_back_record(sessions):
    """On the driven gyro the 10-minute means follow temperature with correlation 0.990-0.998
    and a quadratic in it removes 89-93 % of their spread in the first session, 95-97 % in the
    others (seeds 0-19; the held-back record: 0.996 and 92-96 %)."""
    for k, rec in enumerate(sessions):
        y = rec.columns["gx_dps"].reshape(-1, 600).mean(axis=1)
        t = rec.columns["temp_c"].reshape(-1, 600).mean(axis=1)
        assert np.corrcoef(y, t)[0, 1] > 0.985
        left = y - np.polyval(np.polyfit(t, y, 2), t)
        assert 1 - left.std() / y.std() > (0.85 if k == 0 else 0.93)


def test_single_sweep_spans_the_first_half_and_its_control_shares_the_draws():
    rec = make_scenario("temperature_sweep", seed=2)
    ctl = make_scenario("temperature_sweep_control", seed=2)
    temp = rec.columns["temp_c"]
    first = temp[:43_200]
    assert np.ptp(first) > 14.0 and temp[-3600:].mean() == pytest.approx(8.0, abs=0.3)
    assert 5.0 <= temp[43_200:].min() + 0.5 and temp[43_200:].max() <= first.max() + 0.5
    np.testing.assert_array_equal(rec.columns["gy_dps"], ctl.columns["gy_dps"])  # undriven
    assert not any(s["kind"] == "temperature_bias" for s in ctl.truth["sources"])


def test_the_thermal_lag_is_recovered_by_a_grid_of_lags():
    """The lagged sweep's bias is fitted best through a lag near the true 30 minutes (grid of
    450 s: within one step in each seed), and a fit without the lag leaves 5 % more."""
    for seed in range(3):
        rec = make_scenario("temperature_sweep_lag", seed=seed)
        assert sources(rec)["gx_dps_temperature_bias"]["params"]["lag_s"] == 1800.0
        y, temp = rec.columns["gx_dps"], rec.columns["temp_c"]
        lags = np.arange(0.0, 3601.0, 450.0)
        left = []
        for lag in lags:
            t = TemperatureBias((0.0,), lag_s=lag).sensor_temperature(temp, rec.rate) - 15
            design = np.column_stack([np.ones_like(t), t, t**2])
            left.append(np.linalg.lstsq(design, y, rcond=None)[1][0])
        assert abs(lags[int(np.argmin(left))] - 1800.0) <= 450.0
        assert left[0] > 1.05 * min(left)


# -- companion axes ------------------------------------------------------------------------------


@pytest.mark.parametrize("fast", [True, False])
def test_companion_axes_share_their_noise_with_the_covariance_the_truth_gives(fast):
    rec = make_scenario("companion_noise", seed=5, duration=1200.0, fast=fast)
    groups = {tuple(g["channels"]): g for g in rec.truth["cross_covariance"]}
    assert set(groups) == {GYROS, ACCELS}
    src = sources(rec)
    for axes, sensor in ((GYROS, "gyro"), (ACCELS, "accel")):
        white = np.array(src[f"{sensor}_white"]["params"]["covariance"])
        total = white.copy()
        expected = 2 * white  # of first differences: the slow errors drop out
        if fast:
            gm = src[f"{sensor}_fast"]["params"]
            total += np.array(gm["covariance"])
            expected += 2 * (1 - gm["phi"]) * np.array(gm["covariance"])
        np.testing.assert_allclose(groups[axes]["covariance"], total, rtol=1e-12)
        d = np.diff(np.column_stack([rec.columns[c] for c in axes]), axis=0)
        est = np.cov(d.T)
        var = np.diag(est)
        # a difference of white noise has lag-one correlation -1/2: 1.5 times the white error
        tol = Z * np.sqrt(1.5 * (np.outer(var, var) + est**2) / len(d))
        off = ~np.eye(3, dtype=bool)
        assert np.all(np.abs(est - expected)[off] < tol[off])
        assert np.all(np.abs(np.corrcoef(d.T)[off]) > 0.05)  # shared, and plainly so


def test_no_axis_enters_another():
    rec = make_scenario("companion_noise", duration=10.0)
    assert all("used_by" not in info for info in rec.truth["columns"].values())
    assert {s["kind"] for s in rec.truth["sources"]} == {
        "correlated_white_noise", "correlated_gauss_markov", "constant_bias",
        "bias_instability", "random_walk"}
    independent = make_scenario("companion_noise", duration=10.0, gyro_corr=0.0, accel_corr=0.0)
    for group in independent.truth["cross_covariance"]:
        cov = np.array(group["covariance"])
        assert np.all(cov[~np.eye(3, dtype=bool)] == 0.0)
    assert math.isclose(rec.columns["az_mps2"].mean(), STANDARD_GRAVITY, abs_tol=0.1)
