"""Statistical checks of the stochastic sources (data_synth.sources).

Tolerances are derived from the record length: Allan deviations from the
number of averaging clusters, AR coefficients from their asymptotic standard
errors ``sqrt(diag(sigma_e^2 Gamma_p^-1)/N)``, variances from the variance of
the estimator.  ``Z`` standard errors are allowed everywhere.
"""

import math

import allantools
import numpy as np
import pytest
from scipy.linalg import solve_discrete_lyapunov
from scipy.special import hyp2f1
from statsmodels.regression.linear_model import burg, yule_walker

from data_synth.record import source_rng
from data_synth.sources import (
    ARProcess,
    BiasInstability,
    GaussMarkov,
    NonlinearAR,
    RandomWalk,
    TemperatureWhiteNoise,
    WhiteNoise,
    ar_variance,
)
from data_synth.units import adev_flicker_floor, arw_to_density

Z = 4.5


def rng(seed=0, key="test"):
    return source_rng(seed, key)


def oadev(x, rate, taus):
    tau, ad, _, _ = allantools.oadev(x, rate=rate, data_type="freq", taus=np.asarray(taus, float))
    assert np.allclose(tau, taus)
    return ad


def adev_rel_sd(duration, tau):
    """Relative standard deviation of an Allan deviation from duration/tau clusters."""
    return 1.0 / math.sqrt(2.0 * (duration / tau - 1.0))


def ar_stationary_cov(coefs, innovation_std):
    """Covariance of the lag state (x[n-1], ..., x[n-p]) from the Lyapunov equation."""
    p = len(coefs)
    companion = np.zeros((p, p))
    companion[0, :] = coefs
    companion[1:, :-1] = np.eye(p - 1)
    q = np.zeros((p, p))
    q[0, 0] = innovation_std**2
    return solve_discrete_lyapunov(companion, q)


def ar_standard_errors(coefs, n):
    gamma = ar_stationary_cov(tuple(coefs), 1.0)
    return np.sqrt(np.diag(np.linalg.inv(gamma)) / n)


# --- white noise / ARW ------------------------------------------------------------------


def test_white_noise_recovers_arw_within_5_percent():
    rate, duration, arw = 100.0, 3600.0, 2.89  # deg/sqrt(h)
    density = arw_to_density(arw, "deg/s")
    x = WhiteNoise(density).generate(int(rate * duration), rate, rng())
    taus = [0.1, 0.3, 1.0, 3.0, 10.0]
    ad = oadev(x, rate, taus)
    # sigma(1 s) = N [deg/s/sqrt(Hz)]; N*60 = ARW in deg/sqrt(h)
    arw_hat = ad[2] * 60.0
    tol = min(0.05, Z * adev_rel_sd(duration, 1.0))
    assert abs(arw_hat / arw - 1) < tol
    slope = np.polyfit(np.log(taus), np.log(ad), 1)[0]
    assert abs(slope + 0.5) < Z * adev_rel_sd(duration, 10.0) * math.sqrt(2) / math.log(100)


def test_white_noise_sigma_per_sample_and_truth():
    src = WhiteNoise(arw_to_density(2.0, "deg/h"))
    x = src.generate(200_000, 200.0, rng())
    sigma = 2.0 * 60 * math.sqrt(200)
    assert abs(x.std() / sigma - 1) < Z / math.sqrt(2 * len(x))
    t = src.truth(200.0, "deg/h", x)
    assert t["params"]["arw"] == pytest.approx(2.0)
    assert t["params"]["units"]["arw"] == "deg/sqrt(h)"
    assert t["terms"] == [] and t["innovation_std"] == pytest.approx(sigma)
    assert WhiteNoise(0.01).truth(100.0, "m/s^2", x)["params"]["vrw"] == pytest.approx(0.6)


# --- rate random walk -------------------------------------------------------------------


def test_random_walk_allan_slope_plus_half_and_coefficient():
    rate, duration, k = 10.0, 4 * 3600.0, 0.00029  # deg/sqrt(s^3), Koldbæk and Totu (2011)
    x = RandomWalk(k).generate(int(rate * duration), rate, rng())
    taus = [3.0, 10.0, 30.0, 100.0]
    ad = oadev(x, rate, taus)
    # RRW Allan deviation K*sqrt(tau/3): equals K at tau = 3 s; rel. sd ~ sqrt(tau/T)
    assert abs(ad[0] / k - 1) < Z * math.sqrt(3.0 / duration)
    slope = np.polyfit(np.log(taus), np.log(ad), 1)[0]
    assert abs(slope - 0.5) < Z * math.sqrt(100.0 / duration) * math.sqrt(2) / math.log(100 / 3)


