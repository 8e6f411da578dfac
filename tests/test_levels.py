"""Local-level candidates (fosmodel.core.levels) in FOSModel: fit, predict, free run, export."""

import json

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import CandidateSpec, FOSModel, Term, generate_terms
from fosmodel.core.candidates import evaluate_terms
from fosmodel.core.exceptions import InputError
from fosmodel.core.levels import level_after, level_grid, level_name, level_series, level_tau
from fosmodel.filter.statespace import to_nonlinear_state_space, to_state_space

RATE = 100.0


def _record(n=20_000, seed=0, walk=0.01, offset=3.0):
    """AR(2) noise on a random-walk bias, plus an input channel that enters the output."""
    rng = np.random.default_rng(seed)
    temp = np.cumsum(rng.standard_normal(n)) * 0.01
    noise = lfilter([1.0], [1.0, -0.5, 0.2], rng.standard_normal(n)) * 0.3
    return noise + np.cumsum(rng.standard_normal(n)) * walk + offset + 0.2 * temp, temp


def _level_by_hand(y, tau):
    a, out = 1.0 / (tau * RATE), [y[0]]
    for v in y[:-1]:
        out.append((1 - a) * out[-1] + a * v)
    return np.array(out)


def test_level_series_is_the_causal_exponential_mean_started_at_the_first_sample():
    y = np.random.default_rng(1).standard_normal(500)
    np.testing.assert_allclose(level_series(y, 0.3, RATE), _level_by_hand(y, 0.3), rtol=1e-13)
    # the level at n reads only y[:n]: changing y[n] leaves it alone
    z = y.copy()
    z[200] += 100.0
    np.testing.assert_array_equal(level_series(z, 0.3, RATE)[:201],
                                  level_series(y, 0.3, RATE)[:201])
    assert level_after(y[:201], 0.3, RATE) == pytest.approx(level_series(y, 0.3, RATE)[201])


def test_names_parse_back_and_round_to_four_digits():
    assert level_name(20) == "level@20s" and level_tau("level@20s") == 20.0
    assert level_tau(level_name(12.3456789)) == 12.35
    assert level_tau("level@1.5e+03s") == 1500.0 and level_tau("temp") is None
    term = Term.parse("y[n-1]*level@20s")
    assert term.factors == (("y", 1), ("level@20s", 0)) and term.name == "y[n-1]*level@20s"
    assert Term.parse("level@5s^2").name == "level@5s^2"


def test_spec_offers_levels_like_lagged_outputs():
    spec = CandidateSpec(max_lag=2, degree=2, levels=(20.0, 5.0))
    assert spec.levels == (5.0, 20.0) and spec.lag_window == 2
    names = [t.name for t in generate_terms(spec)]
    assert names[:5] == ["1", "y[n-1]", "y[n-2]", "level@5s", "level@20s"]
    assert "y[n-2]*level@20s" in names and "level@5s^2" in names
    assert CandidateSpec(max_lag=0, levels=(1.0,)).lag_window == 1  # level[0] is y[0]
    with pytest.raises(InputError, match="level time constants repeat: level@5s, level@5s"):
        CandidateSpec(levels=(5.0, 5.00001))
    with pytest.raises(InputError, match="must be a positive number of seconds, got -1"):
        CandidateSpec(levels=(-1,))
    with pytest.raises(InputError, match="clashes with a channel"):
        CandidateSpec(columns=("level@3s",))


def test_levels_need_a_rate_and_at_least_one_sample():
    y, _ = _record(2000)
    with pytest.raises(InputError, match=r"need the sample rate in Hz \(rate=...\), got None"):
        FOSModel(levels=[5.0]).fit(y)
    with pytest.raises(InputError, match="level@0.001s is shorter than one sample at 100 Hz"):
        FOSModel(levels=[0.001], rate=RATE).fit(y)


