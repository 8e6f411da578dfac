"""The FOS filter model: recovery of known noise, drivers kept and refused, its state space."""

from __future__ import annotations

import numpy as np
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.filter import FOSFilterModel, accelerometer_run

FS = 10.0


def white_walk(n: int, n_density: float, k_density: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    white = n_density * np.sqrt(FS) * rng.standard_normal(n)
    walk = np.cumsum(k_density / np.sqrt(FS) * rng.standard_normal(n))
    return white + walk


def test_recovers_white_density_and_random_walk():
    y = white_walk(72_000, 0.02, 5e-4, seed=1)
    res = FOSFilterModel().fit(y, FS)
    walk = [c for c in res.components if c.kind == "random walk"][0]
    assert res.white_density == pytest.approx(0.02, rel=0.05)
    assert np.sqrt(walk.variance) == pytest.approx(5e-4, rel=0.3)


def test_gauss_markov_bias_gets_a_state_near_its_time_scale():
    rng = np.random.default_rng(2)
    n, tau, sigma = 72_000, 60.0, 0.01
    a = np.exp(-1.0 / (tau * FS))
    w = sigma * np.sqrt(1 - a * a) * rng.standard_normal(n)
    from scipy.signal import lfilter
    gm = lfilter([1.0], [1.0, -a], w)
    y = gm + 0.02 * np.sqrt(FS) * rng.standard_normal(n)
    res = FOSFilterModel().fit(y, FS)
    gms = [c for c in res.components if c.kind == "gauss-markov"]
    assert gms, res.summary()
    # the bias's variance is carried by the selected time scales and the walk together
    big = max(gms, key=lambda c: c.variance)
    assert 8.0 <= big.tau_s <= 256.0
    assert np.sqrt(sum(c.variance for c in gms)) == pytest.approx(sigma, rel=0.5)


def test_state_space_is_bounded_and_starts_from_a_covariance():
    res = FOSFilterModel().fit(white_walk(36_000, 0.02, 5e-4, seed=3), FS)
    error = res.to_state_space()
    assert np.max(np.abs(np.linalg.eigvals(error.Phi))) <= 1.0
    assert np.allclose(error.H, 1.0)
    assert error.state_names[0] == "white" and error.state_names[-1] == "random walk"
    assert error.Q[0, 0] == pytest.approx(res.white_variance)
    p0 = res.initial_covariance()
    assert p0.shape == (error.n_states,) * 2
    assert np.all(np.linalg.eigvalsh(p0) >= -1e-18)
    assert "random walk" in res.summary()


def sweep_record(n: int, coef: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) / FS
    temp = 25.0 + 10.0 * np.sin(2 * np.pi * t / (t[-1] / 1.5)) + 0.02 * np.arange(n) / n
    return white_walk(n, 0.02, 2e-4, seed) + coef * (temp - 25.0), temp


def test_a_temperature_driver_is_kept_and_its_weight_recovered():
    y, temp = sweep_record(72_000, 0.01, seed=4)
    res = FOSFilterModel().fit(y, FS, exog={"temp_c": temp})
    assert [(d.channel, d.power) for d in res.drivers] == [("temp_c", 1)]
    assert res.drivers[0].coef == pytest.approx(0.01, rel=0.05)
    error = res.to_state_space()
    u = res.input_matrix({"temp_c": temp}, len(temp))
    assert u.shape == (len(temp), 1) and error.input_names == res.input_names
    assert error.state_names[-1] == "drivers" and error.B[-1, 0] == res.drivers[0].coef


def test_a_temperature_that_drives_nothing_is_refused():
    y, temp = sweep_record(72_000, 0.0, seed=5)
    assert FOSFilterModel().fit(y, FS, exog={"temp_c": temp}).drivers == ()


def test_driver_model_beats_the_same_model_without_it_in_the_filter():
    y, temp = sweep_record(72_000, 0.01, seed=6)
    half = len(y) // 2
    exog = {"temp_c": temp[:half]}
    noise = np.random.default_rng(0).standard_normal(half)
    rms = {}
    for name, model, ex in (("with", FOSFilterModel(), exog),
                            ("without", FOSFilterModel(drivers=False), None)):
        res = model.fit(y[:half], FS, exog=ex)
        error = res.to_state_space()
        u = res.input_matrix({"temp_c": temp[half:]}, half) if res.drivers else None
        rms[name] = accelerometer_run(error, res.initial_covariance(), y[half:], noise, 0.1,
                                      60, 1 / FS, u).rms
    assert rms["with"] < 0.8 * rms["without"]


def test_bad_input_says_what_is_wrong():
    with pytest.raises(InputError, match="blocks of 1 s; at least 50 are needed"):
        FOSFilterModel().fit(np.zeros(100), FS)
    with pytest.raises(InputError, match="fs must be a positive rate"):
        FOSFilterModel().fit(np.zeros(1000), 0.0)
    with pytest.raises(InputError, match="shorter than one sample"):
        FOSFilterModel(block_s=0.01).fit(np.zeros(1000), FS)
