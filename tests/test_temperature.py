"""Temperature-dependent models of chamber records (fosmodel.study.temperature)."""

import math

import numpy as np
import pandas as pd
import pytest
from numpy.polynomial import Polynomial
from scipy.signal import lfilter

from data_synth import StepProfile, TemperatureBias, WhiteNoise, compose, make_scenario
from data_synth.profiles import CHAMBER_LEVELS_C
from data_synth.scenarios import CC300_GYRO_ARW, CC300_TEMPS_C
from fosmodel import FOSModel, InputError
from fosmodel.study.temperature import (
    TableModel,
    held_out_comparison,
    segment_noise,
    segment_table,
    temperature_segments,
    term_standard_errors,
)

Z = 4.0


@pytest.fixture(scope="module")
def chamber():
    return {name: make_scenario(name, seed=1)
            for name in ("temp_chamber_gyro", "temp_chamber_accel")}


def _truth_bias(rec, temp):
    """The record's temperature polynomial (truth sidecar) at the given temperatures."""
    src = next(s for s in rec.truth["sources"] if s["kind"] == "temperature_bias")
    return Polynomial(src["params"]["coefs"])(temp - src["params"]["t_ref_c"])


def test_plateaus_are_found_at_the_chamber_levels_without_the_transitions(chamber):
    rec = chamber["temp_chamber_gyro"]
    temp = rec.columns["temp_c"]
    segments = temperature_segments(temp, rec.rate)
    assert [round(float(np.median(temp[s]))) for s in segments] == list(CHAMBER_LEVELS_C)
    profile = StepProfile(CHAMBER_LEVELS_C, lag_s=60.0).generate(rec.n_samples, rec.rate, None)
    dwell = rec.n_samples // len(CHAMBER_LEVELS_C)
    for k, (level, s) in enumerate(zip(CHAMBER_LEVELS_C, segments)):
        # settled: within settle_c = 0.25 C of a level that is itself ~0.05 C short of the set
        # point, more than three thermal time constants (60 s) after the step
        assert np.abs(profile[s] - level).max() <= 0.35
        assert k == 0 or s.start >= k * dwell + 180 * rec.rate
        assert s.stop <= (k + 1) * dwell + 1 and s.stop - s.start >= 120 * rec.rate


def test_plateaus_survive_ten_times_the_read_out_noise():
    rec = compose([StepProfile(CHAMBER_LEVELS_C, lag_s=60.0, channel="temp_c", name="chamber"),
                   WhiteNoise(0.02, channel="temp_c", name="noise"),
                   WhiteNoise(0.05, name="white")],
                  duration=3600, rate=100, seed=2, target="gyro_y",
                  column_units={"temp_c": "degC"})
    temp = rec.columns["temp_c"]
    segments = temperature_segments(temp, rec.rate)
    assert [round(float(np.median(temp[s]))) for s in segments] == list(CHAMBER_LEVELS_C)


def test_a_constant_temperature_is_one_plateau_and_a_ramp_none():
    rate, n = 100.0, 30_000
    noise = 0.02 * np.random.default_rng(0).standard_normal(n)
    assert temperature_segments(25.0 + noise, rate) == [slice(0, n)]
    assert temperature_segments(np.linspace(-30, 60, n) + noise, rate) == []


@pytest.mark.parametrize("name", ["temp_chamber_gyro", "temp_chamber_accel"])
def test_per_plateau_bias_matches_the_truth_polynomial_within_its_standard_error(chamber, name):
    rec = chamber[name]
    y, temp = rec.columns[rec.target], rec.columns["temp_c"]
    segments = temperature_segments(temp, rec.rate)
    table = segment_table(y, temp, segments)
    truth = np.array([_truth_bias(rec, temp[s]).mean() for s in segments])
    assert np.all(np.abs(table["bias"] - truth) <= Z * table["bias_se"])
    # white noise: the AR(1) weight is zero within its standard error, which is ~1/sqrt(n)
    assert np.all(np.abs(table["coef y[n-1]"]) <= Z * table["se y[n-1]"])
    np.testing.assert_allclose(table["se y[n-1]"], 1 / np.sqrt(table["n"]), rtol=0.05)


def test_per_plateau_noise_follows_el_diasty_2007_table_1(chamber):
    rec = chamber["temp_chamber_gyro"]
    y, temp = rec.columns[rec.target], rec.columns["temp_c"]
    segments = temperature_segments(temp, rec.rate)
    table = pd.concat([segment_table(y, temp, segments),
                       segment_noise(y, rec.rate, segments, "gyro", "deg/s")], axis=1)
    arw = np.interp(table["temp_c"], CC300_TEMPS_C, CC300_GYRO_ARW)
    assert set(table["noise_units"]) == {"deg/sqrt(h)"}
    assert np.all(np.abs(table["noise"] - arw) <= Z * table["noise_se"])


