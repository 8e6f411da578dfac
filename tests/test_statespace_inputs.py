"""A client's path through the state space: derived inputs, compensations, starting
covariances and the navigation error models built on an error model."""

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel, InputError
from fosmodel.core import derive, describe
from fosmodel.filter import (
    KalmanFilter,
    initial_covariance,
    position_velocity_error_model,
    run_filter,
    tilt_error_model,
    to_state_space,
)
from fosmodel.models import compensation_series

RATE = 10.0
N = 12_000
TIME_COLUMNS = ["t@s", "cos@0.188Hz", "exp(-t/413.66s)"]


def _driven_record(seed=3):
    """AR(2) noise, a trend, a 0.188 Hz line, a decay and a fast temperature part."""
    rng = np.random.default_rng(seed)
    t = np.arange(N) / RATE
    temp = 25.0 + np.cumsum(rng.standard_normal(N)) * 0.02 + 0.3 * rng.standard_normal(N)
    fast = derive("temp_c_fast20s", N, RATE, {"temp_c": temp}, {})
    noise = lfilter([1.0], [1.0, -0.5, 0.2], rng.standard_normal(N)) * 0.1
    y = (2.0 + 1e-4 * t + 0.3 * np.cos(2 * np.pi * 0.188 * t) + 0.5 * np.exp(-t / 413.66)
         + 0.4 * np.r_[0.0, fast[:-1]] + noise)
    return y, {"temp_c": temp}


def _one_step(ss, y, u, start):
    """One-step predictions through the exported filter from the true past."""
    out = np.full(len(y), np.nan)
    for n in range(start, len(y)):
        x = ss.state_from(y[:n], u[:n] if np.any(ss.D) else None)
        out[n] = ss.predict_measurement(ss.step(x, u[n]), u[n])
    return out


def test_derive_counts_time_from_start_and_describe_gives_definition_and_unit():
    np.testing.assert_array_equal(derive("t@s", 4, 10.0, {}, {}, start=100),
                                  [10.0, 10.1, 10.2, 10.3])
    whole = derive("cos@0.188Hz", 50, 10.0, {}, {})
    np.testing.assert_allclose(derive("cos@0.188Hz", 20, 10.0, {}, {}, start=30), whole[30:],
                               rtol=0, atol=1e-12)
    assert describe("t@s") == ("t, t = (start + n) / rate in s", "s")
    assert describe("cos@0.188Hz").unit == "1"
    assert describe("temp_c_fast20s", {"temp_c": "degC"}).unit == "degC"
    assert describe("rate(temp_c,60s)").unit == "[temp_c]/s"
    assert describe("pow(lowpass(temp_c,600s),2,25)", {"temp_c": "degC"}).unit == "(degC)^2"
    with pytest.raises(InputError, match=r"^column 'temp_c\[n-1\]' is not one fosmodel can "
                                         r"derive$"):
        describe("temp_c[n-1]")


def test_input_matrix_builds_every_derived_input_and_reproduces_predict():
    y, exog = _driven_record()
    # fitted as the loop fits it: every derived column given as an array
    arrays = {name: derive(name, N, RATE, exog, {}) for name in [*TIME_COLUMNS, "temp_c_fast20s"]}
    model = FOSModel(max_lag=2, columns=TIME_COLUMNS, exog_lags={"temp_c_fast20s": 1},
                     rate=RATE).fit(y, {**exog, **arrays})
    assert {"t@s", "cos@0.188Hz", "exp(-t/413.66s)", "temp_c_fast20s[n-1]"} <= set(model.terms_)
    ss = to_state_space(model)
    u = ss.input_matrix(exog, N)  # the raw channel only: every derived input is built
    assert ss.input_names[0] == "1" and np.all(u[:, 0] == 1.0)
    start = 200
    np.testing.assert_allclose(_one_step(ss, y, u, start)[start:],
                               model.predict(y, exog)[start:], rtol=0, atol=1e-9)
    # the second half, as a client filtering it alone: time counts from the fitting record
    half = N // 2
    second = ss.input_matrix({"temp_c": exog["temp_c"][half:]}, N - half, start=half)
    time_cols = [ss.input_names.index(c) for c in ["1", *TIME_COLUMNS]]
    np.testing.assert_allclose(second[:, time_cols], u[half:, time_cols], rtol=0, atol=1e-12)
    with pytest.raises(InputError, match="channel 'temp_c' not given"):
        ss.input_matrix({}, N)


