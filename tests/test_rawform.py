"""The raw form of a centred FOS model: products of z - mu multiplied out into raw monomials."""

import numpy as np
import pytest

from fosmodel import FOSModel
from fosmodel.core.candidates import Term, evaluate_terms
from fosmodel.core.levels import level_series
from fosmodel.models.rawform import expand_centred


def _offset_narx(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """SysIdentPy's test system with an input of mean 1 and an output offset of 3."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 2.0, n)
    e = 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.2 * y[k - 1] + 0.1 * y[k - 1] * x[k - 1] + 0.9 * x[k - 2] + e[k]
    return y + 3.0, x


def _raw_prediction(raw: dict[str, float], signals: dict[str, np.ndarray], start: int):
    terms = [Term.parse(name) for name in raw]
    return evaluate_terms(terms, signals, start) @ np.array(list(raw.values()))


def test_a_square_and_a_cross_product_multiply_out_by_hand():
    # 0.5 + 2 (y1 - 1)^2 - 3 (y1 - 1)(x2 - 4), with mu_y = 1 moved over to the constant
    terms = [Term.parse("y[n-1]^2"), Term.parse("y[n-1]*x[n-2]")]
    raw = expand_centred(terms, [2.0, -3.0], 0.5, {"y": 1.0, "x": 4.0})
    assert {t.name: w for t, w in raw.items()} == {
        "1": 0.5 + 1.0 + 2.0 - 12.0, "y[n-1]": -4.0 + 12.0, "x[n-2]": 3.0,
        "y[n-1]^2": 2.0, "y[n-1]*x[n-2]": -3.0}
    assert [t.degree for t in raw] == [0, 1, 1, 2, 2]


@pytest.mark.parametrize("degree", [2, 3])
def test_raw_form_predicts_what_the_centred_model_predicts(degree):
    y, x = _offset_narx(3000, 0)
    model = FOSModel(max_lag=3, degree=degree, exog_lags={"x": 2}, stop="max_terms",
                     max_terms=8).fit(y, {"x": x})
    raw = model.raw_coefficients()
    prediction = model.predict(y, {"x": x})
    np.testing.assert_allclose(_raw_prediction(raw, {"y": y, "x": x}, 3), prediction[3:],
                               rtol=0, atol=1e-10)


def test_raw_form_of_levels_and_user_columns():
    y, x = _offset_narx(4000, 1)
    trend = np.linspace(-1.0, 2.0, len(y))
    y = y + 0.4 * trend
    model = FOSModel(max_lag=2, degree=2, exog_lags={"x": 2}, columns=["trend"], levels=[0.5],
                     rate=100.0, stop="max_terms", max_terms=10).fit(y, {"x": x, "trend": trend})
    assert "level@0.5s" in " ".join(model.terms_) and "trend" in model.terms_
    signals = {"y": y, "x": x, "trend": trend, "level@0.5s": level_series(y, 0.5, 100.0)}
    prediction = model.predict(y, {"x": x, "trend": trend})
    np.testing.assert_allclose(_raw_prediction(model.raw_coefficients(), signals, 2),
                               prediction[2:], rtol=0, atol=1e-10)


def test_an_uncentred_model_comes_back_unchanged():
    y, x = _offset_narx(3000, 2)
    model = FOSModel(max_lag=2, degree=2, exog_lags={"x": 2}, stop="max_terms", max_terms=3,
                     center=False).fit(y, {"x": x})
    assert model.raw_coefficients() == {"1": model.intercept_,
                                        **dict(zip(model.terms_, model.coef_))}


def test_a_centred_model_with_the_extra_term_recovers_the_raw_system():
    # centred, y[n-1]*x[n-1] needs a centred x[n-1] beside it; in raw form that is the system
    y, x = _offset_narx(5000, 3)
    model = FOSModel(max_lag=2, degree=2, exog_lags={"x": 2}, stop="max_terms",
                     max_terms=4).fit(y, {"x": x})
    assert set(model.terms_) == {"y[n-1]", "x[n-1]", "x[n-2]", "y[n-1]*x[n-1]"}
    raw = model.raw_coefficients()
    # y = 3 + y' with y' the system: 0.1 (y - 3) x = 0.1 y x - 0.3 x, constant 3 (1 - 0.2)
    truth = {"1": 2.4, "y[n-1]": 0.2, "x[n-1]": -0.3, "x[n-2]": 0.9, "y[n-1]*x[n-1]": 0.1}
    assert set(raw) == set(truth)
    for name, value in truth.items():
        assert raw[name] == pytest.approx(value, abs=0.03), name
