"""Columns rebuilt from their names (fosmodel.core.derived), and models that rebuild them."""

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel
from fosmodel.core.derived import (
    channels_read,
    cosine_name,
    derive,
    exp_name,
    fast_name,
    is_derived,
    step_name,
)
from fosmodel.core.exceptions import InputError
from fosmodel.core.levels import level_series

RATE, N = 50.0, 4000
T = np.arange(N) / RATE


def test_each_name_rebuilds_its_column():
    temp = np.linspace(20, 30, N)
    channels, offsets = {"temp": temp}, {"temp": 25.0}
    np.testing.assert_allclose(derive(cosine_name(1.5), N, RATE, {}, {}), np.cos(3 * np.pi * T))
    np.testing.assert_allclose(derive("sin@1.5Hz", N, RATE, {}, {}), np.sin(3 * np.pi * T))
    np.testing.assert_array_equal(derive("t@s", N, RATE, {}, {}), T)
    np.testing.assert_allclose(derive(exp_name(7.5), N, RATE, {}, {}), np.exp(-T / 7.5))
    np.testing.assert_array_equal(derive(step_name(12.34), N, RATE, {}, {}),
                                  (T >= 12.34).astype(float))
    np.testing.assert_allclose(derive("sq(temp)", N, RATE, channels, offsets), (temp - 25) ** 2)
    np.testing.assert_allclose(derive(fast_name("temp", 20), N, RATE, channels, {}),
                               temp - level_series(temp, 20.0, RATE))


def test_names_keep_enough_digits_and_say_what_they_read():
    assert cosine_name(7.31374321) == "cos@7.3137432Hz"
    assert step_name(2051.2345) == "step@2051.2345s"
    assert fast_name("ay_g", 20.0) == "ay_g_fast20s"
    assert all(map(is_derived, ["t@s", "exp(-t/62.3s)", "sq(x)", "x_fast20s", "cos@1e-05Hz"]))
    assert not any(map(is_derived, ["t", "temp", "x_fast", "cos@Hz", "level@20s"]))
    assert channels_read(["sq(a)", "b_fast5s", "t@s", "sq(a)"]) == ["a", "b"]
    with pytest.raises(InputError, match="needs the channel 'temp' and its training mean"):
        derive("sq(temp)", N, RATE, {}, {})
    with pytest.raises(InputError, match="not one fosmodel can derive"):
        derive("temp", N, RATE, {}, {})


def test_a_fitted_model_rebuilds_its_columns_and_fast_channels():
    rng = np.random.default_rng(2)
    temp = 20 + np.cumsum(rng.standard_normal(N)) * 0.05
    fast = derive(fast_name("temp", 10), N, RATE, {"temp": temp}, {})
    y = (lfilter([1.0], [1.0, -0.5], rng.standard_normal(N)) * 0.1
         + 0.3 * np.cos(2 * np.pi * 1.5 * T) + 0.5 * fast + 0.2 * (T >= 40.0))
    exog = {"temp_fast10s": fast, "cos@1.5Hz": np.cos(3 * np.pi * T), "step@40s": T >= 40.0}
    model = FOSModel(max_lag=2, exog_lags={"temp_fast10s": 1}, columns=["cos@1.5Hz", "step@40s"],
                     rate=RATE).fit(y, exog)
    assert {"temp_fast10s[n-0]", "cos@1.5Hz", "step@40s"} <= set(model.terms_)
    assert model.input_columns() == ["temp"]
    np.testing.assert_allclose(model.predict(y, {"temp": temp}), model.predict(y, exog),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(model.simulate(y[:1000], 500, {"temp": temp[:1500]}),
                               model.simulate(y[:1000], 500, {k: np.asarray(v[:1500], float)
                                                              for k, v in exog.items()}),
                               rtol=0, atol=1e-12)
    without_rate = FOSModel(columns=["cos@1.5Hz"]).fit(y, exog)
    with pytest.raises(InputError, match="can be rebuilt only with the model's sample rate"):
        without_rate.predict(y)