def test_the_constant_input_is_built_and_a_wrong_one_refused_by_name():
    y, exog = _driven_record()
    ss = to_state_space(FOSModel(max_lag=2, rate=RATE).fit(y))
    assert ss.input_names == ("1",)
    np.testing.assert_array_equal(ss.input_matrix(None, 5), np.ones((5, 1)))
    with pytest.raises(InputError) as err:
        ss.input_matrix({"1": np.zeros(5)}, 5)
    assert str(err.value) == ("input '1' is the constant 1 (the intercept and the centring "
                              "offsets sit in its column of B); exog's column '1' is not all "
                              "ones")
    with pytest.raises(InputError, match=r"^u must hold the 1 input\(s\) 1; got 0 value\(s\)$"):
        ss.step(np.zeros(ss.n_states), [])


def test_a_compensation_is_the_feedthrough_and_the_model_of_what_remains_is_public():
    y, exog = _driven_record(5)
    comp = {"lowpass(temp_c,60s)": 0.2, "t@s": 1e-4}
    model = FOSModel(max_lag=2, rate=RATE, compensation=comp).fit(y, exog)
    ss = to_state_space(model)
    for name, w in comp.items():
        assert ss.D[0, ss.input_names.index(name)] == w
    u = ss.input_matrix(exog, N)
    np.testing.assert_allclose(u @ ss.D[0], compensation_series(comp, exog, N, RATE),
                               rtol=0, atol=1e-12)
    start = 100
    np.testing.assert_allclose(_one_step(ss, y, u, start)[start:],
                               model.predict(y, exog)[start:], rtol=0, atol=1e-9)
    plain = model.without_compensation()
    assert plain.compensation is None and plain.terms_ == model.terms_
    remains = y - compensation_series(comp, exog, N, RATE)
    np.testing.assert_allclose(plain.predict(remains), model.predict(y, exog) - (y - remains),
                               rtol=0, atol=1e-9)
    with pytest.raises(InputError, match=r"feedthrough D u \(inputs lowpass\(temp_c,60s\), t@s\)"):
        ss.state_from(y[:10])


def test_process_covariance_is_g_q_g():
    y, _ = _driven_record()
    ss = to_state_space(FOSModel(max_lag=3, levels=[30.0], rate=RATE).fit(y))
    np.testing.assert_array_equal(ss.process_covariance(), ss.G @ ss.Q @ ss.G.T)
    assert ss.process_covariance().shape == (ss.n_states, ss.n_states)


def _walk_plus_ar(n=20_000, seed=8):
    rng = np.random.default_rng(seed)
    return (lfilter([1.0], [1.0, -0.6], rng.standard_normal(n)) * 0.05
            + np.cumsum(rng.standard_normal(n)) * 0.002)