@pytest.mark.parametrize("degree", [1, 2])
def test_fast_correlations_match_the_point_by_point_reference(degree):
    y, temp = _record(6000)
    kw = dict(max_lag=4, degree=degree, levels=[0.5, 5.0, 20.0], rate=RATE,
              exog_lags={"temp": 1}, max_terms=10)
    fast = FOSModel(**kw).fit(y, {"temp": temp})
    ref = FOSModel(**kw, correlations="reference").fit(y, {"temp": temp})
    assert fast.terms_ == ref.terms_
    assert any("level@" in t for t in fast.terms_)
    np.testing.assert_allclose(fast.coef_, ref.coef_, rtol=1e-8, atol=1e-12)


def test_weights_and_predictions_agree_with_least_squares_on_the_level_columns():
    y, _ = _record()
    model = FOSModel(max_lag=3, levels=[2.0, 10.0, 30.0], rate=RATE).fit(y)
    yc = y - model.offsets_["y"]
    signals = {"y": yc, **{level_name(t): _level_by_hand(yc, t) for t in (2.0, 10.0, 30.0)}}
    x = evaluate_terms([Term.parse(t) for t in model.terms_], signals, model.lag_window_)
    design = np.column_stack([np.ones(len(x)), x])
    coef = np.linalg.lstsq(design, yc[model.lag_window_:], rcond=None)[0]
    np.testing.assert_allclose([model.intercept_, *model.coef_], coef, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(model.predict(y)[model.lag_window_:],
                               design @ coef + model.offsets_["y"], rtol=0, atol=1e-10)


def test_a_level_tracks_a_random_walk_bias_that_a_global_mean_cannot():
    y, _ = _record(walk=0.02)
    train, test = slice(0, 10_000), slice(10_000, None)
    plain = FOSModel(max_lag=3).fit(y[train])
    level = FOSModel(max_lag=3, levels=[2.0, 10.0], rate=RATE).fit(y[train])
    assert any(t.startswith("level@") for t in level.terms_)
    err = {name: np.mean((y - m.predict(y))[test] ** 2) for name, m in
           (("plain", plain), ("level", level))}
    assert err["level"] < 0.9 * err["plain"]


def test_free_run_feeds_the_level_its_own_predictions_never_the_truth():
    y, _ = _record(walk=0.02)
    model = FOSModel(max_lag=2, levels=[1.0], rate=RATE).fit(y)
    start, steps = 8000, 500
    run = model.simulate(y[:start], steps)
    # by hand: the level starts from the true past, then follows the run
    mu, a = model.offsets_["y"], 1.0 / RATE
    out, lv = list(y[start - 2:start] - mu), level_after(y[:start] - mu, 1.0, RATE)
    weights = dict(zip(model.terms_, model.coef_))
    for _ in range(steps):
        v = (model.intercept_ + weights.get("y[n-1]", 0) * out[-1]
             + weights.get("y[n-2]", 0) * out[-2] + weights["level@1s"] * lv)
        out.append(v)
        lv = (1 - a) * lv + a * v
    np.testing.assert_allclose(run, np.array(out[2:]) + mu, rtol=0, atol=1e-11)
    # changing the truth inside the outage changes nothing of the run
    changed = y.copy()
    changed[start:] += 50.0
    np.testing.assert_array_equal(model.free_runs(changed, [start], steps)[0],
                                  model.free_runs(y, [start], steps)[0])


@pytest.mark.parametrize("degree", [1, 2])
def test_free_runs_at_once_equal_one_at_a_time(degree):
    y, temp = _record()
    model = FOSModel(max_lag=3, degree=degree, levels=[1.0, 8.0], rate=RATE,
                     exog_lags={"temp": 1}, max_terms=9, stop="max_terms").fit(y, {"temp": temp})
    starts, steps = [3, 1000, 12_345, 19_000], 1000
    many = model.free_runs(y, starts, steps, {"temp": temp})
    for row, s in zip(many, starts):
        one = model.simulate(y[:s], steps, {"temp": temp[: s + steps]})
        np.testing.assert_allclose(row, one, rtol=1e-12, atol=1e-12)


def test_json_round_trip_predicts_and_runs_identically():
    y, _ = _record()
    model = FOSModel(max_lag=3, levels=[2.0, 10.0], rate=RATE).fit(y)
    back = FOSModel.from_dict(json.loads(json.dumps(model.to_dict())))
    assert back.terms_ == model.terms_ and back.get_params() == model.get_params()
    np.testing.assert_array_equal(back.predict(y), model.predict(y))
    np.testing.assert_array_equal(back.simulate(y[:5000], 300), model.simulate(y[:5000], 300))
    text = str(model.summary())
    assert "Levels offered" in text and "level@2s, level@10s" in text


@pytest.mark.parametrize("nonlinear", [False, True])
def test_state_space_reproduces_predictions_and_free_runs(nonlinear):
    y, temp = _record()
    kw = dict(max_lag=3, levels=[2.0, 10.0], rate=RATE, exog_lags={"temp": 1})
    if nonlinear:
        kw.update(degree=2, max_terms=9, stop="max_terms")
    model = FOSModel(**kw).fit(y, {"temp": temp})
    ss = (to_nonlinear_state_space if nonlinear else to_state_space)(model)
    n_levels = sum(name.startswith("level@") for name in ss.state_names)
    assert n_levels == len({f[0] for t in model.terms_ for f in Term.parse(t).factors
                            if f[0].startswith("level@")})
    u = ss.input_matrix({"temp": temp}, len(y))
    pred = model.predict(y, {"temp": temp})
    for s in (10, 4321, 15_000):
        x = ss.state_from(y[:s])
        assert ss.predict_measurement(ss.step(x, u[s])) == pytest.approx(pred[s], abs=1e-12)
        run = ss.simulate(400, x, u[s : s + 400])
        np.testing.assert_allclose(run, model.simulate(y[:s], 400, {"temp": temp[: s + 400]}),
                                   rtol=0, atol=1e-11)
    if nonlinear:
        x, eps = ss.state_from(y[:4321]), 1e-6
        numeric = np.column_stack([(ss.f(x + eps * e, u[4321]) - ss.f(x - eps * e, u[4321]))
                                   / (2 * eps) for e in np.eye(len(x))])
        np.testing.assert_allclose(ss.jacobian(x, u[4321]), numeric, atol=1e-7)


def test_level_grid_spans_below_the_allan_floor():
    grid = level_grid(1_000_000, RATE, tau_floor_s=300.0)
    assert len(grid) == 4 and grid == tuple(sorted(grid))
    assert grid[-1] == pytest.approx(300 / np.sqrt(3), rel=1e-3)
    assert grid[0] == pytest.approx(10.0, rel=1e-3)
    assert level_grid(200_000, RATE)[-1] == 100.0  # no floor: a twentieth of the record
    assert level_grid(100, RATE) == ()  # too short for a level of 10 samples


@pytest.mark.parametrize("start", [0, 777])
@pytest.mark.parametrize("as_series", [False, True])
def test_a_long_prediction_in_blocks_equals_the_one_pass(monkeypatch, start, as_series):
    import pandas as pd

    from fosmodel.models import model as model_module

    y, temp = _record(6000)
    sine = {"sin@0.7Hz": np.sin(2 * np.pi * 0.7 * np.arange(len(y)) / RATE)}
    fit = FOSModel(max_lag=4, degree=2, levels=[0.5, 5.0], rate=RATE, exog_lags={"temp": 2},
                   columns=list(sine), max_terms=12, stop="max_terms")
    fit.fit(y, {"temp": temp, **sine})  # levels, products, temp and their products
    assert any("level" in t for t in fit.terms_) and any("*temp" in t for t in fit.terms_)
    exog = {"temp": temp, **sine, **{level_name(t): level_series(y, t, RATE) for t in (0.5, 5.0)}}
    assert fit._blockable(exog, len(y)) and not fit._blockable({"temp": temp}, len(y))
    whole = fit.predict(y, exog, start=start)
    monkeypatch.setattr(model_module, "_PREDICT_ROWS", 1000)  # 6 blocks, the last one short
    y_in = pd.Series(y, index=np.arange(len(y)) + 5) if as_series else y
    blocks = fit.predict(y_in, exog, start=start)
    np.testing.assert_array_equal(np.asarray(blocks), whole)
    assert isinstance(blocks, pd.Series) == as_series
    np.testing.assert_array_equal(fit.predict(y, {"temp": temp}, start=start), whole)


@pytest.mark.parametrize("degree", [1, 2])  # the linear runs' superposition, the recursion
def test_free_runs_over_a_long_record_in_groups_equal_the_one_call(monkeypatch, degree):
    from fosmodel.models import model as model_module

    y, temp = _record(6000)
    fit = FOSModel(max_lag=4, degree=degree, levels=[0.5, 5.0], rate=RATE,
                   exog_lags={"temp": 2}, max_terms=10, stop="max_terms")
    fit.fit(y, {"temp": temp})
    assert any("level" in t for t in fit.terms_)
    exog = {"temp": temp, **{level_name(t): level_series(y, t, RATE) for t in (0.5, 5.0)}}
    starts = np.r_[5000, np.arange(10, 5800, 397), 3001, 407]  # out of order, with a repeat
    whole = fit.free_runs(y, starts, 150, exog)
    calls = []
    one_call = model_module.FOSModel.free_runs
    monkeypatch.setattr(model_module.FOSModel, "free_runs",
                        lambda self, *a: calls.append(a[1]) or one_call(self, *a))
    monkeypatch.setattr(model_module, "_PREDICT_ROWS", 1000)  # groups of runs within 1000 samples
    groups = fit.free_runs(y, starts, 150, exog)
    np.testing.assert_array_equal(groups, whole)
    spans = [s.max() + 150 - (s.min() - fit.lag_window_) for s in calls[1:]]
    assert len(calls) == 6 and max(spans) <= 1000  # five groups
    assert sorted(np.concatenate(calls[1:]).tolist()) == sorted(starts.tolist())
    # a level not given is computed over the record's whole past: one call, as before
    np.testing.assert_array_equal(fit.free_runs(y, starts, 150, {"temp": temp}), whole)


def test_a_channel_of_another_length_is_named_in_a_long_prediction(monkeypatch):
    from fosmodel.models import model as model_module

    y, temp = _record(3000)
    fit = FOSModel(max_lag=3, exog_lags={"temp": 1}).fit(y, {"temp": temp})
    monkeypatch.setattr(model_module, "_PREDICT_ROWS", 500)
    with pytest.raises(InputError, match="channel 'temp' has 2999 samples, the output has 3000"):
        fit.predict(y, {"temp": temp[:-1]})


def test_level_series_keeps_recent_series_within_its_budget(monkeypatch):
    from fosmodel.core import levels

    monkeypatch.setattr(levels, "_RECENT", [])
    monkeypatch.setattr(levels, "_KEEP_SAMPLES", 1000)
    y = np.random.default_rng(0).standard_normal(400)
    first = level_series(y, 1.0, 100.0)
    assert level_series(y, 1.0, 100.0) is first
    second, third = level_series(y, 2.0, 100.0), level_series(y, 3.0, 100.0)  # 1200 samples
    assert level_series(y, 3.0, 100.0) is third and level_series(y, 2.0, 100.0) is second
    again = level_series(y, 1.0, 100.0)  # the oldest went first
    assert again is not first
    np.testing.assert_array_equal(again, first)
    long = np.random.default_rng(1).standard_normal(1500)  # longer than the budget: not kept
    assert level_series(long, 1.0, 100.0) is not level_series(long, 1.0, 100.0)
    assert levels._RECENT == []


def test_level_series_recognises_an_unpickled_record(monkeypatch):
    # such a record (a worker's) is passed through as_signal again and again: the cache holds
    import pickle

    from fosmodel.core import levels
    from fosmodel.core.validation import as_signal

    monkeypatch.setattr(levels, "_RECENT", [])
    y = pickle.loads(pickle.dumps(np.random.default_rng(2).standard_normal(300)))
    first = level_series(as_signal(y, "y"), 1.0, 100.0)
    assert level_series(as_signal(y, "y"), 1.0, 100.0) is first
    assert level_series(y, 1.0, 100.0) is first
