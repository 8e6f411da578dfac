import json
import math
import warnings

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter
from statsmodels.regression.linear_model import burg, yule_walker
from statsmodels.tsa.ar_model import AutoReg
from statsmodels.tsa.arima_process import ArmaProcess

from fosmodel import InputError, UnstableModelWarning
from fosmodel.models.baselines import (
    METHOD_LABELS,
    ARModel,
    GaussMarkovModel,
    _to_dynamics,
    make_baseline,
)
from fosmodel.typeset.summary import Summary

METHODS = ["yule_walker", "covariance", "burg"]
PHI2 = np.array([1.5, -0.7])                                    # roots of modulus 0.84
PHI4 = -np.real(np.poly([0.9 * np.exp(0.3j), 0.9 * np.exp(-0.3j),
                         0.6 * np.exp(1.9j), 0.6 * np.exp(-1.9j)]))[1:]
SIGMA = 0.5                                                    # innovation std
MU = 3.0                                                       # a sensor bias


def _ar_record(phi, n, seed, sigma=SIGMA, mu=MU):
    """AR(p) record from white Gaussian noise, the start-up transient discarded."""
    burn = 2000
    e = sigma * np.random.default_rng(seed).standard_normal(n + burn)
    return mu + lfilter([1.0], np.r_[1.0, -np.asarray(phi)], e)[burn:]


def _phi_se(phi, n):
    """Asymptotic standard errors of the AR weights: sqrt(diag(Gamma_p^-1) sigma2 / N).

    Gamma_p is the p x p autocovariance matrix of the process; with unit innovation
    variance sigma2 cancels, so se_k = sqrt([Gamma_p(sigma2=1)^-1]_kk / N).
    """
    p = len(phi)
    acov = ArmaProcess(ar=np.r_[1.0, -np.asarray(phi)]).acovf(p)
    gamma = acov[np.abs(np.subtract.outer(np.arange(p), np.arange(p)))]
    return np.sqrt(np.diag(np.linalg.inv(gamma)) / n)


def _sigma2_tol(sigma2, n):
    """4 standard errors of a Gaussian variance estimate: var(s^2) = 2 sigma^4 / N."""
    return 4 * sigma2 * math.sqrt(2 / n)


# -- statsmodels conventions -------------------------------------------------------------


def test_normalisation_squares_yule_walker_std_and_keeps_variances():
    phi, s2 = _to_dynamics("yule_walker", [0.5, -0.2], 3.0)
    assert phi.tolist() == [0.5, -0.2] and s2 == 9.0
    for method in ("covariance", "burg"):
        phi, s2 = _to_dynamics(method, np.array([0.5, -0.2]), 3.0)
        assert phi.tolist() == [0.5, -0.2] and s2 == 3.0


@pytest.mark.filterwarnings("ignore::FutureWarning")  # statsmodels 0.15 tuple-vs-result notice
def test_normalisation_matches_statsmodels_outputs_on_data():
    y = _ar_record(PHI2, 5000, seed=3)
    x = y - y.mean()
    rho, sigma = yule_walker(x, order=2, method="mle", demean=False)[:2]
    fit = ARModel(2, "yule_walker").fit(y)
    np.testing.assert_allclose(fit.coef_, rho, rtol=1e-12)
    assert fit.sigma2_ == pytest.approx(sigma**2, rel=1e-12)
    ar, sigma2 = burg(x, order=2, demean=False)
    fit = ARModel(2, "burg").fit(y)
    np.testing.assert_allclose(fit.coef_, ar, rtol=1e-12)
    assert fit.sigma2_ == pytest.approx(sigma2, rel=1e-12)
    ols = AutoReg(x, lags=2, trend="n").fit()
    fit = ARModel(2, "covariance").fit(y)
    np.testing.assert_allclose(fit.coef_, ols.params, rtol=1e-12)
    assert fit.sigma2_ == pytest.approx(np.mean(ols.resid**2), rel=1e-12)


def test_normalisation_rejects_non_finite_estimates():
    with pytest.raises(InputError, match="non-finite"):
        _to_dynamics("yule_walker", [0.5], float("nan"))


# -- recovery of known models ------------------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("phi", [PHI2, PHI4], ids=["AR2", "AR4"])
def test_recovers_known_ar_weights_and_innovation_variance(method, phi):
    n = 50_000
    y = _ar_record(phi, n, seed=len(phi))
    model = ARModel(len(phi), method).fit(y)
    assert np.all(np.abs(model.coef_ - phi) <= 4 * _phi_se(phi, n)), (model.coef_, phi)
    assert abs(model.sigma2_ - SIGMA**2) <= _sigma2_tol(SIGMA**2, n)
    assert model.mean_ == pytest.approx(y.mean())
    assert model.method_ == method
    assert model.lag_window_ == model.n_terms_ == len(phi)


