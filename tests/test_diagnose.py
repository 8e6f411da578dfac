"""Each residual test: agreement with references, detection, and its false-alarm rate."""

import numpy as np
import pytest
from scipy import stats
from scipy.signal import lfilter, lombscargle

from fosmodel.core.fos import fos
from fosmodel.loop import diagnose as dg

RATE = 100.0


def _white(n, seed):
    return np.random.default_rng(seed).standard_normal(n)


def _time(n):
    return np.arange(n) / RATE


def _false_alarm_bound(trials, alpha):
    """Upper end of what a test at level alpha may fire in `trials` (binomial, about 4 sd)."""
    return trials * alpha + 4 * np.sqrt(trials * alpha * (1 - alpha)) + 1


def test_least_squares_spectrum_equals_scipy_lomb_scargle():
    n = 600
    t = _time(n)
    x = _white(n, 0) + 0.3 * np.sin(2 * np.pi * 3.07 * t) + 5.0
    freqs, s = dg.least_squares_spectrum(x, RATE)
    ref = lombscargle(t, x, 2 * np.pi * freqs, normalize=True, floating_mean=True)
    np.testing.assert_allclose(s, ref, rtol=1e-10, atol=1e-14)


def test_closed_form_sinusoid_correlations_equal_explicit_sums():
    n, t0 = 777, 3.21
    time = t0 + np.arange(n) / RATE
    omega = 2 * np.pi * np.array([0.5, 7.31, 7.31, 7.33, 49.9, 49.9])
    phase = np.array([0.0, 0.3, 1.2, 2.0, 0.0, np.pi / 2])
    cols = np.cos(np.outer(time, omega) + phase)
    x = _white(n, 11)
    corr = dg._SinusoidCorrelations(omega, phase, t0, 1 / RATE, n, cols.T @ x / n, x @ x / n)
    np.testing.assert_allclose(corr.means, cols.mean(axis=0), atol=1e-12)
    np.testing.assert_allclose(corr.diag, (cols**2).mean(axis=0), atol=1e-12)
    for j in range(len(omega)):
        np.testing.assert_allclose(corr.column(j), cols.T @ cols[:, j] / n, atol=1e-12)


