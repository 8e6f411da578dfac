"""The FOS kernel against least squares, brute-force greedy selection and the paper's rules."""

import math

import numpy as np
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.core.fos import (
    DataCorrelations,
    StopRule,
    _GramCorrelations,
    center,
    criterion,
    fos,
    fos_search,
)


def _problem(seed, n=400, c=30, k=5, noise=0.1, correlated=True):
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n, c))
    if correlated:  # overlapping candidates, as lagged signals are
        X = X + 0.6 * np.roll(X, 1, axis=1) + 2.0
    support = rng.choice(c, k, replace=False)
    coef = rng.uniform(0.5, 2.0, k) * rng.choice([-1, 1], k)
    y = 1.5 + X[:, support] @ coef + noise * rng.standard_normal(n)
    return X, y, support, coef


def _lstsq(X, y, support, intercept=True):
    A = X[:, support]
    if intercept:
        A = np.column_stack([np.ones(len(y)), A])
    sol, *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = y - A @ sol
    return sol, float(resid @ resid) / len(y)


def _greedy(X, y, n_terms):
    """Brute force: at each step refit every remaining candidate and keep the best."""
    chosen = []
    for _ in range(n_terms):
        best = min((c for c in range(X.shape[1]) if c not in chosen),
                   key=lambda c: _lstsq(X, y, chosen + [c])[1])
        chosen.append(best)
    return chosen


@pytest.mark.parametrize("seed", range(8))
def test_coefficients_and_mse_path_equal_least_squares(seed):
    X, y, _, _ = _problem(seed)
    res = fos(X, y, max_terms=8, stop="max_terms")
    sol, _ = _lstsq(X, y, list(res.support))
    np.testing.assert_allclose(res.coef, sol[1:], rtol=1e-9)
    assert res.intercept == pytest.approx(sol[0], rel=1e-9)
    for m in range(1, res.n_terms + 1):
        _, mse = _lstsq(X, y, list(res.support[:m]))
        assert res.mse_path[m - 1] == pytest.approx(mse, rel=1e-9)


@pytest.mark.parametrize("seed", range(10))
def test_selection_equals_brute_force_greedy(seed):
    X, y, _, _ = _problem(seed, n=200, c=15, noise=1.0)
    res = fos(X, y, max_terms=6, stop="max_terms")
    assert res.support.tolist() == _greedy(X, y, 6)


@pytest.mark.parametrize("seed", range(5))
def test_recovers_true_support(seed):
    X, y, support, coef = _problem(seed, n=2000, noise=0.05)
    res = fos(X, y, stop="bic")
    assert sorted(res.support) == sorted(support)
    order = np.argsort(res.support)
    np.testing.assert_allclose(res.coef[order], coef[np.argsort(support)], rtol=1e-2)


def test_gram_and_data_paths_agree():
    X, y, _, _ = _problem(3)
    a = fos(X, y, max_terms=10, stop="max_terms", precompute=True)
    b = fos(X, y, max_terms=10, stop="max_terms", precompute=False)
    assert a.support.tolist() == b.support.tolist()
    np.testing.assert_allclose(a.coef, b.coef, rtol=1e-10)


def test_without_intercept_matches_least_squares():
    X, y, _, _ = _problem(4)
    res = fos(X, y, max_terms=5, stop="max_terms", fit_intercept=False)
    sol, mse = _lstsq(X, y, list(res.support), intercept=False)
    np.testing.assert_allclose(res.coef, sol, rtol=1e-9)
    assert res.intercept == 0.0
    assert res.mse_null == pytest.approx(np.mean(y**2))
    assert res.mse == pytest.approx(mse, rel=1e-9)


def test_duplicate_and_collinear_candidates_are_skipped():
    rng = np.random.default_rng(0)
    base = rng.standard_normal((300, 4))
    X = np.column_stack([base, base[:, 0], base[:, 1] - 2 * base[:, 2], np.full(300, 7.0)])
    y = base @ [1.0, -2.0, 3.0, 0.5] + 0.01 * rng.standard_normal(300)
    res = fos(X, y, stop="max_terms")
    chosen = set(res.support.tolist())
    # four independent directions; of each dependent group only one member
    assert res.n_terms == 4 and res.stop_reason == "exhausted" and res.n_dependent == 3
    assert 6 not in chosen and len(chosen & {0, 4}) == 1 and len(chosen & {1, 2, 5}) == 2
    assert np.all(np.isfinite(res.coef))
    fitted = X[:, res.support] @ res.coef + res.intercept
    sol, *_ = np.linalg.lstsq(np.column_stack([np.ones(300), base]), y, rcond=None)
    np.testing.assert_allclose(fitted, sol[0] + base @ sol[1:], atol=1e-9)