def test_random_walk_truth_terms():
    t = RandomWalk(0.00029).truth(102.4, "deg/h", np.zeros(3))
    assert t["terms"] == [{"term": "y[n-1]", "coef": 1.0}]
    assert t["params"]["rrw"] == pytest.approx(0.00029 / 3600)
    assert t["innovation_std"] == pytest.approx(0.00029 / math.sqrt(102.4))


# --- AR(p) and Gauss-Markov -------------------------------------------------------------


@pytest.mark.parametrize(
    "coefs",
    [
        (1.2130613194252668, -0.36787944117144233),  # 2nd-order GM, 0.02 s stages at 100 Hz
        # AR(4) with roots 0.9, 0.5, 0.7 exp(+-1j): well conditioned (Yule-Walker is biased by
        # far more than its standard error when roots crowd near 1, as Tamazin et al. (2013) warn)
        tuple(-np.real(np.poly([0.9, 0.5, 0.7 * np.exp(1j), 0.7 * np.exp(-1j)]))[1:]),
    ],
)
def test_ar_coefficients_return_through_yule_walker_and_burg(coefs):
    n = 200_000
    x = ARProcess(coefs, 0.3).generate(n, 100.0, rng())
    se = ar_standard_errors(coefs, n)
    rho, sigma = yule_walker(x, order=len(coefs), method="mle", result_object=False)
    ar_burg, sigma2_burg = burg(x, order=len(coefs))
    assert np.all(np.abs(rho - coefs) < Z * se)
    assert np.all(np.abs(ar_burg - coefs) < Z * se)
    assert abs(sigma / 0.3 - 1) < Z / math.sqrt(2 * n)
    assert abs(math.sqrt(sigma2_burg) / 0.3 - 1) < Z / math.sqrt(2 * n)


def test_ar_starts_in_its_stationary_law():
    coefs = (1.2130613194252668, -0.36787944117144233)
    src = ARProcess(coefs, 1.0)
    first = np.array([src.generate(2, 100.0, rng(s)) for s in range(3000)])
    cov = ar_stationary_cov(coefs, 1.0)
    m = len(first)
    assert abs(first[:, 0].var() / cov[0, 0] - 1) < Z * math.sqrt(2 / m)
    r1 = cov[0, 1] / cov[0, 0]
    assert abs(np.corrcoef(first[:, 0], first[:, 1])[0, 1] - r1) < Z * (1 - r1**2) / math.sqrt(m)


def test_ar_variance_matches_lyapunov_and_gauss_markov_closed_form():
    coefs = (2.1564, -1.999, 1.0264, -0.2205)
    assert ar_variance(coefs, 0.3) == pytest.approx(ar_stationary_cov(coefs, 0.3)[0, 0], rel=1e-9)
    assert ar_variance((0.9,), 2.0) == pytest.approx(4.0 / 0.19)
    # m identical stages of pole phi: variance 2F1(m, m; 1; phi^2) per unit innovation, even
    # where the lag-state covariance is numerically singular (4 stages of 10 s at 200 Hz)
    for order, tau in ((2, 1.0), (4, 10.0)):
        src = GaussMarkov(1.0, tau, order=order)
        phi = src.phi(200.0)
        expected = 1.0 / math.sqrt(hyp2f1(order, order, 1, phi * phi))
        assert src.innovation_std(200.0) == pytest.approx(expected, rel=1e-9)
        x = src.generate(1000, 200.0, rng())
        assert np.all(np.isfinite(x)) and len(x) == 1000


def test_ar_rejects_nonstationary_coefficients():
    with pytest.raises(ValueError, match="not stationary"):
        ARProcess((1.0,), 1.0)
    with pytest.raises(ValueError):
        ARProcess((), 1.0)


def test_first_order_gauss_markov_returns_correlation_time_and_sigma():
    rate, tau, sigma, n = 100.0, 0.5, 2.0, 200_000
    src = GaussMarkov(sigma, tau)
    x = src.generate(n, rate, rng())
    (phi_hat,), _ = yule_walker(x, order=1, method="mle", result_object=False)
    phi = src.phi(rate)
    se_phi = math.sqrt((1 - phi**2) / n)
    tau_hat = -1 / (rate * math.log(phi_hat))
    se_tau = se_phi / (rate * phi * math.log(phi) ** 2)
    assert abs(tau_hat - tau) < Z * se_tau
    # variance of the sample variance of an AR(1): 2 sigma^4 (1+phi^2)/((1-phi^2) N)
    se_var = sigma**2 * math.sqrt(2 * (1 + phi**2) / ((1 - phi**2) * n))
    assert abs(x.var() - sigma**2) < Z * se_var


