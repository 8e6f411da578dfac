"""The results of a fit: standard errors, their file form and the summary that shows them."""

import json

import numpy as np
from scipy.signal import lfilter

from fosmodel import FOSModel


def test_standard_errors_equal_statsmodels_autoreg():
    """An AR(2) by FOS has the terms of AutoReg(2): the same OLS, the same standard errors."""
    from statsmodels.tsa.ar_model import AutoReg

    y = lfilter([1.0], [1.0, -1.5, 0.7], np.random.default_rng(4).standard_normal(3000)) + 2.0
    model = FOSModel(max_lag=2, stop="max_terms", max_terms=2).fit(y)
    assert model.terms_ == ["y[n-1]", "y[n-2]"]
    ref = AutoReg(y, lags=2, trend="c").fit()
    # AutoReg's sigma2 is RSS / nobs; FOS's standard errors take RSS / (N - k), as OLS does
    n, k = ref.nobs, 3
    bse = np.asarray(ref.bse) * np.sqrt(n / (n - k))
    np.testing.assert_allclose(model.coef_se_, bse[1:], rtol=1e-8)
    np.testing.assert_allclose(model.coef_, np.asarray(ref.params)[1:], rtol=1e-8)


def test_standard_errors_are_kept_by_files_and_absent_from_version_1():
    y = lfilter([1.0], [1.0, -0.9], np.random.default_rng(5).standard_normal(2000))
    model = FOSModel(max_lag=3).fit(y)
    data = model.to_dict()
    again = FOSModel.from_dict(json.loads(json.dumps(data)))
    np.testing.assert_array_equal(again.coef_se_, model.coef_se_)
    assert again.intercept_se_ == model.intercept_se_
    old = {**data, "format_version": 1,
           "fitted": {k: v for k, v in data["fitted"].items()
                      if k not in ("coef_se", "intercept_se")}}
    loaded = FOSModel.from_dict(old)
    assert np.isnan(loaded.coef_se_).all() and len(loaded.coef_se_) == len(model.terms_)
    np.testing.assert_array_equal(loaded.predict(y), model.predict(y))


def test_summary_shows_standard_errors_and_says_they_ignore_the_selection():
    y = lfilter([1.0], [1.0, -0.9], np.random.default_rng(6).standard_normal(2000))
    summary = FOSModel(max_lag=3).fit(y).summary()
    assert "std err" in summary.table.columns
    assert any("ignores the search over the candidates" in note for note in summary.notes)