def test_constant_output_gives_intercept_only():
    X = np.random.default_rng(1).standard_normal((50, 3))
    res = fos(X, np.full(50, 4.2))
    assert res.n_terms == 0 and res.intercept == pytest.approx(4.2)
    assert res.stop_reason == "no_reduction"


def test_stop_max_terms_and_variance_and_mean_square():
    X, y, _, _ = _problem(5, noise=0.5)
    assert fos(X, y, max_terms=3, stop="max_terms").n_terms == 3
    res = fos(X, y, stop="variance", tol=0.05)
    assert res.stop_reason == "variance"
    assert res.mse <= 0.05 * res.y_var < res.mse_path[-2]
    res = fos(X, y, stop="mean_square", tol=0.03)
    assert res.mse <= 0.03 * res.y_mean_sq < res.mse_path[-2]


def test_korenberg_rule_is_four_times_mse_over_n():
    X, y, _, _ = _problem(6, noise=1.0)
    res = fos(X, y, stop="korenberg")
    n = len(y)
    # every selected term passed the test ...
    assert np.all(res.q > 4 * res.mse_path / n)
    # ... and the best remaining one failed it
    nxt = fos(X, y, max_terms=res.n_terms + 1, stop="max_terms")
    assert nxt.q[-1] <= 4 * nxt.mse_path[-1] / n
    assert res.stop_reason == "korenberg"


@pytest.mark.parametrize("kind", ["aic", "bic", "fpe", "mdl"])
def test_information_criteria_stop_at_first_increase_of_path(kind):
    X, y, _, _ = _problem(7, noise=1.0)
    res = fos(X, y, stop=kind)
    full = fos(X, y, stop="max_terms")
    n, k0 = len(y), 1
    path = [criterion(kind, full.mse_null, k0, n)] + [
        criterion(kind, m, k0 + i + 1, n) for i, m in enumerate(full.mse_path)]
    first_rise = next(i for i in range(1, len(path)) if path[i] >= path[i - 1])
    assert res.n_terms == first_rise - 1
    np.testing.assert_allclose(res.criterion_path, path[1:first_rise])
    assert res.stop_reason == kind


def test_criteria_formulas():
    assert criterion("aic", math.e, 3, 100) == pytest.approx(100 + 6)
    assert criterion("bic", math.e, 3, 100) == pytest.approx(100 + 3 * math.log(100))
    assert criterion("mdl", 2.0, 3, 100) == criterion("bic", 2.0, 3, 100)
    assert criterion("fpe", 2.0, 3, 100) == pytest.approx(2.0 * 103 / 97)


def test_scaling_and_offset_do_not_change_selection():
    X, y, _, _ = _problem(8, noise=0.5)
    ref = fos(X, y, max_terms=8, stop="max_terms")
    for yy in (y * 1e6, y + 1e4, y * 1e-6):
        res = fos(X, yy, max_terms=8, stop="max_terms")
        assert res.support.tolist() == ref.support.tolist()


def test_never_more_terms_than_samples_allow():
    X = np.random.default_rng(2).standard_normal((6, 20))
    y = np.random.default_rng(3).standard_normal(6)
    res = fos(X, y, stop="max_terms")
    assert res.n_terms == 4 and res.stop_reason == "samples"
    assert np.all(np.isfinite(res.coef))