def test_term_standard_errors_are_ols_on_the_selected_terms():
    rng = np.random.default_rng(4)
    n = 20_000
    y = 3.0 + lfilter([1.0], [1.0, -1.2, 0.5], rng.standard_normal(n))
    model = FOSModel(max_lag=4).fit(y)
    table = term_standard_errors(model, y)
    assert table["term"].tolist() == ["1", "y[n-1]", "y[n-2]"]
    np.testing.assert_allclose(table["coef"], [model.intercept_, *model.coef_], atol=1e-10)
    assert np.all(np.abs(table["coef"].to_numpy()[1:] - [1.2, -0.5]) <= Z * table["se"][1:])
    # the AR(2) weights' asymptotic standard error: sqrt((1 - a2^2) / n)
    np.testing.assert_allclose(table["se"][1:], math.sqrt((1 - 0.25) / n), rtol=0.05)
    temp = np.linspace(20.0, 30.0, n)
    with_temp = FOSModel(max_lag=2, exog_lags={"temp_c": 1}).fit(y, {"temp_c": temp})
    with pytest.raises(InputError, match=r"^the model reads temp_c; pass them in exog$"):
        term_standard_errors(with_temp, y)


def _short_chamber(seed, dependent):
    """Five chamber levels, 10 s thermal lag, 180 s dwell: a fast stand-in for a chamber run."""
    sources = [StepProfile(CHAMBER_LEVELS_C[::2], lag_s=10.0, channel="temp_c", name="chamber"),
               WhiteNoise(0.002, channel="temp_c", name="temp_noise"),
               WhiteNoise(0.05, name="white")]
    if dependent:
        sources.append(TemperatureBias((0.28, 0.006, 1e-4), name="temperature_bias"))
    rec = compose(sources, duration=900, rate=100, seed=seed, target="gyro_y",
                  column_units={"temp_c": "degC"})
    return rec.columns["gyro_y"], rec.columns["temp_c"]


@pytest.mark.parametrize("dependent", [True, False])
def test_temperature_input_helps_on_held_out_plateaus_only_when_the_bias_depends_on_it(
        dependent):
    y, temp = _short_chamber(5, dependent)
    segments = temperature_segments(temp, 100.0)
    assert len(segments) == 5
    res = held_out_comparison(y, temp, 100.0, segments, sensor="gyro", units="deg/s",
                              n_starts=5)
    mean = res.groupby("model")[["mse", "outage_position_error_m"]].mean()
    gain = mean.loc["fos_temp"] / mean.loc["fos"]
    if dependent:
        # the white-noise floor 0.05^2 * 100 (deg/s)^2 is reached; outages drift far less
        assert mean.loc["fos_temp", "mse"] == pytest.approx(0.25, rel=0.01)
        assert gain["mse"] < 0.95 and gain["outage_position_error_m"] < 0.2
        assert mean.loc["table", "outage_position_error_m"] < 0.2 * mean.loc["fos",
                                                                             "outage_position_error_m"]
    else:
        assert gain["mse"] == pytest.approx(1.0, abs=0.01)
        assert gain["outage_position_error_m"] > 0.8


def test_table_model_predicts_the_temperature_bias_and_ar_weight():
    temp = np.repeat([0.0, 20.0, 40.0], 4)
    table = pd.DataFrame({"temp_c": [0.0, 20.0, 40.0], "bias": [1.0, 2.0, 5.0],
                          "bias_se": [0.1] * 3, "coef y[n-1]": [0.5] * 3,
                          "se y[n-1]": [0.01] * 3})
    model = TableModel(table, temp)
    y = np.linspace(0, 1, 12)
    bias = np.repeat([1.0, 2.0, 5.0], 4)
    expected = bias[1:] + 0.5 * (y[:-1] - bias[:-1])
    np.testing.assert_allclose(model.predict(y)[1:], expected, atol=1e-12)
    free = model.simulate(y[:5], 3)
    np.testing.assert_allclose(free, [2 + 0.5 * (y[4] - 2), 2 + 0.25 * (y[4] - 2),
                                      2 + 0.125 * (y[4] - 2)], atol=1e-12)


def test_held_out_needs_three_plateaus():
    with pytest.raises(InputError, match="at least 3 plateaus"):
        held_out_comparison(np.zeros(100), np.zeros(100), 10.0, [slice(0, 50), slice(50, 100)])
