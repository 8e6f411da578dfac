"""Before/after ratios and their intervals: coverage on records of known models."""

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel.loop.intervals import lag_window, ratio, ratio_interval

REPLICATES = 200
#: A 95 % interval covers 190 of 200 on average; binomially 95 % +- 3 sd is 180-200 (the
#: sd of the count is sqrt(200 0.95 0.05) = 3.1), so coverage below 0.90 is a fault.
LOWEST = 0.90


def _ar1(rng, n, phi):
    return lfilter([np.sqrt(1 - phi**2)], [1.0, -phi], rng.standard_normal(n + 200))[200:]


@pytest.mark.parametrize("windows, phi, scale", [(60, 0.0, 0.8), (60, 0.5, 0.8), (200, 0.5, 1.0),
                                                 (100, 0.3, 1.2)])
def test_the_interval_covers_the_true_ratio_of_correlated_windows(windows, phi, scale):
    """Window errors of two models that share a slow, correlated error: ``b = s a + e``.

    ``E[b^2] / E[a^2] = s^2 + var(e)``, with ``var(a) = 1`` and ``e`` an independent AR(1) of
    variance 0.25.
    """
    rng = np.random.default_rng(windows)
    truth = scale**2 + 0.25
    hits = 0
    for _ in range(REPLICATES):
        a = _ar1(rng, windows, phi)
        b = scale * a + 0.5 * _ar1(rng, windows, phi)
        _, low, high = ratio_interval(a, b, 0.95)
        hits += low <= truth <= high
    assert LOWEST <= hits / REPLICATES <= 1.0


def test_the_interval_covers_the_one_step_mse_ratio_of_two_known_predictors():
    """An AR(1) record predicted by its own coefficient and by a wrong one.

    The true ratio of the one-step MSEs is ``1 + (phi - phi')^2 / (1 - phi^2)``.
    """
    rng = np.random.default_rng(1)
    phi, wrong, n = 0.6, 0.45, 3000
    truth = 1 + (phi - wrong) ** 2 / (1 - phi**2)
    hits = 0
    for _ in range(REPLICATES):
        y = lfilter([1.0], [1.0, -phi], rng.standard_normal(n + 100))[100:]
        right, off = y[1:] - phi * y[:-1], y[1:] - wrong * y[:-1]
        found = ratio("one-step MSE", "mse", right, off, 0.95)
        hits += found.low <= truth <= found.high
    assert LOWEST <= hits / REPLICATES <= 1.0


def test_a_slow_shared_error_widens_the_interval_as_it_should():
    rng = np.random.default_rng(3)
    slow, white = _ar1(rng, 100, 0.9), rng.standard_normal(100)
    assert lag_window(slow - slow.mean()) > lag_window(white - white.mean()) == 1
    wide = ratio_interval(slow, 0.8 * slow + 0.3 * _ar1(rng, 100, 0.9), 0.95)
    narrow = ratio_interval(white, 0.8 * white + 0.3 * rng.standard_normal(100), 0.95)
    assert wide[2] / wide[1] > narrow[2] / narrow[1]
