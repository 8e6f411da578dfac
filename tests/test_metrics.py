import math

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel, InputError
from fosmodel.noise.metrics import (
    PAPER_GRAVITY,
    STANDARD_GRAVITY,
    bias_rms,
    equivalent_position_error,
    free_run_errors,
    integrated_position_error,
    one_step_mse,
    outage_metrics,
    outage_starts,
    to_si_scale,
)

DEG_H = math.pi / 180.0 / 3600.0  # rad/s in one deg/h

# -- units --------------------------------------------------------------------------------


@pytest.mark.parametrize("sensor, units, scale", [
    ("gyro", "rad/s", 1.0),
    ("gyro", "deg/s", math.pi / 180.0),
    ("gyro", "deg/h", math.pi / 648_000.0),
    ("accel", "m/s^2", 1.0),
    ("accel", "g", 9.80665),
    ("accel", "mg", 0.00980665),
])
def test_to_si_scale(sensor, units, scale):
    assert to_si_scale(sensor, units) == pytest.approx(scale, rel=1e-15)


def test_unknown_units_name_the_valid_ones():
    with pytest.raises(InputError, match=r"'furlong/s'.*rad/s, deg/s, deg/h"):
        to_si_scale("gyro", "furlong/s")
    with pytest.raises(InputError, match=r"'m/s\^2'.*valid gyro units"):
        to_si_scale("gyro", "m/s^2")
    with pytest.raises(InputError, match=r"'deg/h'.*m/s\^2, g, mg"):
        to_si_scale("accel", "deg/h")


def test_unknown_sensor_names_the_valid_ones():
    with pytest.raises(InputError, match="'magnetometer'.*accel, gyro"):
        to_si_scale("magnetometer", "T")


# -- Tamazin et al.'s (2013) equivalent position error (T = 3600 s) --------------------------------

# Table 1 (accelerometer-Y, MSE in (m/s^2)^2) and Table 2 (gyro-Y, MSE in (deg/h)^2):
# (MSE, position error in metres as printed).
TABLE_1 = [(5e-9, 458), (3e-11, 35), (1e-11, 20), (2e-12, 9), (3e-14, 1)]
TABLE_2 = [(7e-6, 978), (2e-6, 523), (2e-7, 165), (4e-10, 7), (3e-11, 2)]
# Rows whose printed value is the formula truncated, not rounded: 826.96 and 369.83 m.
TABLE_2_TRUNCATED = [(5e-6, 826), (1e-6, 369)]


@pytest.mark.parametrize("mse, metres", TABLE_1)
def test_paper_table_1(mse, metres):
    assert round(equivalent_position_error(mse, "accel", "m/s^2")) == metres


def test_paper_table_1_smallest_row():
    assert round(equivalent_position_error(2e-16, "accel", "m/s^2"), 2) == 0.09


@pytest.mark.parametrize("mse, metres", TABLE_2)
def test_paper_table_2(mse, metres):
    assert round(equivalent_position_error(mse, "gyro", "deg/h")) == metres


@pytest.mark.parametrize("mse, metres", TABLE_2_TRUNCATED)
def test_paper_table_2_rows_that_are_truncated(mse, metres):
    value = equivalent_position_error(mse, "gyro", "deg/h")
    assert round(value) == metres + 1
    assert math.floor(value) == metres


def test_every_paper_row_is_the_truncated_formula():
    for mse, metres in TABLE_1:
        assert math.floor(equivalent_position_error(mse, "accel", "m/s^2")) == metres
    for mse, metres in TABLE_2 + TABLE_2_TRUNCATED:
        assert math.floor(equivalent_position_error(mse, "gyro", "deg/h")) == metres


def test_gyro_position_error_uses_the_papers_gravity_not_standard_gravity():
    one = equivalent_position_error(1.0, "gyro", "deg/h")
    assert one == pytest.approx(9.81 * DEG_H * 3600.0**3 / 6.0, rel=1e-14)
    assert PAPER_GRAVITY == 9.81 and STANDARD_GRAVITY == 9.80665
    assert equivalent_position_error(1.0, "gyro", "deg/h", g=2 * 9.81) == pytest.approx(2 * one)


def test_equivalent_position_error_units_and_horizon():
    # 1 mg^2 is (9.80665e-3 m/s^2)^2; the error grows as T^2 (accel) and T^3 (gyro)
    assert equivalent_position_error(1.0, "accel", "mg", horizon_s=10.0) == pytest.approx(
        0.5 * 9.80665e-3 * 100.0, rel=1e-14)
    assert equivalent_position_error(4.0, "gyro", "rad/s", horizon_s=2.0, g=3.0) == \
        pytest.approx(3.0 * 2.0 * 8.0 / 6.0, rel=1e-14)