def test_second_order_gauss_markov_is_ar2_with_repeated_pole():
    rate, n = 200.0, 200_000
    src = GaussMarkov(0.5, 0.05, order=2)
    phi = math.exp(-1 / (rate * 0.05))
    assert src.coefs(rate) == pytest.approx((2 * phi, -phi * phi))
    x = src.generate(n, rate, rng())
    rho, sigma = yule_walker(x, order=2, method="mle", result_object=False)
    assert np.all(np.abs(rho - src.coefs(rate)) < Z * ar_standard_errors(src.coefs(rate), n))
    assert abs(sigma / src.innovation_std(rate) - 1) < Z / math.sqrt(2 * n)
    t = src.truth(rate, "deg/s", x)
    assert [d["term"] for d in t["terms"]] == ["y[n-1]", "y[n-2]"]
    assert t["params"]["ar_coefs"] == pytest.approx(list(src.coefs(rate)))
    assert "component alone" in t["params"]["convention"]


# --- bias instability -------------------------------------------------------------------


def test_bias_instability_has_flat_allan_floor_0664_b():
    rate, duration, b = 10.0, 20 * 3600.0, 0.01
    x = BiasInstability(b, 0.1, 10_000.0).generate(int(rate * duration), rate, rng())
    taus = [3.0, 10.0, 30.0]
    ad = oadev(x, rate, taus)
    # design ripple of the GM sum (< 4 %) plus the estimation noise at the longest tau
    tol = 0.04 + Z * adev_rel_sd(duration, taus[-1])
    assert np.all(np.abs(ad / adev_flicker_floor(b) - 1) < tol)


def test_bias_instability_components():
    src = BiasInstability(1.0, 0.1, 1000.0, per_decade=3)
    taus = src.taus()
    assert len(taus) == 13 and taus[0] == pytest.approx(0.1) and taus[-1] == pytest.approx(1000.0)
    assert src.component_sigma() == pytest.approx(math.sqrt(math.log(10 ** (1 / 3)) / math.pi))
    with pytest.raises(ValueError):
        BiasInstability(1.0, 10.0, 1.0)


# --- nonlinear AR -----------------------------------------------------------------------


def test_nonlinear_ar_coefficients_return_by_least_squares():
    src = NonlinearAR((0.5, -0.2), ((2, 1, 0.2),), 0.35)
    assert src.cross == ((1, 2, 0.2),)
    x = src.generate(60_000, 200.0, rng())
    y, y1, y2 = x[2:], x[1:-1], x[:-2]
    design = np.column_stack([y1, y2, y1 * y2])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    resid = y - design @ coef
    se = np.sqrt(np.diag(np.linalg.inv(design.T @ design)) * resid.var())
    assert np.all(np.abs(coef - [0.5, -0.2, 0.2]) < Z * se)
    assert abs(resid.std() / 0.35 - 1) < Z / math.sqrt(2 * len(y))
    t = src.truth(200.0, "deg/s", x)
    assert {d["term"]: d["coef"] for d in t["terms"]} == {
        "y[n-1]": 0.5,
        "y[n-2]": -0.2,
        "y[n-1]*y[n-2]": 0.2,
    }


def test_nonlinear_ar_stays_bounded_over_an_hour_at_200_hz():
    src = NonlinearAR((0.5, -0.2), ((1, 2, 0.2),), 0.35)
    for seed in range(3):
        x = src.generate(720_000, 200.0, rng(seed))
        assert np.all(np.isfinite(x)) and np.abs(x).max() < src.escape_radius()
        assert abs(x.std() / src.linear_std() - 1) < 0.1  # the cross term only perturbs


def test_nonlinear_ar_rejects_unbounded_parameters():
    with pytest.raises(ValueError, match="escape radius"):
        NonlinearAR((0.5, -0.2), ((1, 2, 2.0),), 0.35)
    with pytest.raises(ValueError):
        NonlinearAR((0.5,), ((0, 1, 0.1),), 0.35)


# --- temperature-dependent white noise --------------------------------------------------


def test_temperature_white_noise_density_follows_temperature():
    rate, n = 100.0, 100_000
    temp = np.r_[np.full(n // 2, -30.0), np.full(n // 2, 15.0)]
    src = TemperatureWhiteNoise((-30.0, 0.0, 30.0), (0.03, 0.02, 0.04))
    x = src.generate(n, rate, rng(), {"temp_c": temp})
    for half, density in ((x[: n // 2], 0.03), (x[n // 2 :], 0.03)):
        assert abs(half.std() / (density * math.sqrt(rate)) - 1) < Z / math.sqrt(len(half))
    assert src.requires == ("temp_c",)
    with pytest.raises(ValueError, match="needs the column"):
        src.generate(n, rate, rng())
    assert src.truth(rate, "deg/s", x)["terms"] is None
