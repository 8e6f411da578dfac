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
    start = temp[: round(20 * RATE)].mean()  # the level starts at the first 20 s's mean
    np.testing.assert_allclose(derive(fast_name("temp", 20), N, RATE, channels, {}),
                               temp - level_series(np.r_[start, temp], 20.0, RATE)[1:])


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


HEADERS = ["temp_c", "Accel X (g)", "gyro_rad[0]", "a*b^2", "2nd sensor", "x__y", "u__z",
           "température", "acc.x [m/s^2]", "_"]


@pytest.mark.parametrize("header", HEADERS)
def test_any_header_round_trips_through_its_token_and_every_name(header):
    from fosmodel.core.candidates import CandidateSpec, Term
    from fosmodel.core.derived import (
        channel_token,
        lowpass_name,
        power_name,
        rate_name,
        square_name,
        token_channel,
    )

    token = channel_token(header)
    assert token_channel(token) == header
    assert token.isidentifier() and (token == header) == (header in ("temp_c", "_"))
    names = [lowpass_name(header, 600), rate_name(header, 60.0), power_name(header, 2, -3.5),
             power_name(header, 3, 25.25, tau_s=1200), square_name(header)]
    for name in names:
        assert is_derived(name) and channels_read([name]) == [header]
        assert Term.parse(name).name == name  # a term of its own, read back whole
    spec = CandidateSpec(2, 1, {fast_name(header, 20): 3}, names)  # raises if a name is bad
    assert channels_read(spec.exog_lags) == [header]


def test_a_driver_s_forms_compute_what_their_names_say():
    from fosmodel.core.derived import first_order_lag, lowpass_name, power_name, rate_name

    rng = np.random.default_rng(0)
    x = 20 + np.cumsum(rng.standard_normal(N)) * 0.1
    channels = {"Die temp (C)": x}
    lag = np.empty(N)  # the recursion, sample by sample: the reference
    lag[0] = x[0]
    for k in range(1, N):
        lag[k] = lag[k - 1] + (x[k] - lag[k - 1]) / (30.0 * RATE)
    np.testing.assert_allclose(first_order_lag(x, 30.0, RATE), lag, rtol=1e-12)
    name = lowpass_name("Die temp (C)", 30)
    assert name == "lowpass(u__Die_20_temp_20__28_C_29_,30s)"
    np.testing.assert_allclose(derive(name, N, RATE, channels, {}), lag, rtol=1e-12)
    np.testing.assert_allclose(derive(rate_name("Die temp (C)", 30), N, RATE, channels, {}),
                               np.r_[0.0, np.diff(lag) * RATE], rtol=0, atol=1e-11)
    np.testing.assert_allclose(derive(power_name("Die temp (C)", 2, 21.5), N, RATE, channels,
                                      {}), (x - 21.5) ** 2, rtol=1e-12)
    np.testing.assert_allclose(derive(power_name("Die temp (C)", 3, -1.0, tau_s=30), N, RATE,
                                      channels, {}), (lag + 1.0) ** 3, rtol=1e-12)
    with pytest.raises(InputError, match=r"needs the channel 'Die temp \(C\)'"):
        derive(name, N, RATE, {}, {})
    with pytest.raises(InputError, match="shorter than one sample"):
        derive(lowpass_name("Die temp (C)", 0.001), N, RATE, channels, {})
    assert not is_derived("pow(cos@1Hz,2,0)")  # a power reads a channel or its lag only


def test_a_spelled_token_is_its_channel_as_an_input_with_lags():
    """``Accel Y (g)`` enters a model as the input ``u__...``: rebuilt from the record's column
    of that header, its square centred on the mean the fitted model keeps under the token."""
    from fosmodel.core.candidates import CandidateSpec
    from fosmodel.core.derived import channel_token, square_name

    rng = np.random.default_rng(1)
    x = rng.normal(2.0, 1.0, N)
    token = channel_token("Accel Y (g)")
    assert is_derived(token) and channels_read([token]) == ["Accel Y (g)"]
    np.testing.assert_array_equal(derive(token, N, RATE, {"Accel Y (g)": x}, {}), x)
    spec = CandidateSpec(2, 1, {token: 3}, [square_name("Accel Y (g)")])
    assert channels_read([*spec.exog_lags, *spec.columns]) == ["Accel Y (g)"]
    square = derive(square_name("Accel Y (g)"), N, RATE, {"Accel Y (g)": x}, {token: 2.0})
    np.testing.assert_allclose(square, (x - 2.0) ** 2)
    assert not is_derived("temp_c") and not is_derived("u_x")
