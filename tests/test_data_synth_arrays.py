"""Correlated noise across the gyros of an array (data_synth.arrays)."""

import math

import numpy as np
import pytest

from data_synth.arrays import (
    CorrelatedGaussMarkov,
    CorrelatedRandomWalk,
    CorrelatedWhiteNoise,
    correlated_normal,
)
from data_synth.record import source_rng
from fosmodel.filter.arrays import correlation

Z = 4.5
NAMES = tuple(f"gyro_{i}" for i in range(1, 9))


def test_array_sources_refuse_an_impossible_correlation():
    # the check is fosmodel.filter.arrays.correlation's (tested there); the sources apply it
    CorrelatedWhiteNoise(NAMES, (0.1,), corr=-1 / 7)  # Koldbæk and Totu 2011, eq. 6.38
    with pytest.raises(ValueError, match="rho >= -0.142857"):
        CorrelatedWhiteNoise(NAMES, (0.1,), corr=-0.2)
    with pytest.raises(ValueError, match="symmetric"):
        CorrelatedRandomWalk(NAMES[:2], (0.1,), corr=[[1.0, 0.5], [0.4, 1.0]])


def test_correlated_draws_have_the_requested_correlation():
    n = 100_000
    target = correlation(4, 0.3)
    target[0, 1] = target[1, 0] = -0.2
    z = correlated_normal(n, target, source_rng(0, "c"))
    est = np.corrcoef(z.T)
    tol = Z * (1 - target**2) / math.sqrt(n)
    assert np.all(np.abs(est - target) <= tol + 1e-12)


def test_correlated_white_noise_per_gyro_density_and_correlation():
    rate, n = 102.4, 100_000
    densities = [0.07118, 0.06882, 0.06434, 0.07874, 0.06654, 0.08422, 0.06221, 0.06654]
    src = CorrelatedWhiteNoise(NAMES, densities, -0.1)
    x = src.generate(n, rate, source_rng(0, "w"))
    assert x.shape == (n, 8) and src.outputs("gyro_1") == NAMES
    sd = x.std(axis=0) / (np.array(densities) * math.sqrt(rate))
    assert np.all(np.abs(sd - 1) < Z / math.sqrt(2 * n))
    r = np.corrcoef(x.T)[np.triu_indices(8, 1)]
    assert np.all(np.abs(r + 0.1) < Z * (1 - 0.01) / math.sqrt(n))
    t = src.truth(rate, "deg/s", x)
    assert t["params"]["arw"][0] == pytest.approx(0.07118 * 60)
    assert len(t["component_std"]) == 8 and t["terms"] is None


def test_correlated_random_walk_increments():
    rate, n = 102.4, 50_000
    src = CorrelatedRandomWalk(NAMES[:3], [0.00029], 0.5)
    x = src.generate(n, rate, source_rng(0, "r"))
    inc = np.diff(x, axis=0)
    assert np.all(np.abs(inc.std(axis=0) / (0.00029 / math.sqrt(rate)) - 1) < Z / math.sqrt(2 * n))
    r = np.corrcoef(inc.T)[np.triu_indices(3, 1)]
    assert np.all(np.abs(r - 0.5) < Z * (1 - 0.25) / math.sqrt(n))
    assert src.truth(rate, "deg/s", x)["params"]["rrw"] == [0.00029] * 3


def test_array_sources_validate_channels():
    with pytest.raises(ValueError):
        CorrelatedWhiteNoise(("g1", "g1"), [0.1], 0.0)
    with pytest.raises(ValueError):
        CorrelatedWhiteNoise(("g1", "y"), [0.1], 0.0)
    with pytest.raises(ValueError):
        CorrelatedWhiteNoise(("g1", "g2"), [0.1, 0.2, 0.3], 0.0)


AXES = ("gx_dps", "gy_dps", "gz_dps")
CORR = [[1.0, 0.4, -0.2], [0.4, 1.0, 0.3], [-0.2, 0.3, 1.0]]


def _cross_tol(cov, k_sum):
    """Z standard errors of sample cross-covariances: sqrt((s_ii s_jj + s_ij^2) k_sum / n)
    per sample, ``k_sum`` the sum over lags of the product of the autocorrelations."""
    d = np.diag(cov)
    return Z * np.sqrt((np.outer(d, d) + cov**2) * k_sum)


def test_correlated_white_noise_gives_its_per_sample_covariance():
    rate, n = 100.0, 200_000
    src = CorrelatedWhiteNoise(AXES, (0.033, 0.037, 0.032), CORR)
    cov = np.array(src.covariance(rate))
    sigma = np.array([0.033, 0.037, 0.032]) * 10.0
    np.testing.assert_allclose(cov, np.array(CORR) * np.outer(sigma, sigma), rtol=1e-12)
    x = src.generate(n, rate, source_rng(3, "w"))
    assert np.all(np.abs(np.cov(x.T) - cov) < _cross_tol(cov, 1.0) / math.sqrt(n))
    assert src.truth(rate, "deg/s", x)["params"]["covariance"] == cov.tolist()
    assert CorrelatedRandomWalk(AXES, (1e-4,), 0.2).covariance(rate) is None  # not stationary


def test_correlated_gauss_markov_cross_covariance_at_lags_and_stationary_start():
    rate, n, tau = 100.0, 400_000, 0.2
    sigmas = (0.1, 0.2, 0.05)
    src = CorrelatedGaussMarkov(AXES, sigmas, tau, CORR)
    phi = math.exp(-1 / (rate * tau))
    assert src.phi(rate) == pytest.approx(phi)
    cov = src.covariance(rate)
    np.testing.assert_allclose(cov, np.array(CORR) * np.outer(sigmas, sigmas), rtol=1e-12)
    x = src.generate(n, rate, source_rng(4, "gm"))
    tol = _cross_tol(cov, (1 + phi**2) / (1 - phi**2)) / math.sqrt(n)
    for k in (0, 5, 20):  # cov(x_i[m], x_j[m-k]) = cov_ij phi^k
        est = (x[k:].T @ x[: n - k]) / (n - k)
        assert np.all(np.abs(est - cov * phi**k) < tol)
    # the first sample is drawn from the stationary law: no warm-up transient
    firsts = np.array([src.generate(2, rate, source_rng(s, "gm"))[0] for s in range(3000)])
    assert np.all(np.abs(firsts.std(axis=0) / sigmas - 1) < Z / math.sqrt(2 * 3000))
    t = src.truth(rate, "deg/s", x)
    assert t["params"]["covariance"] == cov.tolist() and t["params"]["tau_s"] == tau
    with pytest.raises(ValueError, match="tau_s"):
        CorrelatedGaussMarkov(AXES, sigmas, 0.0, CORR)
    with pytest.raises(ValueError, match="symmetric"):
        CorrelatedGaussMarkov(AXES, sigmas, tau, [[1.0, 0.2], [0.2, 1.0]])
