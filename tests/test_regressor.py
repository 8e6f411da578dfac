import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import OrthogonalMatchingPursuit
from sklearn.utils.estimator_checks import parametrize_with_checks

from fosmodel import FOSRegressor, fos


@parametrize_with_checks([FOSRegressor(), FOSRegressor(stop="bic", fit_intercept=False)])
def test_sklearn_compatible(estimator, check):
    check(estimator)


def test_matches_fos_and_omp_on_the_same_matrix():
    rng = np.random.default_rng(0)
    X = rng.standard_normal((400, 40))
    y = X[:, [3, 17, 25]] @ [1.0, -2.0, 0.5] + 0.1 * rng.standard_normal(400)
    reg = FOSRegressor(max_terms=3, stop="max_terms").fit(X, y)
    res = fos(X, y, max_terms=3, stop="max_terms")
    assert reg.support_.tolist() == res.support.tolist()
    np.testing.assert_allclose(reg.coef_[res.support], res.coef)
    omp = OrthogonalMatchingPursuit(n_nonzero_coefs=3).fit(X, y)
    # both are greedy least-squares selections; with one clear winner per step they agree
    assert set(np.flatnonzero(omp.coef_)) == set(reg.support_)
    np.testing.assert_allclose(reg.coef_, omp.coef_, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(reg.predict(X), omp.predict(X), rtol=1e-8)


def test_feature_names_are_kept():
    X = pd.DataFrame({"a": np.arange(50.0), "b": np.sin(np.arange(50.0))})
    reg = FOSRegressor().fit(X, 2 * X["b"] + 1)
    assert list(reg.feature_names_in_) == ["a", "b"]
    assert reg.support_.tolist()[0] == 1 and reg.intercept_ == pytest.approx(1.0)
