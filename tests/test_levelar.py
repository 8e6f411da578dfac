"""Baselines about the local level (fosmodel.models.levelar) against a hand-written recursion."""

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel.core.exceptions import InputError
from fosmodel.core.levels import level_series
from fosmodel.models.baselines import ARModel, GaussMarkovModel
from fosmodel.models.levelar import LocalLevelAR

RATE, TAU = 100.0, 5.0


def _record(n=20_000, seed=0):
    rng = np.random.default_rng(seed)
    return (lfilter([1.0], [1.0, -0.6, 0.1], rng.standard_normal(n)) * 0.3
            + np.cumsum(rng.standard_normal(n)) * 0.01 + 2.0)


def _by_hand(model, y, start, steps):
    """The recursion with the level fed the model's own output."""
    phi, mu, a, p = model.base.coef_, model.base.mean_, 1 / (TAU * RATE), len(model.base.coef_)
    out, level = list(y[:start]), list(level_series(y[:start], TAU, RATE))
    level.append((1 - a) * level[-1] + a * out[-1])
    for _ in range(steps):
        n = len(out)
        v = level[n] + mu + sum(phi[k] * (out[n - 1 - k] - level[n - 1 - k] - mu)
                                for k in range(p))
        out.append(v)
        level.append((1 - a) * level[-1] + a * v)
    return np.array(out[start:])


@pytest.mark.parametrize("base", [ARModel(3, "burg"), GaussMarkovModel(RATE)])
def test_predictions_and_free_runs_follow_the_level(base):
    y = _record()
    model = LocalLevelAR(base, TAU, RATE).fit(y[:10_000])
    level = level_series(y, TAU, RATE)
    d = y[:10_000] - level[:10_000]
    assert model.base.mean_ == pytest.approx(d[1:].mean())
    pred = model.predict(y)
    phi, mu, p = model.base.coef_, model.base.mean_, model.lag_window_
    n = 7000
    expected = level[n] + mu + sum(phi[k] * (y[n - 1 - k] - level[n - 1 - k] - mu)
                                   for k in range(p))
    assert pred[n] == pytest.approx(expected, abs=1e-12) and np.isnan(pred[: p]).all()
    runs = model.free_runs(y, [5000, 12_000], 300)
    for row, start in zip(runs, (5000, 12_000)):
        np.testing.assert_allclose(row, _by_hand(model, y, start, 300), rtol=0, atol=1e-11)
    np.testing.assert_allclose(model.simulate(y[:5000], 300), runs[0], rtol=0, atol=1e-11)
    assert model.n_terms_ == p + 1 and model.is_stable()


def test_a_level_of_less_than_one_sample_is_refused():
    with pytest.raises(InputError, match="shorter than one sample"):
        LocalLevelAR(ARModel(2), 0.001, RATE)