def test_refine_frequency_is_the_fos_choice_between_bins():
    n = 20000
    t = _time(n)
    x = 0.2 * np.cos(2 * np.pi * 7.3137 * t + 0.7) + 0.5 * _white(n, 1)
    f0 = round(7.3137 * n / RATE) * RATE / n  # nearest FFT bin
    f = dg.refine_frequency(x, t, f0, RATE)
    assert abs(f - 7.3137) < 0.05 * RATE / n  # a twentieth of a bin
    # the same choice as FOS over the explicit candidate matrix
    grid = f0 + np.arange(-1, 1.01, 0.02) * RATE / n
    phases = np.arange(16) * np.pi / 16
    cols = np.column_stack([np.cos(2 * np.pi * fr * t + p) for fr in grid for p in phases])
    first = fos(cols, x, max_terms=1, stop="max_terms").support[0]
    assert f == pytest.approx(grid[first // 16], abs=1e-12)


@pytest.mark.parametrize("block", [1000, 4096, 2**20])  # a short last block; one pass
def test_zoom_sums_by_blocks_equal_the_point_by_point_sums(monkeypatch, block):
    n = 20_011
    x = 0.2 * np.cos(2 * np.pi * 7.3137 * _time(n)) + _white(n, 3)
    grid = 7.3 + np.arange(-1, 1.01, 0.1) * RATE / n
    monkeypatch.setattr(dg, "ZOOM_BLOCK", block)
    direct = np.exp(-2j * np.pi * np.outer(grid, np.arange(n)) / RATE) @ x
    np.testing.assert_allclose(dg._zoom(x, grid, RATE), direct, rtol=0,
                               atol=1e-10 * np.abs(direct).max())  # phases of ~1e4 rad


def test_refine_frequency_by_blocks_makes_the_same_choice(monkeypatch):
    n = 20000
    t = _time(n) + 3.0  # a record that does not start at 0
    x = 0.2 * np.cos(2 * np.pi * 7.3137 * t + 0.7) + 0.5 * _white(n, 1)
    f0 = round(7.3137 * n / RATE) * RATE / n
    whole = dg.refine_frequency(x, t, f0, RATE)
    monkeypatch.setattr(dg, "ZOOM_BLOCK", 3000)
    assert dg.refine_frequency(x, t, f0, RATE) == whole


def test_periodic_finds_an_off_grid_sinusoid_and_stays_quiet_on_white_noise():
    n = 20000
    t = _time(n)
    found = dg.periodic(0.05 * np.cos(2 * np.pi * 7.3137 * t) + 0.5 * _white(n, 2), t, RATE)
    assert found.fired and abs(found.evidence["freq_hz"] - 7.3137) < 0.001
    fires = sum(dg.periodic(_white(4000, s), _time(4000), RATE, alpha=0.05).fired
                for s in range(100))
    assert fires <= _false_alarm_bound(100, 0.05)


def test_aux_finds_channel_and_lag_and_respects_its_level_with_slow_channels():
    rng = np.random.default_rng(3)
    n = 20000
    x = lfilter([1.0], [1.0, -0.6], rng.standard_normal(n))
    r = 0.1 * np.r_[np.zeros(3), x[:-3]] + rng.standard_normal(n)
    found = dg.aux_correlation(r, {"accel": x, "temp": np.cumsum(rng.standard_normal(n))})
    assert found[0].fired and found[0].evidence["lag"] == 3
    assert not found[1].fired
    # a slowly wandering channel against a residual that is not quite white
    fires = 0
    for seed in range(100):
        g = np.random.default_rng(seed)
        resid = lfilter([1.0], [1.0, -0.3], g.standard_normal(4000))
        temp = np.cumsum(g.standard_normal(4000)) + 20
        fires += dg.aux_correlation(resid, {"temp": temp}, alpha=0.05)[0].fired
    assert fires <= _false_alarm_bound(100, 0.05)


def test_nonlinearity_reset():
    rng = np.random.default_rng(4)
    n = 20000
    y = lfilter([1.0], [1.0, -0.5], rng.standard_normal(n))
    lagged = np.column_stack([np.r_[np.zeros(k), y[:-k]] for k in range(1, 5)])
    r = 0.1 * lagged[:, 0] * lagged[:, 1] + rng.standard_normal(n)
    found = dg.nonlinearity(r, lagged)
    assert found.fired and found.evidence["strongest"] == "y[n-1]*y[n-2]"
    fires = 0
    for seed in range(100):
        g = np.random.default_rng(100 + seed)
        yy = lfilter([1.0], [1.0, -0.5], g.standard_normal(3000))
        lag = np.column_stack([np.r_[np.zeros(k), yy[:-k]] for k in range(1, 5)])
        fires += dg.nonlinearity(g.standard_normal(3000), lag, alpha=0.05).fired
    assert fires <= _false_alarm_bound(100, 0.05)


def test_nonlinearity_in_blocks_matches_one_pass(monkeypatch):
    # long records accumulate the Gram matrix over blocks: force it, blocks of 37 rows
    rng = np.random.default_rng(5)
    y = lfilter([1.0], [1.0, -0.5], rng.standard_normal(5000))
    lagged = np.column_stack([np.r_[np.zeros(k), y[:-k]] for k in range(1, 5)])
    r = 0.05 * lagged[:, 0] * lagged[:, 2] + rng.standard_normal(5000)
    one_pass = dg.nonlinearity(r, lagged)
    monkeypatch.setattr(dg, "BLOCKED_ROWS", 0)
    monkeypatch.setattr(dg, "BLOCK", 37)
    blocked = dg.nonlinearity(r, lagged)
    assert blocked.statistic == pytest.approx(one_pass.statistic, rel=1e-9)
    assert blocked.p_value == pytest.approx(one_pass.p_value, rel=1e-6)
    assert blocked.evidence == one_pass.evidence == {
        "products": 10, "max_lag": 4, "strongest": "y[n-1]*y[n-3]"}
    for key in ("product", "mean_residual"):  # the figure's bin means of the strongest product
        np.testing.assert_allclose(blocked.plot[key], one_pass.plot[key], rtol=1e-12, atol=1e-12)


def test_plot_arrays_are_short_on_a_long_residual():
    # a finding keeps at most PLOT_POINTS values per array (one per second for the slow part)
    n, rate = 3 * dg.PLOT_POINTS + 7, 100.0
    t = np.arange(n) / rate
    r = _white(n, 3) + 0.01 * t
    lagged = np.column_stack([np.r_[np.zeros(k), r[:-k]] for k in range(1, 3)])
    found = [dg.periodic(r, t, rate), dg.trend(r, t), dg.change_point(r, t),
             dg.nonlinearity(r, lagged)]
    for f in found:
        for key, value in f.plot.items():
            if key in ("second", "mean"):
                assert len(value) == n // 100
            else:
                assert len(value) <= dg.PLOT_POINTS, (f.test, key)
    trend, step = found[1].plot, found[2].plot
    np.testing.assert_array_equal(step["time"], t[::4])
    np.testing.assert_allclose(step["cusum"], np.cumsum(r - r.mean())[::4], rtol=1e-9)
    np.testing.assert_allclose(trend["mean"], r[: n // 100 * 100].reshape(-1, 100).mean(axis=1))
    np.testing.assert_array_equal(trend["second"], t[: n // 100 * 100 : 100])
    freqs, s = dg.least_squares_spectrum(r, rate)
    np.testing.assert_allclose(found[0].plot["spectrum"],
                               s[: len(s) // 2 * 2].reshape(-1, 2).mean(axis=1))
    assert len(found[0].plot["freqs"]) == len(s) // 2


def test_thinning_helpers_against_their_definitions():
    x = np.arange(10.0)
    np.testing.assert_array_equal(dg.thinned(x, 4), [0.0, 3.0, 6.0, 9.0])
    np.testing.assert_array_equal(dg.thinned(x, 20), x)
    np.testing.assert_array_equal(dg.block_means(x, 4), [1.0, 4.0, 7.0])
    np.testing.assert_array_equal(dg.block_means(x, 10), x)
    assert not np.shares_memory(dg.thinned(x, 4), x)
    centres, means = dg.bin_means(np.r_[np.zeros(5), np.ones(5)], x, bins=4)
    np.testing.assert_array_equal(centres, [0.0, 1.0])
    np.testing.assert_array_equal(means, [2.0, 7.0])


@pytest.mark.parametrize("shape, form", [("linear", "linear"), ("warmup", "exponential")])
def test_trend_detects_and_names_the_form(shape, form):
    n = 20000
    t = _time(n)
    drift = 0.002 * t if shape == "linear" else 0.3 * (1 - np.exp(-t / 30.0))
    found = dg.trend(drift + _white(n, 5), t)
    assert found.fired and found.evidence["form"] in (form, "linear+exponential")
    if shape == "warmup":
        assert 15 < found.evidence["tau_s"] < 60


@pytest.mark.parametrize("shape", ["linear", "warmup", "quadratic"])
def test_trend_curve_is_the_least_squares_fit_of_its_form(shape):
    # the curve (evidence "range", figure) against numpy's lstsq with the constant column
    n = 20000
    t = _time(n)
    slow = {"linear": 0.002 * t, "warmup": 0.3 * (1 - np.exp(-t / 30.0)),
            "quadratic": 1e-6 * (t - 40.0) ** 2}[shape]
    r = slow + _white(n, 6)
    found = dg.trend(r, t)
    form, tau = found.evidence["form"], None
    cols = [np.ones(n)]
    if form in ("linear", "quadratic", "linear+exponential"):
        cols.append(t - t[0])
    if form == "quadratic":
        cols.append((t - t[0]) ** 2)
    if "exponential" in form:
        span = t[-1] - t[0]
        taus = np.geomspace(span / 50, span, 30)  # the scan's grid: which one won
        fits = [np.linalg.lstsq(np.column_stack([*cols, np.exp(-(t - t[0]) / k)]), r,
                                rcond=None) for k in taus]
        tau = taus[int(np.argmin([f[1][0] for f in fits]))]
        cols.append(np.exp(-(t - t[0]) / tau))
    a = np.column_stack(cols)
    curve = a @ np.linalg.lstsq(a, r, rcond=None)[0]
    assert found.evidence["range"] == pytest.approx(np.ptp(curve), rel=1e-9)
    np.testing.assert_allclose(found.plot["fit"], curve, rtol=1e-9, atol=1e-12)  # 20,000: all


def test_trend_and_step_false_alarms_on_white_noise():
    t = _time(3000)
    trend_fires = step_fires = 0
    for seed in range(100):
        x = _white(3000, 200 + seed)
        trend_fires += dg.trend(x, t, alpha=0.05).fired
        step_fires += dg.change_point(x, t, alpha=0.05).fired
    assert trend_fires <= _false_alarm_bound(100, 0.05)
    assert step_fires <= _false_alarm_bound(100, 0.05)


def test_change_point_locates_a_step():
    n = 20000
    t = _time(n)
    found = dg.change_point(_white(n, 6) + 0.1 * (t >= 123.4), t)
    assert found.fired and abs(found.evidence["time_s"] - 123.4) < 5.0
    assert found.evidence["shift"] == pytest.approx(0.1, abs=0.03)


def test_allan_flags_a_random_walk_and_not_white_noise():
    n = 30000
    white = dg.allan(_white(n, 7), RATE)
    assert not white.fired and white.evidence["slope"] == pytest.approx(-0.5, abs=0.2)
    walk = dg.allan(_white(n, 7) + np.cumsum(_white(n, 8)) * 0.02, RATE)
    assert walk.fired and walk.evidence["slope"] > 0


def test_whiteness_ljung_box():
    from statsmodels.stats.diagnostic import acorr_ljungbox

    x = lfilter([1.0], [1.0, -0.05], _white(3000, 12))
    ref = acorr_ljungbox(x, lags=[20], return_df=True)
    found = dg.whiteness(x)
    assert found.statistic == pytest.approx(float(ref["lb_stat"].iloc[0]), rel=1e-9)
    assert found.p_value == pytest.approx(float(ref["lb_pvalue"].iloc[0]), rel=1e-6)
    assert not dg.whiteness(_white(5000, 9)).fired
    colored = lfilter([1.0], [1.0, -0.2], _white(5000, 9))
    assert dg.whiteness(colored).fired


def test_finding_serialises():
    f = dg.whiteness(_white(1000, 10))
    d = f.to_dict()
    assert set(d) == {"test", "statistic", "p_value", "alpha", "fired", "evidence"}
    assert d["fired"] is False and isinstance(d["p_value"], float)


def test_change_point_does_not_take_a_wander_for_a_step():
    """The residual a level leaves beside it: white noise and a Gauss-Markov wander of 30
    samples.  A kernel long-run variance over 15 lags misses the wander and fired on 25 of
    these 50 records at 0.001; batch means see it, and a true step still fires."""
    n, t = 6000, _time(6000)
    fired = 0
    for seed in range(50):
        rng = np.random.default_rng(500 + seed)
        x = rng.standard_normal(n) + lfilter([0.3], [1, -np.exp(-1 / 30)], rng.standard_normal(n))
        fired += dg.change_point(x, t).fired
        if seed == 0:
            stepped = dg.change_point(x + 3.0 * (t >= 40.0), t)
            assert stepped.fired and stepped.evidence["time_s"] == pytest.approx(40.0, abs=0.5)
    assert fired <= 1


def test_the_step_test_p_value_counts_the_variance_estimate():
    """With the long-run variance from 30 batches the tail is wider than Kolmogorov's."""
    assert dg._bridge_sf(1.95, 29) > stats.kstwobign.sf(1.95)
    assert dg._bridge_sf(1.95, 10**6) == pytest.approx(stats.kstwobign.sf(1.95), rel=1e-3)


def test_mean_stability_fires_on_a_wandering_mean_and_not_on_white_noise():
    """The level's test: a random walk under white noise wanders; white noise does not."""
    n = 10000
    walk = np.cumsum(0.01 * _white(n, 9)) + _white(n, 10)
    found = dg.mean_stability(walk)
    assert found.test == "wander" and found.fired
    fired = sum(dg.mean_stability(_white(3000, 300 + seed), alpha=0.05).fired
                for seed in range(100))
    assert fired <= _false_alarm_bound(100, 0.05)


def test_change_point_does_not_take_a_slow_bias_instability_for_a_step():
    """A Gauss-Markov wander of 300 s (a tenth of the record, ten batches) beside white
    noise: batch means alone took it for a step on 40 of these 100 records at 0.001; with
    their lag-one correlation counted where it is beyond chance, 10.  A step five times the
    wander's spread still fires on all, and a white record's step loses no power."""
    n, t = 30000, np.arange(30000) / 10.0
    fired = stepped = 0
    for seed in range(100):
        rng = np.random.default_rng(900 + seed)
        x = rng.standard_normal(n) + lfilter([0.02], [1, -np.exp(-1 / 3000)],
                                             rng.standard_normal(n))
        fired += dg.change_point(x, t).fired
        if seed < 20:
            stepped += dg.change_point(x + 4.0 * (t >= 1000.0), t).fired
    assert fired <= 12
    assert stepped == 20
    white = [dg.change_point(_white(n, 40 + s) + 0.3 * (t >= 1000.0), t) for s in range(10)]
    assert all(f.fired and abs(f.evidence["time_s"] - 1000.0) < 60 for f in white)


def test_the_step_test_widens_its_variance_by_the_batch_correlation():
    """The factor is (1 + phi) / (1 - phi) of the batch means' lag-one correlation,
    clipped to 0.9 and taken as 0 within chance (1.96 / sqrt(30)): checked by hand on batch
    means that oscillate slowly (phi 0.8), that are half a cosine (phi beyond the clip),
    that alternate (phi below 0) and that oscillate fast (phi 0.23, within chance)."""
    def batched(means: np.ndarray) -> np.ndarray:
        return np.repeat(means, 10)

    means = np.sin(2 * np.pi * np.arange(30) / 10)
    phi = float(means[1:] @ means[:-1] / (means @ means))
    assert 0.7 < phi < 0.85
    lrv, batches = dg._batch_variance(batched(means))
    assert batches == 30
    assert lrv == pytest.approx(10 * float(means @ means) / 29 * (1 + phi) / (1 - phi))
    smooth = np.cos(np.pi * np.arange(30) / 29)
    assert dg._batch_variance(batched(smooth))[0] == pytest.approx(
        10 * float(smooth @ smooth) / 29 * 1.9 / 0.1)
    alternating = np.tile([1.0, -1.0], 15)
    assert dg._batch_variance(batched(alternating))[0] == pytest.approx(10 * 30 / 29)
    fast = np.sin(2 * np.pi * np.arange(30) / 30 * 6.3)
    weak = float(fast[1:] @ fast[:-1] / (fast @ fast))
    assert 0.0 < weak < 1.96 / np.sqrt(30)
    assert dg._batch_variance(batched(fast))[0] == pytest.approx(10 * float(fast @ fast) / 29)