@pytest.mark.parametrize(
    "args, message",
    [((np.ones((3, 2)), np.ones(4)), "rows"),
     ((np.ones(3), np.ones(3)), "2-D"),
     ((np.array([[1.0], [np.nan]]), np.ones(2)), "non-finite value at index (1, 0)"),
     ((np.ones((2, 1)), np.array([1.0, np.inf])), "non-finite"),
     ((np.ones((1, 1)), np.ones(1)), "at least 2 samples")],
)
def test_bad_input_errors(args, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        fos(*args)


def test_stop_rule_validation():
    for kwargs in ({"kind": "variance"}, {"kind": "nope"}, {"max_terms": -1},
                   {"kind": "mean_square", "tol": 1.5}):
        with pytest.raises(InputError):
            StopRule(**kwargs)


def test_kernel_runs_on_any_provider():
    X, y, _, _ = _problem(9)
    Xc, yc = X - X.mean(0), y - y.mean()
    a = fos_search(DataCorrelations(Xc, yc), StopRule("max_terms", max_terms=5))
    b = fos_search(_GramCorrelations.from_data(Xc, yc), StopRule("max_terms", max_terms=5))
    assert a.support.tolist() == b.support.tolist()


def test_center_makes_exactly_constant_signals_and_columns_zero():
    rng = np.random.default_rng(3)
    varying = rng.standard_normal(50)
    same_ends = varying.copy()
    same_ends[-1] = same_ends[0]  # equal ends, varies in between
    const = np.full(50, 0.1)  # its mean does not round back to 0.1: a - mean is not 0
    assert (center(const)[0] == 0.0).all()
    for sig in (varying, same_ends):
        out, mean = center(sig)
        assert mean == sig.mean() and np.array_equal(out, sig - sig.mean()) and out.any()
    X = np.column_stack([varying, const, same_ends, const * -3.0])
    for arr in (X, np.asfortranarray(X)):
        out, mean = center(arr)
        assert np.array_equal(mean, arr.mean(axis=0))
        assert (out[:, [1, 3]] == 0.0).all()
        assert np.array_equal(out[:, [0, 2]], (arr - arr.mean(axis=0))[:, [0, 2]])


def test_each_stop_rule_decides_for_itself():
    """StopRule.should_stop / reached against the rules written out (n = 1000, k = 3)."""
    from fosmodel.core.fos import StopRule

    n, k, mse = 1000, 3, 2.0
    korenberg = StopRule("korenberg")
    assert korenberg.should_stop(0.0079, mse, k, n)  # 0.0079 <= 4 (2 - 0.0079) / 1000
    assert not korenberg.should_stop(0.0081, mse, k, n)
    aic = StopRule("aic")
    gain = 2.0 / n  # AIC falls iff n ln(mse_new / mse) < -2, i.e. mse_new < mse e^(-2/n)
    assert aic.should_stop(mse * (1 - np.exp(-gain)) * 0.99, mse, k, n)
    assert not aic.should_stop(mse * (1 - np.exp(-gain)) * 1.01, mse, k, n)
    assert not StopRule("max_terms").should_stop(0.0, mse, k, n)
    variance = StopRule("variance", tol=0.5)
    assert variance.reached(1.0, 2.0, 9.0) and not variance.reached(1.01, 2.0, 9.0)
    assert StopRule("mean_square", tol=0.1).reached(0.9, 2.0, 9.0)


def _ols_std_errors(A, y):
    """Standard errors point by point: s^2 (A'A)^-1 with s^2 = RSS / (N - k)."""
    sol, *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = y - A @ sol
    s2 = float(resid @ resid) / (A.shape[0] - A.shape[1])
    return np.sqrt(s2 * np.diag(np.linalg.inv(A.T @ A)))


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("intercept", [True, False])
def test_standard_errors_equal_least_squares(seed, intercept):
    X, y, _, _ = _problem(seed, noise=0.5)
    res = fos_search(DataCorrelations(X, y), StopRule("max_terms", max_terms=6),
                     intercept=intercept)
    A = X[:, res.support]
    if intercept:
        A = np.column_stack([np.ones(len(y)), A])
    se = _ols_std_errors(A, y)
    got = np.r_[res.intercept_se, res.coef_se] if intercept else res.coef_se
    np.testing.assert_allclose(got, se, rtol=1e-8)
    if not intercept:
        assert math.isnan(res.intercept_se)


def test_standard_errors_of_constant_only_model_are_those_of_the_mean():
    y = np.random.default_rng(2).normal(3.0, 2.0, 200)
    res = fos_search(DataCorrelations(np.ones((200, 1)), y), StopRule("korenberg"))
    assert res.coef_se.shape == (0,)
    assert res.intercept_se == pytest.approx(y.std(ddof=1) / math.sqrt(200), rel=1e-12)