@pytest.mark.parametrize("kwargs", [dict(mse=-1.0), dict(mse=float("nan")),
                                    dict(mse=1.0, horizon_s=0.0), dict(mse=1.0, g=-9.81)])
def test_equivalent_position_error_rejects_bad_numbers(kwargs):
    with pytest.raises(InputError):
        equivalent_position_error(sensor="gyro", units="deg/h", **kwargs)


def test_equivalent_position_error_is_a_held_constant_error():
    # sqrt(MSE) held for one hour at 200 Hz and integrated gives the paper's value
    for sensor, units, mse in [("accel", "m/s^2", 5e-9), ("gyro", "deg/h", 7e-6)]:
        row = np.full(720_000, math.sqrt(mse))
        held = integrated_position_error(row, 200.0, sensor, units)
        assert held == pytest.approx(equivalent_position_error(mse, sensor, units), rel=1e-9)


# -- integrated position error: the sample-and-hold rule ----------------------------------

RATE = 100.0
DT = 1.0 / RATE


def test_constant_biases_are_exact():
    n = 3000
    h = n * DT
    b, w = 0.02, 5.0  # m/s^2 and deg/h
    assert integrated_position_error(np.full(n, b), RATE, "accel", "m/s^2") == pytest.approx(
        b * h**2 / 2, rel=1e-12)
    assert integrated_position_error(np.full(n, w), RATE, "gyro", "deg/h") == pytest.approx(
        9.81 * w * DEG_H * h**3 / 6, rel=1e-12)
    assert integrated_position_error(np.full(n, 1.0), RATE, "accel", "mg") == pytest.approx(
        9.80665e-3 * h**2 / 2, rel=1e-12)


def test_one_value_per_row():
    rows = np.array([[1.0, 1.0, 1.0], [-2.0, -2.0, -2.0]])
    out = integrated_position_error(rows, 1.0, "accel", "m/s^2")
    np.testing.assert_allclose(out, [4.5, -9.0], rtol=1e-14)
    assert out.shape == (2,)


def test_ramp_closed_forms():
    n, r = 1000, 0.003  # r in units per second, e[k] = r k dt
    h = n * DT
    ramp = r * np.arange(n) * DT
    accel = integrated_position_error(ramp, RATE, "accel", "m/s^2")
    gyro = integrated_position_error(ramp, RATE, "gyro", "rad/s", g=9.81)
    # held ramp: r dt^(m+1)/m! * sum_{j<n} j^m, with Faulhaber's sums of squares and cubes
    assert accel == pytest.approx(r * DT**3 * (n - 1) * n * (2 * n - 1) / 12, rel=1e-12)
    assert gyro == pytest.approx(9.81 * r * DT**4 * n**2 * (n - 1) ** 2 / 24, rel=1e-12)
    # and the continuous ramp r H^3/6, g r H^4/24 to within the hold's leading term
    assert abs(accel - r * h**3 / 6) <= r * DT * h**2 / 4
    assert abs(gyro - 9.81 * r * h**4 / 24) <= 9.81 * r * DT * h**3 / 12


def test_white_noise_gives_the_random_walk_variance():
    # accel white noise (std s per sample, density s^2 dt) -> velocity random walk,
    # var p(H) = s^2 dt H^3/3; gyro -> angle random walk, var p(H) = g^2 s^2 dt H^5/20.
    # The hold rule differs from these by a relative O(1/n^2), negligible here; the
    # mean of m squared Gaussian values has relative std sqrt(2/m): 5 of them allowed.
    m, n, s = 4000, 200, 0.5
    h = n * DT
    noise = np.random.default_rng(7).standard_normal((m, n)) * s
    tol = 5 * math.sqrt(2 / m)
    accel = integrated_position_error(noise, RATE, "accel", "m/s^2")
    assert np.mean(accel**2) / (s**2 * DT * h**3 / 3) == pytest.approx(1.0, abs=tol)
    gyro = integrated_position_error(noise, RATE, "gyro", "deg/s")
    var = 9.81**2 * (s * math.pi / 180) ** 2 * DT * h**5 / 20
    assert np.mean(gyro**2) / var == pytest.approx(1.0, abs=tol)


