"""Gyro arrays (fosmodel.filter.arrays): closed forms of Koldbæk and Totu 2011, gain, drift, FOS."""

import math

import numpy as np
import pytest

from data_synth import CorrelatedRandomWalk, CorrelatedWhiteNoise, compose, make_scenario
from data_synth.scenarios import ARRAY_ARW, ARRAY_RRW
from fosmodel import InputError
from fosmodel.filter.arrays import (
    CORR_EQ_8_8,
    CORR_Q3,
    CORR_Q5,
    ArrayModel,
    angle_error_std,
    angle_sum,
    averaging_angle_std,
    averaging_rate_std,
    conditional_variance,
    constant_gain_filter,
    correlation,
    covariance,
    cross_gyro_comparison,
    kalman_angle_std,
    recursive_gain,
    steady_state_gain,
)

NAMES = tuple(f"gyro_{i}" for i in range(1, 9))
#: Koldbæk and Totu (2011) eq. 8.9: the converged recursive gain of the three-gyro example
#: (rows omega, b_1..3).
GAIN_EQ_8_9 = np.array([
    [0.332815351545374, 0.332820262807916, 0.332827785499759],
    [3.31879037392269e-05, -7.49804087920127e-06, -2.56898612103661e-05],
    [-2.58677834142207e-06, 3.13564393958052e-05, -2.87696601089407e-05],
    [-1.32559067993142e-05, -2.12469682356657e-05, 3.45028735409536e-05]])


@pytest.mark.parametrize(("n_gyros", "rho", "hours", "thesis"), [
    (1, 0.0, 1, 36.4), (8, 0.0, 1, 12.87), (8, -0.1, 1, 7.15), (8, -0.1428571, 1, 1.44),
    (8, -1 / 7, 1, 1.44), (8, 0.3, 1, 22.56), (8, -0.1428571, 10, 4.57)])
def test_averaging_drift_reproduces_koldbaek_totu_2011_table_10_2(n_gyros, rho, hours, thesis):
    drift = averaging_angle_std(3600.0 * hours, 100.0, 0.0029, 0.68, n_gyros, rho_w=rho)
    digits = len(str(thesis).split(".")[1])
    assert round(drift, digits) == thesis


def test_averaging_rate_noise_reproduces_koldbaek_totu_2011_table_10_1():
    assert round(averaging_rate_std(3600.0, 100.0, n_gyros=8), 4) == 0.2405
    assert round(averaging_rate_std(3600.0, 100.0, n_gyros=8, rho_w=-0.1428571), 4) == 0.2404
    assert round(averaging_rate_std(3600.0, 100.0, n_gyros=8, rho_w=0.3), 4) == 0.2407
    # the single-sensor entry 0.4627 of Table 10.1 is the variance, (deg/s)^2, of eq. 7.5
    assert round(averaging_rate_std(3600.0, 100.0) ** 2, 4) == 0.4627


def test_averaging_drift_reproduces_the_averaging_column_of_koldbaek_totu_2011_table_10_3():
    model = {"Q3": ArrayModel.from_noise(8, 100.0, corr_w=CORR_Q3),
             "Q5": ArrayModel.from_noise(8, 100.0, corr_w=CORR_Q5)}
    got = {(k, h): round(float(angle_error_std(360_000 * h, 0.01, m.cov_w, m.cov_v)), 2)
           for k, m in model.items() for h in (1, 2)}
    assert got == {("Q3", 1): 9.24, ("Q3", 2): 25.91, ("Q5", 1): 13.14, ("Q5", 2): 36.99}


def test_angle_sum_is_the_bracket_of_eq_7_15_and_the_sum_of_min():
    for n in (1, 2, 7, 30):
        bracket = n * (n + 1) / 2 + 2 * sum(k * (n - k) for k in range(1, n))
        pairs = sum(min(k, m) for k in range(1, n + 1) for m in range(1, n + 1))
        assert angle_sum(n) == bracket == pairs


def test_general_angle_error_matches_the_covariance_of_the_summed_readings():
    rng = np.random.default_rng(0)
    n, n_steps, ts = 3, 6, 0.5
    a_w, a_v = rng.normal(size=(n, n)), rng.normal(size=(n, n))
    cov_w, cov_v, weights = a_w @ a_w.T, a_v @ a_v.T, rng.normal(size=n)
    # angle = ts sum_k a'(b[k] + v[k]), b[k] = ts sum_{p<=k} w[p]: linear in all the noises
    load_w = np.kron(ts * ts * np.arange(n_steps, 0, -1), weights)
    load_v = np.kron(ts * np.ones(n_steps), weights)
    var = load_w @ np.kron(np.eye(n_steps), cov_w) @ load_w
    var += load_v @ np.kron(np.eye(n_steps), cov_v) @ load_v
    got = angle_error_std(n_steps, ts, cov_w, cov_v, weights)
    assert got == pytest.approx(math.sqrt(var), rel=1e-12)


def test_steady_state_gain_reproduces_koldbaek_totu_2011_eq_8_9():
    gain = steady_state_gain(ArrayModel.from_noise(3, 100.0, corr_w=CORR_EQ_8_8))
    # float64 limit: sigma_omega = 1e3 against sigma_w = 0.0029 and bias modes of ~3e4 samples
    np.testing.assert_allclose(gain, GAIN_EQ_8_9, rtol=0, atol=1e-4 * 3.5e-5)
    # section 9.4: the bias rows sum to ~1e-12 and the rate row to 1 - 0.0015 (finite sigma_omega)
    np.testing.assert_allclose(gain[1:] @ np.ones(3), [1.65219848910557e-12,
                               9.46897515095597e-13, -1.49632568027759e-12], rtol=0.01)
    assert 1 - gain[0].sum() == pytest.approx(1 - 0.998463399853048, rel=1e-6)