def test_methods_agree_on_a_long_record():
    # The three estimators differ only by end effects of order p/N, far below one
    # sampling standard error sqrt(diag(Gamma^-1)/N) of the weights.
    n = 200_000
    y = _ar_record(PHI4, n, seed=11)
    coefs = {m: ARModel(4, m).fit(y).coef_ for m in METHODS}
    se = _phi_se(PHI4, n)
    for method in ("yule_walker", "covariance"):
        assert np.all(np.abs(coefs[method] - coefs["burg"]) <= se), (method, coefs)


@pytest.mark.parametrize("method", METHODS)
def test_positive_correlation_gives_positive_phi(method):
    n = 20_000
    y = _ar_record([0.6], n, seed=5)
    phi = ARModel(1, method).fit(y).coef_[0]
    assert phi > 0
    assert abs(phi - 0.6) <= 4 * math.sqrt((1 - 0.6**2) / n)


# -- prediction and simulation -----------------------------------------------------------


def _explicit_prediction(phi, mu, y):
    out = np.full(len(y), np.nan)
    for n in range(len(phi), len(y)):
        out[n] = mu + sum(phi[k] * (y[n - k - 1] - mu) for k in range(len(phi)))
    return out


@pytest.mark.parametrize("method", METHODS)
def test_predict_is_the_one_step_recursion(method):
    y = _ar_record(PHI4, 3000, seed=7)
    model = ARModel(4, method).fit(y)
    pred = model.predict(y[:500])
    assert np.isnan(pred[:4]).all() and np.isfinite(pred[4:]).all()
    np.testing.assert_allclose(pred, _explicit_prediction(model.coef_, model.mean_, y[:500]),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(model.residuals(y[:500]), y[:500] - pred)


def test_predict_never_uses_later_samples():
    y = _ar_record(PHI2, 2000, seed=8)
    model = ARModel(2).fit(y)
    changed = y.copy()
    changed[301:] += 100.0
    np.testing.assert_array_equal(model.predict(y)[:302], model.predict(changed)[:302])


def test_predict_keeps_a_series_index():
    y = pd.Series(_ar_record(PHI2, 1000, seed=9), index=np.arange(1000) * 0.01)
    model = ARModel(2).fit(y)
    pred = model.predict(y)
    assert isinstance(pred, pd.Series) and pred.index.equals(y.index)
    assert isinstance(model.residuals(y), pd.Series)


@pytest.mark.parametrize("model", [ARModel(2, m) for m in METHODS] + [GaussMarkovModel()])
def test_read_only_input(model):
    y = _ar_record(PHI2, 2000, seed=14)
    frozen = y.copy()
    frozen.flags.writeable = False
    expected = model.fit(y).predict(y)
    np.testing.assert_array_equal(model.fit(frozen).predict(frozen), expected)
    np.testing.assert_array_equal(model.simulate(frozen[:5], 5), model.simulate(y[:5], 5))


def test_simulate_with_noise_is_the_driven_recursion():
    y = _ar_record(PHI2, 5000, seed=10)
    model = ARModel(2, "covariance").fit(y)
    noise = np.random.default_rng(1).standard_normal(200)
    out = model.simulate(y[:50], 200, noise=noise)
    x = list(y[48:50] - model.mean_)
    for e in noise:
        x.append(model.coef_[0] * x[-1] + model.coef_[1] * x[-2] + e)
    np.testing.assert_allclose(out, np.array(x[2:]) + model.mean_, rtol=1e-10, atol=1e-10)


def test_simulate_without_noise_decays_to_the_mean():
    y = _ar_record(PHI2, 5000, seed=12)
    model = ARModel(2, "burg").fit(y)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = model.simulate(y[:10] + 5.0, 400)
    assert out.shape == (400,)
    # the roots have modulus ~0.84, so after 400 steps the start-up offset is ~1e-30 of itself
    assert abs(out[-1] - model.mean_) < 1e-20
    assert abs(out[0] - model.mean_) > 1e-3


def test_unstable_covariance_fit_warns_on_simulate():
    y = _ar_record([1.01], 2000, seed=13, mu=0.0)  # explosive record
    cov = ARModel(1, "covariance").fit(y)
    assert not cov.is_stable() and np.abs(cov.ar_roots()).max() > 1
    with pytest.warns(UnstableModelWarning, match="unstable"):
        cov.simulate(y[-5:], 10)
    assert "unstable" in "\n".join(cov.summary().notes)
    burg_fit = ARModel(1, "burg").fit(y)  # Burg is stable by construction
    assert burg_fit.is_stable()


def test_diverging_free_run_is_nan_after_overflow():
    data = ARModel(1).fit(_ar_record([0.5], 100, seed=1)).to_dict()
    data["fitted"]["coef"] = [2.0]
    model = ARModel.from_dict(data)
    with pytest.warns(UnstableModelWarning) as record:
        out = model.simulate([1.0], 2000)
    messages = [str(w.message) for w in record]
    assert any("unstable" in m for m in messages) and any("diverged" in m for m in messages)
    first_bad = np.flatnonzero(~np.isfinite(out))[0]
    assert 1000 < first_bad < 1100  # 2**1024 overflows a float64
    assert np.isnan(out[first_bad:]).all()


def test_simulate_argument_errors():
    model = ARModel(3).fit(_ar_record(PHI2, 500, seed=2))
    with pytest.raises(InputError, match="y_init has 2 samples; the model needs at least 3"):
        model.simulate([1.0, 2.0], 5)
    with pytest.raises(InputError, match="n_steps"):
        model.simulate([1.0, 2.0, 3.0], -1)
    with pytest.raises(InputError, match="noise has 4 samples, n_steps is 5"):
        model.simulate([1.0, 2.0, 3.0], 5, noise=np.zeros(4))


# -- Gauss-Markov ------------------------------------------------------------------------


def test_gauss_markov_recovers_the_correlation_time():
    rate, tau, n = 100.0, 2.0, 1_000_000
    phi = math.exp(-1 / (rate * tau))
    y = _ar_record([phi], n, seed=21)
    gm = GaussMarkovModel(rate=rate).fit(y)
    # se of phi is sqrt((1 - phi^2)/N); tau = -dt/ln(phi), so d tau = dt d phi/(phi ln(phi)^2)
    se_tau = math.sqrt((1 - phi**2) / n) / (rate * phi * math.log(phi) ** 2)
    assert abs(gm.correlation_time_s_ - tau) <= 4 * se_tau
    assert gm.beta_ == pytest.approx(1 / gm.correlation_time_s_)
    assert gm.beta_ == pytest.approx(-math.log(gm.coef_[0]) * rate)
    assert abs(gm.sigma2_ - SIGMA**2) <= _sigma2_tol(SIGMA**2, n)
    assert gm.process_var_ == pytest.approx(gm.sigma2_ / (1 - gm.coef_[0] ** 2))
    assert gm.lag_window_ == gm.n_terms_ == 1
    text = str(gm.summary())
    assert "exp(-beta dt)" in text and "Correlation time" in text


def test_gauss_markov_phi_is_the_lag_one_autocorrelation():
    y = _ar_record([0.8], 3000, seed=22)
    x = y - y.mean()
    gm = GaussMarkovModel().fit(y)
    assert gm.coef_[0] == pytest.approx(np.dot(x[1:], x[:-1]) / np.dot(x, x), rel=1e-12)
    assert gm.process_var_ == pytest.approx(np.mean(x**2), rel=1e-12)
    assert math.isnan(gm.beta_) and math.isnan(gm.correlation_time_s_)
    assert any("rate" in note for note in gm.summary().notes)


def test_gauss_markov_negative_phi_has_no_correlation_time():
    gm = GaussMarkovModel(rate=100).fit(_ar_record([-0.5], 5000, seed=23))
    assert gm.coef_[0] < 0
    assert math.isnan(gm.beta_) and math.isnan(gm.correlation_time_s_)
    assert any("undefined" in note for note in gm.summary().notes)


def test_gauss_markov_rejects_a_bad_rate():
    for rate in (0, -1.0, float("inf"), "100", True):
        with pytest.raises(InputError, match="rate must be a positive number"):
            GaussMarkovModel(rate=rate).fit(np.arange(10.0))


# -- summary and persistence -------------------------------------------------------------


def test_ar_summary_reports_method_order_weights_and_stability():
    model = ARModel(2, "yule_walker").fit(_ar_record(PHI2, 5000, seed=30))
    summary = model.summary()
    assert isinstance(summary, Summary)
    info = dict(summary.info)
    assert info["Method"] == "yule_walker" and info["Order p"] == "2"
    assert info["Stable"] == "yes"
    assert float(info["Largest |root|"]) == pytest.approx(np.abs(model.ar_roots()).max(),
                                                          rel=1e-5)
    assert float(info["Innovation var"]) == pytest.approx(model.sigma2_, rel=1e-5)
    table = summary.to_frame()
    assert table["term"].tolist() == ["y[n-1]", "y[n-2]"]
    np.testing.assert_allclose(table["coef"], model.coef_)


@pytest.mark.parametrize("model", [ARModel(4, "burg"), ARModel(3, "covariance"),
                                   GaussMarkovModel(rate=200.0)])
def test_round_trip_predicts_identically(model):
    y = _ar_record(PHI4, 4000, seed=31)
    model.fit(y)
    restored = type(model).from_dict(json.loads(json.dumps(model.to_dict(meta={"col": "gx"}))))
    np.testing.assert_array_equal(restored.predict(y), model.predict(y))
    np.testing.assert_array_equal(restored.simulate(y[:10], 20), model.simulate(y[:10], 20))
    assert restored.sigma2_ == model.sigma2_ and restored.meta_ == {"col": "gx"}
    assert str(restored.summary()) == str(model.summary())


def _corrupt(path, value):
    data = ARModel(2).fit(_ar_record(PHI2, 500, seed=32)).to_dict()
    *parents, key = path
    node = data
    for p in parents:
        node = node[p]
    if value is KeyError:
        del node[key]
    else:
        node[key] = value
    return data


@pytest.mark.parametrize("data, message", [
    ([1, 2], "not a fosmodel ARModel"),
    (_corrupt(["format"], "fosmodel.FOSModel"), "not a fosmodel ARModel"),
    (_corrupt(["format_version"], 2), "newer"),
    (_corrupt(["fitted", "coef"], [0.5]), "1 coefficient"),
    (_corrupt(["fitted", "mean"], float("nan")), "finite"),
    (_corrupt(["fitted", "sigma2"], -1.0), "negative innovation variance"),
    (_corrupt(["fitted", "sigma2"], KeyError), "corrupted"),
    (_corrupt(["params", "order"], 0), "order must be an integer"),
    (_corrupt(["params", "method"], "ols"), "unknown AR method"),
    (_corrupt(["params", "window"], 3), "corrupted"),
])
def test_bad_dicts_raise_input_error(data, message):
    with pytest.raises(InputError, match=message):
        ARModel.from_dict(data)


def test_gauss_markov_does_not_read_an_ar_file():
    data = ARModel(1).fit(_ar_record([0.5], 100, seed=1)).to_dict()
    with pytest.raises(InputError, match="not a fosmodel GaussMarkovModel"):
        GaussMarkovModel.from_dict(data)


# -- input errors and the registry -------------------------------------------------------


@pytest.mark.parametrize("order", [0, -1, 2.0, "2", True])
def test_bad_order(order):
    with pytest.raises(InputError, match="order must be an integer >= 1"):
        ARModel(order).fit(np.arange(100.0))


def test_unknown_method_is_named():
    with pytest.raises(InputError, match="unknown AR method 'burgs'.*did you mean 'burg'"):
        ARModel(2, "burgs").fit(np.arange(100.0))


def test_too_short_record_names_the_counts():
    with pytest.raises(InputError, match="9 samples, but an AR.4. fit needs at least 10"):
        ARModel(4).fit(np.random.default_rng(0).standard_normal(9))
    ARModel(4).fit(np.random.default_rng(0).standard_normal(10))


def test_non_finite_and_constant_records():
    y = np.random.default_rng(0).standard_normal(100)
    y[17] = np.nan
    with pytest.raises(InputError, match="non-finite.*sample 17"):
        ARModel(2).fit(y)
    with pytest.raises(InputError, match="constant"):
        ARModel(2).fit(np.full(100, 4.0))


def test_unfitted_model():
    with pytest.raises(InputError, match="not fitted"):
        ARModel(2).predict(np.zeros(10))


def test_make_baseline_maps_the_codes():
    assert set(METHOD_LABELS) == {"yw", "cov", "burg", "gm"}
    for code, method in (("yw", "yule_walker"), ("cov", "covariance"), ("burg", "burg")):
        model = make_baseline(code, 5, rate=100.0)
        assert isinstance(model, ARModel) and model.order == 5 and model.method == method
    gm = make_baseline("gm", 5, rate=100.0)
    assert isinstance(gm, GaussMarkovModel) and gm.rate == 100.0
    with pytest.raises(InputError, match="unknown baseline method 'ywm'.*yw, cov, burg, gm"):
        make_baseline("ywm", 2)


def test_one_step_prediction_in_blocks_is_the_sum_in_the_order_of_the_lags(monkeypatch):
    # the one-step predictions run over blocks of rows: blocks of 7 give the bits of the
    # point-by-point sum mu + phi_1 (y[n-1] - mu) + ... + phi_p (y[n-p] - mu)
    from fosmodel.models import dynamics

    y = np.random.default_rng(8).standard_normal(500)
    phi, mu = np.array([0.5, -0.2, 0.1]), 0.3
    monkeypatch.setattr(dynamics, "_ROWS", 7)
    np.testing.assert_array_equal(dynamics.ar_one_step(phi, mu, y),
                                  _explicit_prediction(phi, mu, y))
    np.testing.assert_array_equal(dynamics.ar_one_step(phi, mu, y[:3]), np.full(3, np.nan))
    np.testing.assert_array_equal(dynamics.ar_one_step(np.empty(0), mu, y), np.full(500, mu))