def test_integrated_position_error_rejects_bad_input():
    with pytest.raises(InputError, match="shape"):
        integrated_position_error(np.zeros((2, 2, 2)), RATE, "accel", "m/s^2")
    with pytest.raises(InputError, match="rate"):
        integrated_position_error(np.zeros(5), 0.0, "accel", "m/s^2")
    with pytest.raises(InputError, match="furlong"):
        integrated_position_error(np.zeros(5), RATE, "accel", "furlong/s")


# -- bias RMS ------------------------------------------------------------------------------


def test_bias_rms_of_a_constant():
    assert bias_rms(np.full(1000, -0.3), 100.0, 1.0) == pytest.approx(0.3, rel=1e-12)


def test_bias_rms_of_white_noise():
    # window means have std s/sqrt(w); the RMS of k of them has relative std ~ 1/sqrt(2k)
    s, rate, tau = 2.0, 100.0, 1.0
    k = 2000
    noise = np.random.default_rng(3).standard_normal(int(k * tau * rate)) * s
    value = bias_rms(noise, rate, tau)
    assert value / (s / math.sqrt(tau * rate)) == pytest.approx(1.0, abs=5 / math.sqrt(2 * k))


def test_bias_rms_of_window_means():
    r = np.repeat([1.0, -1.0, 3.0, 1.0], 100)
    assert bias_rms(r, 100.0, 1.0) == pytest.approx(math.sqrt(3.0), rel=1e-12)
    assert bias_rms(r, 100.0, 2.0) == pytest.approx(math.sqrt(2.0), rel=1e-12)  # means 0, 2


def test_bias_rms_drops_the_incomplete_window():
    r = np.r_[np.ones(200), 100.0 * np.ones(50)]
    assert bias_rms(r, 100.0, 1.0) == 1.0


def test_bias_rms_too_short():
    with pytest.raises(InputError, match="150 samples.*2 windows of 100 samples"):
        bias_rms(np.zeros(150), 100.0, 1.0)
    with pytest.raises(InputError, match="shorter than one sample"):
        bias_rms(np.zeros(150), 100.0, 0.001)


def test_bias_rms_requires_finite_input():
    r = np.zeros(500)
    r[:4] = np.nan
    with pytest.raises(InputError, match="first at sample 0.*lag window"):
        bias_rms(r, 100.0, 1.0)


# -- outage starts -------------------------------------------------------------------------


def test_outage_starts_evenly_spaced():
    s = outage_starts(0, 1000, 100, 20)
    assert len(s) == 20 and s[0] == 0 and s[-1] == 900
    assert set(np.diff(s)) <= {47, 48}


@pytest.mark.parametrize("start, stop, n_steps, count", [
    (0, 1000, 100, 20), (37, 5000, 1, 7), (5, 700, 600, 3), (0, 30, 10, 40)])
def test_outages_lie_inside_the_segment(start, stop, n_steps, count):
    s = outage_starts(start, stop, n_steps, count)
    assert s.min() >= start and s.max() + n_steps <= stop
    assert np.all(np.diff(s) > 0) and len(s) <= count


def test_outage_starts_edge_cases():
    np.testing.assert_array_equal(outage_starts(10, 110, 100), [10])  # exactly one fits
    np.testing.assert_array_equal(outage_starts(0, 105, 100, 20), np.arange(6))  # fewer
    np.testing.assert_array_equal(outage_starts(3, 500, 10, 1), [3])


def test_outage_starts_refuses_a_segment_shorter_than_one_horizon():
    with pytest.raises(InputError, match=r"\[0, 99\) has 99 samples.*100 samples"):
        outage_starts(0, 99, 100)
    with pytest.raises(InputError, match="has 0 samples"):
        outage_starts(50, 10, 5)


@pytest.mark.parametrize("args", [(0, 100, 0), (-1, 100, 10), (0, 100, True), (0, 100, 2.5),
                                  (0, 100, 10, 0)])
def test_outage_starts_refuses_bad_integers(args):
    with pytest.raises(InputError, match="integer"):
        outage_starts(*args)


# -- free-run errors and outage metrics with fake models -----------------------------------


class ZeroModel:
    """Predicts zero, one step ahead and in free run."""

    def simulate(self, y_init, n_steps):
        return np.zeros(n_steps)

    def predict(self, y):
        return np.zeros(len(y))