def test_steady_state_gain_is_the_limit_of_the_recursive_filter():
    model = ArrayModel.from_noise(3, 10.0, sigma_w=0.05, sigma_omega=1.0, corr_w=CORR_EQ_8_8)
    gain = steady_state_gain(model)
    np.testing.assert_allclose(recursive_gain(model, 3000), gain, rtol=0,
                               atol=1e-10 * np.abs(gain[1:]).max())
    early = recursive_gain(model, 20)
    assert np.abs(early[1:] - gain[1:]).max() > 0.1 * np.abs(gain[1:]).max()
    with pytest.raises(InputError, match=r"^n_steps must be at least 1, got 0$"):
        recursive_gain(model, 0)  # no update, so no gain


def test_kalman_equals_averaging_for_equal_uncorrelated_gyros():
    model = ArrayModel.from_noise(8, 100.0)
    kalman = kalman_angle_std(model, steady_state_gain(model), 60_000, every=20_000)
    average = angle_error_std(np.array([20_000, 40_000, 60_000]), 0.01, model.cov_w, model.cov_v)
    np.testing.assert_allclose(kalman, average, rtol=1e-6)


def _still_array(seed, corr_w, rrw, duration=60.0, rate=102.4):
    rec = compose([CorrelatedWhiteNoise(NAMES, ARRAY_ARW, 0.0, name="arw"),
                   CorrelatedRandomWalk(NAMES, rrw, corr_w, name="rrw")],
                  duration=duration, rate=rate, seed=seed, target="gyro_1",
                  column_units={n: "deg/s" for n in NAMES})
    return np.column_stack([rec.columns[n] for n in NAMES])


@pytest.mark.slow
def test_monte_carlo_drift_agrees_with_the_closed_forms():
    rate, runs = 102.4, 400
    rrw = 30 * np.array(ARRAY_RRW)  # 30x the thesis's RRW: bias walks matter in 60 s
    model = ArrayModel(covariance(rrw * math.sqrt(rate), CORR_Q5, 8),
                       covariance(np.array(ARRAY_ARW) * math.sqrt(rate), 0.0, 8), rate)
    gain = steady_state_gain(model)
    z = np.stack([_still_array(seed, CORR_Q5, rrw) for seed in range(runs)])
    ts, n = 1.0 / rate, z.shape[1]
    final = {"single": ts * z[:, :, 0].sum(axis=1), "average": ts * z.mean(axis=2).sum(axis=1),
             "kalman": ts * constant_gain_filter(z, gain)[:, :, 0].sum(axis=1)}
    closed = {"single": angle_error_std(n, ts, model.cov_w, model.cov_v, np.eye(8)[0]),
              "average": angle_error_std(n, ts, model.cov_w, model.cov_v),
              "kalman": kalman_angle_std(model, gain, n)[-1]}
    tol = 4.0 / math.sqrt(2 * runs)  # four standard errors of a standard deviation
    for name, values in final.items():
        assert math.sqrt(np.mean(values**2)) / closed[name] == pytest.approx(1.0, abs=tol), name
    assert closed["kalman"] < 0.5 * closed["average"]


def test_constant_gain_filter_runs_records_together_or_alone():
    z = _still_array(1, 0.0, ARRAY_RRW, duration=5.0)
    gain = steady_state_gain(ArrayModel.from_noise(8, 102.4))
    both = constant_gain_filter(np.stack([z, 2 * z]), gain)
    # batched and single products may round differently (numpy's stacked matmul): compare to
    # rounding relative to each estimate's scale, not to entries that cancel to ~1e-18
    scale = 1e-12 * np.abs(both[0]).max(axis=0)
    assert np.all(np.abs(both[0] - constant_gain_filter(z, gain)) <= scale)
    assert np.all(np.abs(both[1] - 2 * both[0]) <= 2 * scale)
    with pytest.raises(InputError, match="z has 7 gyros, the gain is for 8"):
        constant_gain_filter(z[:, :7], gain)


@pytest.mark.parametrize(("params", "helps"), [
    ({"rho_arw": 0.3}, True), ({"rho_arw": -0.1}, True), ({}, False), ({"rho_rrw": 0.9}, False)])
def test_fos_with_the_other_gyros_beats_ar_only_when_white_noises_correlate(params, helps):
    rec = make_scenario("gyro_array_8", duration=120, seed=3, **params)
    res = cross_gyro_comparison(rec.columns, "gyro_1")
    ratio = res["fos_exog_mse"] / res["ar_mse"]
    sigma_v = np.array(ARRAY_ARW) * math.sqrt(rec.rate)
    bound = conditional_variance(covariance(sigma_v, params.get("rho_arw", 0.0), 8))
    if helps:
        assert ratio < 0.85
        assert res["fos_exog_mse"] == pytest.approx(bound, rel=0.05)
        assert all(t.endswith("[n-0]") and t.startswith("gyro_") for t in res["fos_exog_terms"])
    else:
        assert ratio == pytest.approx(1.0, abs=0.01)


def test_correlations_outside_eq_6_38_are_refused():
    correlation(8, -1 / 7)
    with pytest.raises(InputError, match=r"rho >= -0.1428571"):
        correlation(8, -0.2)
    with pytest.raises(InputError, match="symmetric 2 x 2"):
        correlation(2, np.array([[1.0, 0.5], [0.4, 1.0]]))
