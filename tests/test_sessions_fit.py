"""A FOS model shared by sessions of one sensor, with a constant per session."""

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel
from fosmodel.core.exceptions import InputError
from fosmodel.models.sessions import fit_sessions, session_constant, within


def _sessions(seed=0, beta=0.03):
    """Three sessions whose turn-on biases grow with their mean temperatures."""
    rng = np.random.default_rng(seed)
    ys, exogs, biases = [], [], (0.0, 0.5, 1.0)
    for k, bias in enumerate(biases):
        n = 6000
        temp = 10 + 5 * k + 3 * np.sin(np.arange(n) / 500 + k)
        noise = lfilter([1.0], [1.0, -0.5], rng.standard_normal(n)) * 0.05
        ys.append(bias + beta * temp + noise)
        exogs.append({"temp": temp})
    return ys, exogs, biases


def test_sessions_with_free_constants_reproduce_a_known_shared_sensitivity():
    ys, exogs, biases = _sessions()
    model, constants = fit_sessions(FOSModel(max_lag=2, exog_lags={"temp": 0}), ys, exogs)
    weights = dict(zip(model.terms_, model.coef_))
    # the one-step model y = a y[n-1] + b temp + c: the sensitivity is b / (1 - a)
    a = weights.get("y[n-1]", 0.0) + weights.get("y[n-2]", 0.0)
    assert weights["temp[n-0]"] / (1 - a) == pytest.approx(0.03, rel=0.05)
    # each session's constant is its own: the differences of the turn-on biases, shrunk by
    # the output's own weights as a one-step constant is
    np.testing.assert_allclose(np.diff(constants) / (1 - a), np.diff(biases), atol=0.02)
    for y, e, c in zip(ys, exogs, constants):
        assert session_constant(model.shifted(c), y, e, slice(0, len(y))) == pytest.approx(
            0.0, abs=1e-9)
    # one fit of every sample as one record takes the biases for temperature
    pooled = FOSModel(max_lag=2, exog_lags={"temp": 0}).fit(
        np.concatenate(ys), {"temp": np.concatenate([e["temp"] for e in exogs])})
    pooled_weights = dict(zip(pooled.terms_, pooled.coef_))
    pooled_a = pooled_weights.get("y[n-1]", 0.0) + pooled_weights.get("y[n-2]", 0.0)
    assert pooled_weights.get("temp[n-0]", 0.0) / (1 - pooled_a) > 0.05


def test_within_and_the_refusals():
    x = np.arange(10.0)
    np.testing.assert_array_equal(within(x, [slice(0, 4), slice(4, 10)]),
                                  np.r_[x[:4] - 1.5, x[4:] - 6.5])
    ys, exogs, _ = _sessions()
    with pytest.raises(InputError, match="a fit over sessions needs at least one"):
        fit_sessions(FOSModel(max_lag=2), [], [])
    with pytest.raises(InputError, match="the sessions' channels differ: temp against hum"):
        fit_sessions(FOSModel(max_lag=2), ys[:2], [exogs[0], {"hum": exogs[1]["temp"]}])


def test_a_level_models_session_constant_leaves_its_free_runs_still():
    """A model whose level follows the output carries a session's turn-on bias in that level.

    Its constant from a new session's first 600 samples must not drift its free runs: the
    mean one-step residual there is mostly white noise, and a level held to sum to one
    would turn it into a ramp over every outage.
    """
    rng = np.random.default_rng(3)

    def session(bias, n=20_000):
        return bias + np.cumsum(rng.normal(0, 0.002, n)) + rng.normal(0, 1.0, n)

    ys = [session(b) for b in (0.0, 5.0, -3.0)]
    model, _ = fit_sessions(FOSModel(max_lag=2, levels=[20, 60], rate=1.0), ys,
                            [None] * 3, hold=True)
    new = session(8.0)
    shifted = model.shifted(session_constant(model, new, None, slice(0, 600)))
    starts = np.arange(600, 18_000, 1800)
    biases = (new[starts[:, None] + np.arange(1800)]
              - shifted.free_runs(new, starts, 1800)).mean(axis=1)
    assert np.sqrt(np.mean(biases**2)) < 0.4