class TruthModel:
    """Knows the record: its free run is the truth; predict has a 3-sample lag window."""

    def __init__(self, y):
        self.y = np.asarray(y, dtype=float)

    def simulate(self, y_init, n_steps):
        n = len(y_init)
        np.testing.assert_array_equal(y_init, self.y[:n])  # started from the true past
        return self.y[n:n + n_steps]

    def predict(self, y):
        out = np.array(y, dtype=float)
        out[:3] = np.nan
        return out


def test_free_run_errors_exact():
    y = np.random.default_rng(0).standard_normal(100)
    starts = [0, 5, 96]
    zero = free_run_errors(ZeroModel(), y, starts, 4)
    np.testing.assert_array_equal(zero, np.array([y[0:4], y[5:9], y[96:100]]))
    np.testing.assert_array_equal(free_run_errors(TruthModel(y), y, starts, 4), np.zeros((3, 4)))


def test_free_run_errors_refuses_outages_past_the_end():
    with pytest.raises(InputError, match="sample 97 needs 4 samples, but y has 100"):
        free_run_errors(ZeroModel(), np.zeros(100), [0, 97], 4)


def test_outage_metrics_with_zero_model():
    rate, c = 10.0, 2.0  # y = 2 mg held: every outage misses all of it
    y = np.full(2000, c)
    out = outage_metrics(ZeroModel(), y, rate, "accel", "mg", slice(100, 1900), horizon_s=30.0)
    assert out["outage_mse"] == c**2
    assert out["outage_position_error_m"] == pytest.approx(
        c * 9.80665e-3 * 30.0**2 / 2, rel=1e-12)
    assert out["bias_rms"] == {1.0: c, 10.0: c, 30.0: c}
    with pytest.raises(InputError, match=r"^the accel position error needs the record's units$"):
        outage_metrics(ZeroModel(), y, rate, "accel", None, slice(100, 1900), horizon_s=30.0)


def test_outage_metrics_with_zero_model_on_noise():
    rate = 10.0
    y = np.random.default_rng(5).standard_normal(3000)
    seg = slice(200, 2800)
    out = outage_metrics(ZeroModel(), y, rate, "gyro", "deg/h", seg, horizon_s=20.0, n_starts=9,
                         taus=(5.0,))
    starts = outage_starts(200, 2800, 200, 9)
    rows = y[starts[:, None] + np.arange(200)]
    assert out["outage_mse"] == pytest.approx(np.mean(rows**2), rel=1e-12)
    position = integrated_position_error(rows, rate, "gyro", "deg/h")
    assert out["outage_position_error_m"] == pytest.approx(np.sqrt(np.mean(position**2)))
    assert out["bias_rms"][5.0] == pytest.approx(bias_rms(y[seg], rate, 5.0), rel=1e-12)


def test_outage_metrics_with_truth_model():
    y = np.random.default_rng(1).standard_normal(1000)
    out = outage_metrics(TruthModel(y), y, 10.0, "gyro", "deg/s", slice(3, None),
                         horizon_s=5.0, taus=(2.0,))
    assert out == {"outage_mse": 0.0, "outage_position_error_m": 0.0, "bias_rms": {2.0: 0.0}}


def test_outage_metrics_residual_given_or_wrong():
    y = np.zeros(1000)
    out = outage_metrics(ZeroModel(), y, 10.0, "accel", "g", slice(0, 500), horizon_s=5.0,
                         taus=(1.0,), residual=np.full(500, 0.25))
    assert out["bias_rms"] == {1.0: 0.25}
    with pytest.raises(InputError, match=r"shape \(400,\).*\[0, 500\) has 500"):
        outage_metrics(ZeroModel(), y, 10.0, "accel", "g", slice(0, 500), residual=np.zeros(400))
    bad = np.full(500, 0.25)
    bad[7] = np.nan
    with pytest.raises(InputError, match="first at sample 7; bias_rms needs a finite residual"):
        outage_metrics(ZeroModel(), y, 10.0, "accel", "g", slice(0, 500), horizon_s=5.0,
                       taus=(1.0, 2.0), residual=bad)


def test_outage_metrics_segment_inside_the_lag_window():
    y = np.ones(1000)
    with pytest.raises(InputError, match="first at sample 0.*lag window"):
        outage_metrics(TruthModel(y), y, 10.0, "accel", "m/s^2", slice(0, None), horizon_s=5.0)


@pytest.mark.parametrize("segment, horizon_s, match", [
    (slice(0, 1000, 2), 5.0, "step 1"), (slice(500, 100), 5.0, "empty"),
    (slice(0, 40), 5.0, "40 samples"), (slice(0, 1000), 0.01, "shorter than one sample")])