def test_a_level_held_inside_an_ar_gets_a_starting_covariance_and_its_filter_converges():
    y = _walk_plus_ar()
    fitted = FOSModel(max_lag=3, levels=[30.0], rate=RATE).fit(y)
    held = fitted.refit_weights(y, hold=True)
    ss = to_state_space(held)
    assert np.max(np.abs(np.linalg.eigvals(ss.Phi))) == pytest.approx(1.0, abs=1e-9)
    p0 = initial_covariance(ss, 10_000)
    assert np.all(np.isfinite(p0)) and np.all(np.linalg.eigvalsh(p0) > 0)
    # the unit root's direction l (l Phi = l) holds the walk the calibration leaves: its
    # variance per step q_l over 1 - rho^2, about q_l n / 3
    vals, vecs = np.linalg.eig(ss.Phi.T)
    lead = vecs[:, np.argmin(np.abs(vals - 1.0))].real
    q_l = lead @ ss.process_covariance() @ lead
    rho = (1 - 1.5 / 10_000) / np.max(np.abs(vals))
    assert lead @ p0 @ lead == pytest.approx(q_l / (1 - rho**2), rel=1e-6)
    level = ss.n_states - 1
    # the filter of the model's own output from x0 = 0 and this P0: estimates converge
    rng = np.random.default_rng(9)
    m = 4000
    sim = ss.simulate(m, inputs=np.ones((m, 1)), noise=rng.standard_normal(m)
                      * math.sqrt(ss.Q[0, 0]))
    r = 0.02**2
    kf = KalmanFilter(ss.Phi, ss.G, ss.Q, ss.H, [[r]], np.zeros(ss.n_states), p0, ss.B)
    z = sim - ss.mu + rng.standard_normal(m) * math.sqrt(r)
    run = run_filter(kf, z, np.ones((m, 1)))
    err = run.x[:, 0] - (sim - ss.mu)
    late = slice(m // 2, m)
    rms = float(np.sqrt(np.mean(err[late] ** 2)))
    sigma = float(np.sqrt(np.mean(run.variance[late, 0])))
    assert rms < 0.5 * float(np.std(z[late]))  # it tracks the output
    assert 0.7 < sigma / rms < 1.4  # and its covariance says how well
    assert run.variance[-1, level] < 1e-3 * p0[level, level]  # the diffuse prior is narrowed


def _white_gyro_model(n_sd, rate):
    y = np.random.default_rng(1).standard_normal(20_000) * n_sd
    from fosmodel.models.baselines import GaussMarkovModel

    return to_state_space(GaussMarkovModel(rate=rate).fit(y))


def test_tilt_model_integrates_the_gyro_error_through_g_theta():
    dt, g = 0.1, 9.80665
    error = _white_gyro_model(1e-3, 1 / dt)
    tilt = tilt_error_model(error, dt, scale=math.pi / 180)
    assert tilt.state_names[:3] == ("dp", "dv", "dtheta")
    rng = np.random.default_rng(2)
    m = 600
    w = rng.standard_normal(m) * math.sqrt(error.Q[0, 0])
    sim = tilt.simulate(m, noise=w)
    # the recursion of studies/kalman_joint.py in 1-D, on the error model's own output
    rate_error = error.simulate(m, noise=w) - error.mu
    p = v = theta = 0.0
    truth = np.empty(m)
    for k in range(m):
        rate_prev = rate_error[k - 1] if k else 0.0
        p, v, theta = p + dt * v, v + dt * g * theta, theta + dt * math.radians(rate_prev)
        truth[k] = p
    np.testing.assert_allclose(sim, truth, rtol=1e-9, atol=1e-15)


def test_an_uncompensated_bias_enters_the_integrator_it_drives():
    dt = 0.01
    error = _white_gyro_model(1e-3, 1 / dt)
    biased = tilt_error_model(error, dt, bias="uncompensated")
    assert biased.input_names == ("1", *error.input_names)
    m = 1000
    pos = biased.simulate(m, inputs=np.ones((m, 1)))
    # a constant rate error b: theta = b k dt, v = g b dt^2 k(k-1)/2, p its sum
    b, g = error.mu, 9.80665
    k = np.arange(1, m + 1)
    expected = g * b * dt**3 * (k - 1) * (k - 2) * k / 6
    np.testing.assert_allclose(pos, expected, rtol=1e-9)
    accel = position_velocity_error_model(error, dt, bias="uncompensated")
    np.testing.assert_allclose(accel.simulate(m, inputs=np.ones((m, 1))),
                               b * dt**2 * (k - 1) * k / 2, rtol=1e-9)
    with pytest.raises(InputError, match=r"^bias must be one of compensated, uncompensated, "
                                         r"got 'angle'$"):
        tilt_error_model(error, dt, bias="angle")
