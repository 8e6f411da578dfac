"""The compiled filter loop against the NumPy loop and filterpy; the aided runner."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import block_diag

from fosmodel.core.exceptions import InputError
from fosmodel.filter import (
    KalmanFilter,
    StateSpace,
    accelerometer_run,
    aided_position_run,
    compare_in_filter,
    integrate,
    position_fixes,
    position_velocity_error_model,
    run_filter,
)

pytest.importorskip("numba", reason="the compiled loop needs numba (the fast extra)")

DT = 0.05


def error_model(with_input: bool = False) -> StateSpace:
    phi = np.diag([0.0, np.exp(-DT / 20.0), 1.0])
    b = np.array([[0.0], [0.0], [0.0]]) if not with_input else np.array([[0.0], [0.3], [0.0]])
    return StateSpace(Phi=phi, B=b[:, :1] if with_input else np.zeros((3, 0)), G=np.eye(3),
                      H=np.ones((1, 3)), Q=np.diag([1e-4, 1e-7, 1e-10]), mu=0.0,
                      state_names=("white", "gm", "rw"),
                      input_names=("u",) if with_input else ())


def filters(system: StateSpace, p0: np.ndarray) -> tuple[KalmanFilter, KalmanFilter]:
    return tuple(KalmanFilter.from_state_space(system, [[0.01]], np.zeros(system.n_states), p0)
                 for _ in range(2))


@pytest.mark.parametrize("with_input", [False, True])
def test_compiled_loop_matches_the_numpy_loop(with_input):
    system = position_velocity_error_model(error_model(with_input), DT)
    p0 = block_diag(np.zeros((2, 2)), np.diag([1e-4, 1e-7, 1e-6]))
    rng = np.random.default_rng(0)
    n = 3000
    z = np.where(position_fixes(n, 20, DT), rng.standard_normal(n), np.nan)
    u = rng.standard_normal((n, 1)) if with_input else None
    a, b = filters(system, p0)
    slow = run_filter(a, z, u, engine="numpy")
    fast = run_filter(b, z, u, engine="numba")
    np.testing.assert_allclose(fast.x, slow.x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fast.variance, slow.variance, rtol=1e-9, atol=1e-18)
    np.testing.assert_allclose(b.P, a.P, rtol=1e-9, atol=1e-18)


def test_compiled_loop_matches_filterpy():
    from filterpy.kalman import KalmanFilter as FilterPy

    system = position_velocity_error_model(error_model(), DT)
    p0 = block_diag(np.eye(2) * 1e-3, np.diag([1e-4, 1e-7, 1e-6]))
    n = 2000
    z = np.where(position_fixes(n, 10, DT), np.random.default_rng(1).standard_normal(n),
                 np.nan)
    kf = KalmanFilter.from_state_space(system, [[0.01]], np.zeros(5), p0)
    ours = run_filter(kf, z, engine="numba")
    ref = FilterPy(dim_x=5, dim_z=1)
    ref.F, ref.H, ref.R = system.Phi, system.H, np.array([[0.01]])
    ref.Q = system.G @ system.Q @ system.G.T
    ref.x, ref.P = np.zeros((5, 1)), p0.copy()
    xs, var = [], []
    for zk in z:
        ref.predict()
        if np.isfinite(zk):
            ref.update(np.array([[zk]]))
        xs.append(ref.x[:, 0].copy())
        var.append(np.diag(ref.P).copy())
    np.testing.assert_allclose(ours.x, np.array(xs), rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(ours.variance, np.array(var), rtol=1e-7, atol=1e-18)


def test_engine_errors_name_the_problem():
    kf = KalmanFilter(np.eye(2), np.eye(2), np.eye(2), np.eye(2), np.eye(2), np.zeros(2),
                      np.eye(2))
    with pytest.raises(InputError, match="engine must be"):
        run_filter(kf, np.zeros((3, 2)), engine="fast")
    with pytest.raises(InputError, match="scalar measurement"):
        run_filter(kf, np.zeros((3, 2)), engine="numba")
    auto = run_filter(kf, np.zeros((3, 2)), engine="auto")  # falls back to NumPy
    assert auto.x.shape == (3, 2)


def test_aided_run_of_a_model_on_its_own_process_is_consistent():
    # the record is drawn from the error model itself: the filter's sigma is its error's
    error = error_model()
    rng = np.random.default_rng(3)
    n = 60_000
    x = np.zeros(3)
    accel = np.empty(n)
    for k in range(n):
        x = error.Phi @ x + np.sqrt(np.diag(error.Q)) * rng.standard_normal(3)
        accel[k] = x.sum()
    p0 = np.diag([1e-4, 1e-7 / (1 - error.Phi[1, 1] ** 2), 0.0])
    run = accelerometer_run(error, p0, accel, rng.standard_normal(n), 0.1, 30, DT)
    assert 0.8 < run.sigma_over_rms < 1.25
    assert 0.7 < run.nees < 1.4
    assert run.rms == pytest.approx(np.sqrt(np.mean(run.error**2)))


def test_accelerometer_run_is_the_position_system_with_its_truth():
    error = error_model()
    rng = np.random.default_rng(4)
    accel, noise = 0.01 * rng.standard_normal(4000), rng.standard_normal(4000)
    p0e = np.diag([1e-4, 1e-6, 1e-6])
    run = accelerometer_run(error, p0e, accel, noise, 0.1, 20, DT)
    system = position_velocity_error_model(error, DT)
    same = aided_position_run(system, block_diag(np.zeros((2, 2)), p0e), integrate(accel, DT),
                              noise, 0.1, 20, DT, engine="numpy")
    np.testing.assert_allclose(run.error, same.error, rtol=1e-9, atol=1e-12)
    both = compare_in_filter({"a": (error, p0e), "b": (error, 10 * p0e)}, accel, 0.1, 20, DT)
    assert set(both) == {"a", "b"} and both["a"].error.shape == (3999,)


def test_position_fixes_and_integrate():
    assert position_fixes(8, 0.1, 0.05).tolist() == [True, True, False, False] * 2
    assert integrate(np.ones(4), 1.0).tolist() == [0.0, 0.0, 1.0, 3.0]
    with pytest.raises(InputError, match="cycle_s must be positive"):
        position_fixes(4, 0.0, 0.05)
