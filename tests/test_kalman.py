import math

import numpy as np
import pytest
from scipy.linalg import solve_discrete_are

from fosmodel import InputError
from fosmodel.filter.kalman import KalmanFilter, run_filter
from fosmodel.filter.statespace import position_velocity_error_model, to_state_space
from fosmodel.models.baselines import ARModel


def test_random_walk_reaches_the_closed_form_riccati_solution():
    q, r = 0.04, 1.0
    kf = KalmanFilter([[1.0]], [[1.0]], [[q]], [[1.0]], [[r]], [0.0], [[100.0]])
    z = np.random.default_rng(0).standard_normal(300)
    run_filter(kf, z)
    prior = (q + math.sqrt(q * q + 4 * q * r)) / 2  # P^2 / (P + r) = q
    assert prior == pytest.approx(solve_discrete_are([[1.0]], [[1.0]], [[q]], [[r]])[0, 0])
    assert kf.K[0, 0] == pytest.approx(prior / (prior + r), rel=1e-12)
    assert kf.P[0, 0] == pytest.approx(prior * r / (prior + r), rel=1e-12)


def test_static_state_estimate_is_the_running_mean():
    z = 5.0 + np.random.default_rng(1).standard_normal(200)
    kf = KalmanFilter([[1.0]], [[1.0]], [[0.0]], [[1.0]], [[1.0]], [0.0], [[1e12]])
    run = run_filter(kf, z)
    mean = np.cumsum(z) / np.arange(1, len(z) + 1)
    np.testing.assert_allclose(run.x[:, 0], mean, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.variance[:, 0], 1.0 / np.arange(1, len(z) + 1), rtol=1e-9)


def test_prediction_propagates_the_covariance():
    rng = np.random.default_rng(2)
    n = 4
    phi, g, b = rng.normal(size=(n, n)), rng.normal(size=(n, 2)), rng.normal(size=(n, 1))
    q = np.array([[2.0, 0.3], [0.3, 0.5]])
    a = rng.normal(size=(n, n))
    p0, x0 = a @ a.T, rng.normal(size=n)
    kf = KalmanFilter(phi, g, q, np.eye(1, n), [[1.0]], x0, p0, B=b)
    p, x = p0, x0
    for u in (0.5, -1.0, 2.0):
        kf.predict([u])
        p, x = phi @ p @ phi.T + g @ q @ g.T, phi @ x + b[:, 0] * u
        np.testing.assert_allclose(kf.P, p, rtol=1e-12)
        np.testing.assert_allclose(kf.x, x, rtol=1e-12)


def test_missing_measurements_only_predict():
    kf = KalmanFilter([[0.9]], [[1.0]], [[0.1]], [[1.0]], [[0.5]], [1.0], [[1.0]])
    run = run_filter(kf, [np.nan, np.nan, 2.0])
    p1 = 0.81 * 1.0 + 0.1
    p2 = 0.81 * p1 + 0.1
    np.testing.assert_allclose(run.x[:2, 0], [0.9, 0.81])
    np.testing.assert_allclose(run.variance[:2, 0], [p1, p2])
    np.testing.assert_allclose(run.variance[2, 0], 1 / (1 / (0.81 * p2 + 0.1) + 1 / 0.5))


def test_joseph_update_equals_the_standard_form():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(3, 3))
    p0 = a @ a.T
    h, r = rng.normal(size=(2, 3)), np.diag([0.3, 0.7])
    kf = KalmanFilter(np.eye(3), np.eye(3), np.zeros((3, 3)), h, r, np.zeros(3), p0)
    kf.update([1.0, -2.0])
    k = p0 @ h.T @ np.linalg.inv(h @ p0 @ h.T + r)
    np.testing.assert_allclose(kf.P, (np.eye(3) - k @ h) @ p0, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(kf.x, k @ [1.0, -2.0], rtol=1e-12)


def test_filter_of_an_exported_error_model_tracks_a_simulated_position():
    """The filter of eq. 5.7 stays within its own 3-sigma on data from its model."""
    dt = 0.05
    rng = np.random.default_rng(5)
    acc = np.convolve(rng.standard_normal(6000), [0.5, 0.3, 0.2])[:6000] * 0.01
    model = ARModel(2).fit(acc)
    system = position_velocity_error_model(to_state_space(model), dt)
    a = acc - model.mean_
    v = dt * np.r_[0.0, np.cumsum(a[:-1])]
    p = dt * np.r_[0.0, np.cumsum(v[:-1])]
    kf = KalmanFilter.from_state_space(
        system, [[0.01]], np.zeros(4), np.diag([0.0, 0.0, 1e-4, 1e-4]))
    run = run_filter(kf, p[1:] + 0.1 * rng.standard_normal(len(p) - 1))
    err = run.x[:, 0] - p[1:]
    assert np.mean(np.abs(err) < 3 * np.sqrt(run.variance[:, 0])) > 0.98


def test_bad_shapes_and_missing_inputs_are_refused():
    with pytest.raises(InputError, match="H must be a finite 1 x 2"):
        KalmanFilter(np.eye(2), np.eye(2), np.eye(2), [[1.0, 0.0, 0.0]], [[1.0]],
                     np.zeros(2), np.eye(2))
    kf = KalmanFilter([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]], [0.0], [[1.0]], B=[[1.0]])
    with pytest.raises(InputError, match="u is needed"):
        kf.predict()