def test_outage_metrics_bad_segment_or_horizon(segment, horizon_s, match):
    with pytest.raises(InputError, match=match):
        outage_metrics(ZeroModel(), np.zeros(1000), 10.0, "accel", "m/s^2", segment,
                       horizon_s=horizon_s)


# -- one-step MSE --------------------------------------------------------------------------


def test_one_step_mse():
    y = np.arange(10.0)
    pred = y + 0.5
    pred[:3] = np.nan
    assert one_step_mse(y, pred, slice(3, None)) == 0.25
    assert one_step_mse(y, y - np.r_[np.zeros(5), 2.0 * np.ones(5)], slice(4, 8)) == 3.0


def test_one_step_mse_refuses_the_lag_window():
    pred = np.r_[np.full(3, np.nan), np.zeros(7)]
    with pytest.raises(InputError, match=r"NaN at sample 1 .*\[1, 10\).*lag window"):
        one_step_mse(np.zeros(10), pred, slice(1, None))


def test_one_step_mse_bad_shapes():
    with pytest.raises(InputError, match="shape"):
        one_step_mse(np.zeros(10), np.zeros(9), slice(None))
    with pytest.raises(InputError, match="empty"):
        one_step_mse(np.zeros(10), np.zeros(10), slice(5, 5))


# -- a real FOSModel on an AR(2) record ----------------------------------------------------

A1, A2 = 1.5, -0.7  # y[n] = 1.5 y[n-1] - 0.7 y[n-2] + e[n], e ~ N(0, 1)
N_RECORD = 300_000


@pytest.fixture(scope="module")
def ar2():
    y = lfilter([1.0], [1.0, -A1, -A2], np.random.default_rng(11).standard_normal(N_RECORD))
    return y, FOSModel(max_lag=4).fit(y)


def _impulse_response(n):
    return lfilter([1.0], [1.0, -A1, -A2], np.r_[1.0, np.zeros(n - 1)])


def test_ar2_long_horizon_free_run_approaches_the_process_variance(ar2):
    y, model = ar2
    horizon, m = 100, 1500  # starts 200 apart: rows independent (|roots| = 0.84)
    starts = outage_starts(1000, N_RECORD, horizon, m)
    errors = free_run_errors(model, y, starts, horizon)
    var_process = (1 - A2) / ((1 + A2) * ((1 - A2) ** 2 - A1**2))
    psi2 = _impulse_response(horizon) ** 2
    assert psi2.sum() == pytest.approx(var_process, rel=1e-12)  # converged by the last step
    # last step: m independent squares of N(0, var) -> relative std sqrt(2/m)
    assert np.mean(errors[:, -1] ** 2) / var_process == pytest.approx(1.0,
                                                                      abs=4 * math.sqrt(2 / m))
    # all steps: the h-step error variance is sum_{j<h} psi_j^2, averaged over h = 1..H
    expected = np.mean(np.cumsum(psi2))
    row_mse = np.mean(errors**2, axis=1)
    assert np.mean(row_mse) == pytest.approx(expected, abs=4 * row_mse.std() / math.sqrt(m))


def test_ar2_one_step_horizon_is_the_innovation(ar2):
    y, model = ar2
    m = 1500
    starts = outage_starts(1000, N_RECORD, 1, m)
    errors = free_run_errors(model, y, starts, 1)[:, 0]
    np.testing.assert_allclose(errors, (y - model.predict(y))[starts], rtol=1e-9, atol=1e-12)
    assert np.mean(errors**2) == pytest.approx(1.0, abs=4 * math.sqrt(2 / m))


def test_ar2_outage_metrics(ar2):
    y, model = ar2
    rate, seg = 100.0, slice(1000, N_RECORD)
    out = outage_metrics(model, y, rate, "gyro", "deg/s", seg, horizon_s=1.0, n_starts=50,
                         taus=(1.0,))
    starts = outage_starts(1000, N_RECORD, 100, 50)
    errors = free_run_errors(model, y, starts, 100)
    assert out["outage_mse"] == pytest.approx(np.mean(errors**2), rel=1e-12)
    # the residual is the innovation: windows of 100 white samples, 2990 of them
    k = (N_RECORD - 1000) // 100
    assert out["bias_rms"][1.0] / 0.1 == pytest.approx(1.0, abs=5 / math.sqrt(2 * k))
    assert out["bias_rms"][1.0] == pytest.approx(
        bias_rms(model.residuals(y)[seg], rate, 1.0), rel=1e-12)
