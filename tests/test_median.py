"""The fast exact median against numpy.median, bit for bit."""

import numpy as np
import pytest

from fosmodel.core import median as median_module
from fosmodel.core.median import median

N = 300_001  # above the size numpy.median answers directly

rng = np.random.default_rng(3)
CASES = {
    "normal odd": rng.normal(size=N),
    "normal even": rng.normal(size=N + 1),
    "few distinct values": rng.integers(0, 4, N).astype(float),
    "constant": np.full(N, 2.5),
    "ascending": np.arange(N, dtype=float),
    "descending": np.arange(N + 1, dtype=float)[::-1],
    "heavy tails": rng.standard_cauchy(N),
    "a bias step": np.concatenate([np.zeros(N // 2), np.ones(N // 2 + 2)]),
    "integers": rng.integers(-1000, 1000, N),
    "strided view": rng.normal(size=2 * N)[::2],
    "short": rng.normal(size=101),
    "short even": rng.normal(size=100),
}


@pytest.mark.parametrize("name", CASES)
def test_equals_numpy(name):
    x = CASES[name]
    before = x.copy()
    assert median(x) == float(np.median(x))
    np.testing.assert_array_equal(x, before)


def test_nan_and_empty_as_numpy():
    x = rng.normal(size=N)
    x[1234] = np.nan
    assert np.isnan(median(x))
    assert np.isnan(median(np.empty(0)))


@pytest.mark.parametrize("bracket", [(5.0, 6.0), (-6.0, -5.0), (0.0, 0.0)])
def test_a_bracket_that_misses_falls_back(monkeypatch, bracket):
    x = CASES["normal even"]
    monkeypatch.setattr(median_module, "_bracket", lambda _: bracket)
    assert median(x) == float(np.median(x))


def test_the_bracket_holds_the_middle_ranks():
    x = CASES["heavy tails"]
    lo, hi = median_module._bracket(x)
    below, inside = median_module._split(x, lo, hi)
    assert below < (N - 1) // 2 < below + inside.size
    assert below == np.count_nonzero(x < lo)
    np.testing.assert_array_equal(inside, x[(x >= lo) & (x <= hi)])
    assert inside.size < 0.05 * N  # only a few per cent is partitioned
