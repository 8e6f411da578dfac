"""Free runs (fosmodel.models.freerun): many at once against the sample-by-sample reference."""

import numpy as np
import pytest

from fosmodel.core.candidates import Term
from fosmodel.models import freerun
from fosmodel.models.freerun import run_many, run_one, split_expansion

#: Each nonlinear run is checked with the numba kernel (where the ``fast`` extra is installed)
#: and with the NumPy recursion.
PATHS = ["numba", "numpy"]


@pytest.fixture(params=PATHS)
def path(request, monkeypatch):
    if request.param == "numba":
        pytest.importorskip("numba", reason="the fast extra (numba) is not installed")
    else:
        monkeypatch.setattr(freerun, "_compiled_recursion", lambda: None)
    return request.param


def _expansion(names, coef, levels=(), intercept=0.1):
    return split_expansion([Term.parse(n) for n in names], coef, intercept, 3, levels, 100.0)


def test_split_puts_each_term_where_a_run_needs_it():
    ex = _expansion(["y[n-1]", "level@2s", "temp[n-0]", "y[n-2]*temp[n-1]", "level@2s^2"],
                    [0.5, 0.3, 0.2, 0.1, -0.05], levels=["level@2s"])
    np.testing.assert_array_equal(ex.phi, [0.5, 0.0, 0.0])
    np.testing.assert_array_equal(ex.weights, [0.3])
    assert ex.gains == pytest.approx([1 / 200])
    assert [(t.name, c) for t, c in ex.drive] == [("temp[n-0]", 0.2)]
    assert [(t.rest.name if t.rest else None, t.lags, t.levels) for t in ex.nonlinear] == [
        ("temp[n-1]", (2,), ()), (None, (), (0, 0))]


@pytest.mark.parametrize("nonlinear", [False, True])
def test_many_runs_equal_the_reference_row_by_row(nonlinear, path):
    rng = np.random.default_rng(3)
    names, coef = ["y[n-1]", "y[n-3]", "level@2s", "level@0.5s"], [0.6, -0.2, 0.25, 0.1]
    if nonlinear:
        names, coef = names + ["y[n-1]*level@2s", "y[n-2]*temp[n-0]"], coef + [0.05, 0.02]
    ex = _expansion(names, coef, levels=["level@0.5s", "level@2s"])
    k, steps = 6, 300
    past, levels = rng.standard_normal((k, 5)), rng.standard_normal((k, 2))
    drive = 0.1 + 0.01 * rng.standard_normal((k, steps))
    rests = [rng.standard_normal((k, steps)) if t.rest else None for t in ex.nonlinear]
    many = run_many(ex, past, levels, drive, rests)
    for i in range(k):
        one = run_one(ex, past[i], levels[i], drive[i], [r if r is None else r[i] for r in rests])
        np.testing.assert_allclose(many[i], one, rtol=1e-12, atol=1e-13)


def test_a_diverging_run_is_nan_from_its_first_non_finite_sample_on(path):
    ex = _expansion(["y[n-1]^2"], [3.0], intercept=0.0)
    past = np.array([[0.0, 0.0, 0.1], [0.0, 0.0, 10.0]])
    drive = np.zeros((2, 40))
    many = run_many(ex, past, np.zeros((2, 0)), drive, [None])
    assert np.isfinite(many[0]).all()  # 0.1 -> 0.03 -> ... shrinks
    first = np.flatnonzero(~np.isfinite(many[1]))[0]
    assert np.isnan(many[1, first:]).all() and np.isfinite(many[1, :first]).all()
    one = run_one(ex, past[1], np.zeros(0), drive[1], [None])
    np.testing.assert_array_equal(np.isnan(one), np.isnan(many[1]))


def test_the_compiled_recursion_equals_the_numpy_one(monkeypatch):
    pytest.importorskip("numba", reason="the fast extra (numba) is not installed")
    rng = np.random.default_rng(8)
    names = ["y[n-1]", "y[n-2]", "level@1s", "y[n-1]*y[n-2]", "y[n-3]*level@1s",
             "temp[n-1]*y[n-1]", "level@1s^2", "y[n-2]^2"]
    ex = _expansion(names, [0.5, -0.1, 0.2, 0.03, -0.02, 0.05, 0.01, -0.04], levels=["level@1s"])
    k, steps = 5, 2000
    past, levels = 0.5 * rng.standard_normal((k, 4)), rng.standard_normal((k, 1))
    drive = 0.05 * rng.standard_normal((k, steps))
    rests = [rng.standard_normal((k, steps)) if t.rest else None for t in ex.nonlinear]
    compiled = run_many(ex, past, levels, drive, rests)
    monkeypatch.setattr(freerun, "_compiled_recursion", lambda: None)
    np.testing.assert_allclose(compiled, run_many(ex, past, levels, drive, rests),
                               rtol=1e-12, atol=1e-14)


def test_fosmodel_numba_0_selects_the_numpy_recursion(monkeypatch):
    freerun._compiled_recursion.cache_clear()
    monkeypatch.setenv("FOSMODEL_NUMBA", "0")
    try:
        assert freerun._compiled_recursion() is None
    finally:
        freerun._compiled_recursion.cache_clear()
