"""A model with a compensation: its terms fit the output minus a known driver part."""

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel
from fosmodel.core.derived import derive, lowpass_name, power_name
from fosmodel.core.exceptions import InputError

RATE, N = 10.0, 20_000
TEMP = "Die temp (C)"


def _record(seed=0):
    rng = np.random.default_rng(seed)
    temp = 20 + 5 * np.sin(2 * np.pi * np.arange(N) / N) + 0.01 * rng.standard_normal(N)
    lag = derive(lowpass_name(TEMP, 50), N, RATE, {TEMP: temp}, {})
    noise = lfilter([1.0], [1.0, -0.7], rng.standard_normal(N)) * 0.05
    walk = np.cumsum(rng.standard_normal(N)) * 0.002
    return 1.0 + 0.04 * (lag - 20) + 0.003 * (lag - 20) ** 2 + noise + walk, {TEMP: temp}


COMP = {power_name(TEMP, 1, 20.0, tau_s=50): 0.04, power_name(TEMP, 2, 20.0, tau_s=50): 0.003}


def test_the_terms_model_the_output_minus_the_compensation():
    y, channels = _record()
    comp = sum(w * derive(name, N, RATE, channels, {}) for name, w in COMP.items())
    model = FOSModel(max_lag=3, levels=[20.0], rate=RATE, compensation=COMP).fit(y, channels)
    plain = FOSModel(max_lag=3, levels=[20.0], rate=RATE).fit(y - comp)
    assert model.terms_ == plain.terms_
    np.testing.assert_allclose(model.coef_, plain.coef_, rtol=1e-10)
    np.testing.assert_allclose(model.predict(y, channels), plain.predict(y - comp) + comp,
                               rtol=0, atol=1e-10)
    starts = np.array([500, 7000, 15000])
    runs = model.free_runs(y, starts, 400, channels)
    for row, s in zip(runs, starts):
        np.testing.assert_allclose(
            row, model.simulate(y[:s], 400, {TEMP: channels[TEMP][: s + 400]}), atol=1e-9)
        np.testing.assert_allclose(row, plain.simulate(y[:s] - comp[:s], 400) + comp[s:s + 400],
                                   atol=1e-9)
    assert model.input_columns() == [TEMP]
    back = FOSModel.from_dict(model.to_dict())
    np.testing.assert_allclose(back.predict(y, channels), model.predict(y, channels), atol=1e-12)
    assert "Compensation" in str(model.summary())


def test_refit_weights_keeps_the_compensation_and_follows_the_reference_correlations():
    y, channels = _record(1)
    for compensation in (None, COMP):
        fast = FOSModel(max_lag=3, levels=[20.0], rate=RATE, compensation=compensation)
        fast.fit(y, channels)
        reference = FOSModel(**{**fast.get_params(), "correlations": "reference"})
        reference.fit(y, channels)
        a = fast.refit_weights(y[:8000], {TEMP: channels[TEMP][:8000]})
        b = reference.refit_weights(y[:8000], {TEMP: channels[TEMP][:8000]})
        assert a.compensation == b.compensation == compensation
        np.testing.assert_allclose(a.coef_, b.coef_, rtol=1e-8)


def test_reference_refit_reads_the_candidate_matrix(monkeypatch):
    import fosmodel.models.model as module

    y, _ = _record(2)
    model = FOSModel(max_lag=3, correlations="reference").fit(y)
    used = []
    monkeypatch.setattr(module, "LagCorrelations", lambda *a, **k: used.append(1))
    model.refit_weights(y[:5000])  # would fail if it built the fast tables
    assert not used


def test_a_bad_compensation_is_refused_in_one_line():
    y, channels = _record()
    with pytest.raises(InputError, match="compensation column 'temp' is not one fosmodel can"):
        FOSModel(compensation={"temp": 1.0}).fit(y, channels)
    with pytest.raises(InputError, match="must be a finite number, got nan"):
        FOSModel(rate=RATE, compensation={lowpass_name(TEMP, 5): float("nan")}).fit(y, channels)
    with pytest.raises(InputError, match=r"needs the channel 'Die temp \(C\)'"):
        FOSModel(rate=RATE, compensation=COMP).fit(y)


def test_a_compensated_model_exports_its_compensation_as_the_feedthrough():
    from fosmodel.filter.statespace import to_state_space

    y, channels = _record()
    model = FOSModel(max_lag=2, rate=RATE, compensation=COMP).fit(y, channels)
    ss = to_state_space(model)
    u = ss.input_matrix(channels, N)
    comp = sum(w * derive(name, N, RATE, channels, {}) for name, w in COMP.items())
    np.testing.assert_allclose(u @ ss.D[0], comp, rtol=0, atol=1e-9)
    assert ss.mu == pytest.approx(model.offsets_["y"])


def test_held_weights_are_least_squares_with_the_level_and_lags_summing_to_one():
    """refit_weights(hold=True) against the constrained least squares of the term matrix."""
    from fosmodel.core.candidates import Term, evaluate_terms
    from fosmodel.core.levels import level_series

    rng = np.random.default_rng(7)
    n = 20_000
    y = (lfilter([1.0], [1.0, -0.6], rng.standard_normal(n)) * 0.05
         + np.cumsum(rng.standard_normal(n)) * 0.0001)
    model = FOSModel(max_lag=3, levels=[30.0, 100.0], rate=RATE).fit(y)
    levels = {name: level_series(y, float(name[6:-1]), RATE) for name in model.spec_.level_names}
    held = model.refit_weights(y, levels, hold=True)
    assert held.terms_ == model.terms_ and any(t.startswith("level@") for t in held.terms_)
    assert sum(held.coef_) == pytest.approx(1.0, abs=1e-9)  # every term is a lag or a level
    # the reference: least squares of the centred terms under the constraint, by KKT
    mu = model.offsets_["y"]
    signals = {"y": y - mu, **{k: v - mu for k, v in levels.items()}}
    x = evaluate_terms([Term.parse(t) for t in held.terms_], signals, model.lag_window_)
    target = (y - mu)[model.lag_window_:]
    xc, tc = x - x.mean(axis=0), target - target.mean()
    k = x.shape[1]
    kkt = np.block([[xc.T @ xc, np.ones((k, 1))], [np.ones((1, k)), np.zeros((1, 1))]])
    w = np.linalg.solve(kkt, np.r_[xc.T @ tc, 1.0])[:k]
    np.testing.assert_allclose(held.coef_, w, rtol=1e-7, atol=1e-10)
    assert held.intercept_ == pytest.approx(target.mean() - x.mean(axis=0) @ w, abs=1e-10)
    assert sum(model.coef_) < 0.99  # least squares alone weighs the weak wander too little
