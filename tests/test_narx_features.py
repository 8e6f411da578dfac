"""NARX candidates as a scikit-learn transformer: rows of lags, candidate columns, tuning."""

import numpy as np
import pandas as pd
import pytest
from sklearn.model_selection import GridSearchCV, TimeSeriesSplit
from sklearn.pipeline import Pipeline
from sklearn.utils._param_validation import InvalidParameterError
from sklearn.utils.estimator_checks import (
    check_dataframe_column_names_consistency,
    check_get_feature_names_out_error,
    check_param_validation,
    check_transformer_get_feature_names_out,
    check_transformer_get_feature_names_out_pandas,
    parametrize_with_checks,
)

from fosmodel import FOSModel, FOSRegressor, InputError
from fosmodel.core.candidates import Term, evaluate_terms, generate_terms
from fosmodel.models.narx_features import NARXFeatures, lagged_rows


def _narx(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """y[n] = 0.5 y[n-1] - 0.3 y[n-2] + 0.2 y[n-1] x[n-1] + 0.8 x[n-1] + e[n], x uniform."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, n)
    e = 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] - 0.3 * y[k - 2] + 0.2 * y[k - 1] * x[k - 1] + 0.8 * x[k - 1] + e[k]
    return y, x


# scikit-learn's suite, none marked as failing (its array-API check skips itself unless
# SCIPY_ARRAY_API is set); its arrays have no column names, which NARXFeatures reads as the
# output lags y[n-1], y[n-2], ...
@parametrize_with_checks([NARXFeatures(), NARXFeatures(degree=2, center=False)])
def test_sklearn_compatible(estimator, check):
    check(estimator)


# Checks scikit-learn runs on its own estimators only: the parameter constraints and the
# feature names out, from an array.
@pytest.mark.parametrize("check", [check_param_validation, check_get_feature_names_out_error,
                                   check_transformer_get_feature_names_out])
def test_sklearn_checks_of_parameters_and_names(check):
    check("NARXFeatures", NARXFeatures(degree=2))


# The two checks of DataFrame column names fit on columns named 'col_0', 'col_1', ...: a
# NARXFeatures reads the lag of each column from its name and refuses names that give none.
@pytest.mark.parametrize("check", [check_dataframe_column_names_consistency,
                                   check_transformer_get_feature_names_out_pandas])
def test_sklearn_column_name_checks_are_refused_for_their_names(check):
    with pytest.raises(InputError, match=r"column 'col_?0' of X is not a lagged value"):
        check("NARXFeatures", NARXFeatures())


def test_rows_hold_the_lags_and_the_target_aligned_with_them():
    y, x = np.arange(10.0), 100 + np.arange(10.0)
    rows, target = lagged_rows(pd.Series(y, index=np.arange(10) * 0.01, name="gyro"), {"x": x},
                               max_lag=2, exog_lags={"x": 3})
    assert list(rows.columns) == ["y[n-1]", "y[n-2]", "x[n-0]", "x[n-1]", "x[n-2]", "x[n-3]"]
    assert rows.iloc[0].tolist() == [2.0, 1.0, 103.0, 102.0, 101.0, 100.0]  # the row of n = 3
    assert target.tolist() == y[3:].tolist() and target.name == "gyro"
    assert rows.index.equals(target.index) and rows.index[0] == pytest.approx(0.03)


def test_feature_names_are_the_candidates_as_fosmodel_writes_them():
    y, x = _narx(300, 0)
    rows, _ = lagged_rows(y, {"x": x}, max_lag=3, exog_lags={"x": 1})
    features = NARXFeatures(max_lag=2, degree=2, exog_lags={"x": 1}).fit(rows)
    names = features.get_feature_names_out().tolist()
    assert names == [
        "y[n-1]", "y[n-2]", "x[n-0]", "x[n-1]",
        "y[n-1]^2", "y[n-1]*y[n-2]", "y[n-1]*x[n-0]", "y[n-1]*x[n-1]", "y[n-2]^2",
        "y[n-2]*x[n-0]", "y[n-2]*x[n-1]", "x[n-0]^2", "x[n-0]*x[n-1]", "x[n-1]^2"]
    assert [Term.parse(name).name for name in names] == names
    frame = features.set_output(transform="pandas").transform(rows)
    assert frame.columns.tolist() == names and frame.index.equals(rows.index)
    assert list(NARXFeatures(degree=2).fit(rows[["y[n-1]", "x[n-0]"]]).get_feature_names_out()) \
        == ["y[n-1]", "x[n-0]", "y[n-1]^2", "y[n-1]*x[n-0]", "x[n-0]^2"]


@pytest.mark.parametrize("center", [False, True])
def test_columns_equal_a_product_written_out_by_hand(center):
    y, x = _narx(200, 1)
    rows, _ = lagged_rows(y, {"x": x}, max_lag=2, exog_lags={"x": 1})
    out = NARXFeatures(degree=2, center=center).fit_transform(rows)
    # the mean of each channel over the rows: of y[n-1] (samples 1..N-2) and x[n-0] (2..N-1)
    my, mx = (y[1:-1].mean(), x[2:].mean()) if center else (0.0, 0.0)
    by_hand = []
    for n in range(2, len(y)):
        a, b, c, d = y[n - 1] - my, y[n - 2] - my, x[n] - mx, x[n - 1] - mx
        by_hand.append([a, b, c, d, a * a, a * b, a * c, a * d, b * b, b * c, b * d,
                        c * c, c * d, d * d])
    np.testing.assert_allclose(out, by_hand, rtol=0, atol=1e-14)


def test_columns_equal_those_fosmodel_forms():
    y, x = _narx(400, 2)
    spec = FOSModel(max_lag=3, degree=3, exog_lags={"x": 2}).candidate_spec()
    rows, _ = lagged_rows(y, {"x": x}, max_lag=3, exog_lags={"x": 2})
    out = NARXFeatures(degree=3, center=False).fit_transform(rows)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    np.testing.assert_array_equal(out, evaluate_terms(terms, {"y": y, "x": x}, spec.lag_window))


def test_a_pipeline_selects_what_fosmodel_selects():
    y, x = _narx(3000, 3)
    model = FOSModel(max_lag=2, degree=2, exog_lags={"x": 2}, center=False, stop="max_terms",
                     max_terms=5).fit(y, {"x": x})
    rows, target = lagged_rows(y, {"x": x}, max_lag=2, exog_lags={"x": 2})
    pipe = Pipeline([("narx", NARXFeatures(degree=2, center=False)),
                     ("fos", FOSRegressor(max_terms=5, stop="max_terms"))]).fit(rows, target)
    fos = pipe["fos"]
    assert pipe["narx"].get_feature_names_out()[fos.support_].tolist() == model.terms_
    np.testing.assert_allclose(fos.coef_[fos.support_], model.coef_, rtol=1e-9)
    np.testing.assert_allclose(pipe.predict(rows), model.predict(y, {"x": x})[2:], rtol=1e-9)


@pytest.mark.slow
def test_grid_search_over_time_series_splits_finds_the_true_lags_and_degree():
    y, x = _narx(2000, 0)
    rows, target = lagged_rows(y, {"x": x}, max_lag=4, exog_lags={"x": 2})
    pipe = Pipeline([("narx", NARXFeatures()), ("fos", FOSRegressor(stop="max_terms"))])
    grid = {"narx__max_lag": [1, 2, 3, 4], "narx__degree": [1, 2], "fos__max_terms": [3, 4, 5, 6]}
    search = GridSearchCV(pipe, grid, cv=TimeSeriesSplit(5)).fit(rows, target)
    assert search.best_params_["narx__max_lag"] == 2 and search.best_params_["narx__degree"] == 2
    scores = pd.DataFrame(search.cv_results_["params"]).assign(
        score=search.cv_results_["mean_test_score"])
    short = scores[(scores["narx__max_lag"] < 2) | (scores["narx__degree"] < 2)]
    assert short["score"].max() < search.best_score_ - 0.01  # too few lags or no product
    best = search.best_estimator_
    weights = dict(zip(best["narx"].get_feature_names_out(), best["fos"].coef_))
    truth = {"y[n-1]": 0.5, "y[n-2]": -0.3, "y[n-1]*x[n-1]": 0.2, "x[n-1]": 0.8}
    assert {name for name, w in weights.items() if abs(w) > 0.05} == set(truth)
    for name, value in truth.items():
        assert weights[name] == pytest.approx(value, abs=0.02), name


def test_test_rows_are_centred_by_the_means_of_the_fitted_rows():
    y, x = _narx(600, 4)
    rows, _ = lagged_rows(y + 5.0, {"x": x}, max_lag=2, exog_lags={"x": 0})
    features = NARXFeatures().fit(rows.iloc[:300])
    assert features.offsets_ == pytest.approx({"y": rows["y[n-1]"].iloc[:300].mean(),
                                               "x": rows["x[n-0]"].iloc[:300].mean()})
    later = features.transform(rows.iloc[300:])
    np.testing.assert_allclose(later[:, 0], rows["y[n-1]"].iloc[300:] - features.offsets_["y"])


@pytest.mark.parametrize(("columns", "params", "message"), [
    (["y[n-1]", "col_0"], {}, "column 'col_0' of X is not a lagged value such as 'y[n-1]' or "
                              "'x[n-0]'"),
    (["y[n-1]", "y[n-1]*x[n-0]"], {}, "column 'y[n-1]*x[n-0]' of X is not a lagged value such "
                                      "as 'y[n-1]' or 'x[n-0]'"),
    (["y[n-0]", "y[n-1]"], {}, "column 'y[n-0]' of X is the output at n, the value predicted; "
                               "give its lags from 1 on"),
    (["y[n-1]", "x[n-0]"], {"max_lag": 2}, "X has no column 'y[n-2]', which the candidates read "
                                           "(max_lag=2, exog_lags={'x': 0})"),
    (["y[n-1]", "x[n-1]"], {}, "X has no column 'x[n-0]', which the candidates read "
                               "(max_lag=1, exog_lags={'x': 1})"),
    (["x[n-0]"], {"exog_lags": {}}, "no candidates: max_lag is 0 and no input lags are offered"),
])
def test_bad_columns_are_named(columns, params, message):
    rows = pd.DataFrame(np.random.default_rng(0).normal(size=(20, len(columns))), columns=columns)
    with pytest.raises(InputError) as info:
        NARXFeatures(**params).fit(rows)
    assert str(info.value) == message


def test_bad_parameters_and_records_are_refused():
    rows = np.random.default_rng(0).normal(size=(20, 2))
    with pytest.raises(InvalidParameterError, match="The 'degree' parameter of NARXFeatures "
                                                    r"must be an int in the range \[1, inf\)"):
        NARXFeatures(degree=0).fit(rows)
    with pytest.raises(InputError) as info:
        lagged_rows(np.arange(3.0), max_lag=3)
    assert str(info.value) == ("record too short: 3 samples, no longer than the lag window of 3 "
                               "samples (the largest lag)")
    with pytest.raises(InputError) as info:
        lagged_rows(np.arange(9.0), {"x": np.arange(8.0)}, max_lag=1, exog_lags={"x": 1})
    assert str(info.value) == "channel 'x' has 8 samples, the output has 9"
