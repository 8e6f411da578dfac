"""The fast correlation path (tables with end corrections) against the point-by-point reference."""

import numpy as np
import pytest

from fosmodel.core import correlations, shapes
from fosmodel.core.candidates import CandidateSpec, evaluate_terms, generate_terms
from fosmodel.core.correlations import LagCorrelations
from fosmodel.core.fos import DataCorrelations

SPECS = [
    CandidateSpec(6, 1),
    CandidateSpec(4, 2, {"temp": 3}),
    CandidateSpec(3, 3, {"temp": 2}, columns=["sinf"]),
    CandidateSpec(0, 1, {"temp": 0}, columns=["sinf"]),
    CandidateSpec(8, 2, {"a": 8, "b": 0}),
]


@pytest.fixture
def one_column_at_a_time(monkeypatch):
    """Gram columns fetched one at a time, as for candidate sets too large to take at once."""
    monkeypatch.setattr(shapes, "_GRAM_ROWS", 0)
    shapes.gram_columns.cache_clear()
    yield
    shapes.gram_columns.cache_clear()


def _signals(n, seed):
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    return {
        "y": np.cumsum(rng.standard_normal(n)) * 0.1 + rng.standard_normal(n) + 3.0,
        "temp": 20 + 5 * np.exp(-t / 200) + 0.1 * rng.standard_normal(n),
        "a": rng.standard_normal(n),
        "b": rng.uniform(-1, 1, n),
        "sinf": np.sin(0.37 * t),
    }


def _assert_close(fast, ref, scale):
    np.testing.assert_allclose(fast, ref, rtol=1e-10, atol=1e-10 * scale)


def _scale(ref):
    return float(np.max(np.abs(ref.diag))) + ref.y_mean_sq


def _assert_matches(fast, ref):
    """Every mean the search reads and every Gram column equal to the reference's."""
    scale = _scale(ref)
    assert fast.n_samples == ref.n_samples
    for name in ("y_mean", "y_mean_sq", "means", "target", "diag"):
        _assert_close(getattr(fast, name), getattr(ref, name), scale)
    for j in range(len(ref.means)):
        _assert_close(fast.column(j), ref.column(j), scale)


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: f"L{s.max_lag}CP{s.degree}")
@pytest.mark.parametrize("table_degree", [0, 2, 3, 4])
@pytest.mark.parametrize("n", [None, 700])
def test_fast_path_matches_reference(spec, table_degree, n):
    n = n or spec.lag_window + 3  # also the shortest records, where the ends overlap
    signals = _signals(n, 1)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    fast = LagCorrelations(terms, signals, n0, table_degree=table_degree)
    ref = DataCorrelations(evaluate_terms(terms, signals, n0), signals["y"][n0:])
    _assert_matches(fast, ref)


@pytest.mark.parametrize("spec", [SPECS[1], SPECS[4]], ids=lambda s: f"L{s.max_lag}CP{s.degree}")
def test_blocked_weighted_gram_matches_reference(spec, monkeypatch, one_column_at_a_time):
    # long records take the blocked weighted Gram path: force it on a short one, with blocks
    # of a few samples so that block edges fall everywhere
    monkeypatch.setattr(correlations, "_GEMM_SAMPLES", 0)
    monkeypatch.setattr(correlations, "_CHUNK", 37)
    signals = _signals(400, 3)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    fast = LagCorrelations(terms, signals, n0, table_degree=3)
    ref = DataCorrelations(evaluate_terms(terms, signals, n0), signals["y"][n0:])
    scale = _scale(ref)
    calls = []
    blocked = LagCorrelations._weighted_gram_sums
    monkeypatch.setattr(LagCorrelations, "_weighted_gram_sums",
                        lambda self, *args: calls.append(1) or blocked(self, *args))
    for j in range(len(terms)):
        _assert_close(fast.column(j), ref.column(j), scale)
    assert calls  # the blocked path did run


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: f"L{s.max_lag}CP{s.degree}")
@pytest.mark.parametrize("table_degree", [0, 3])
def test_window_summed_in_blocks_matches_reference(spec, table_degree, monkeypatch):
    # windows over _BLOCKED_SAMPLES are summed in blocks of _BLOCK samples: force it on a
    # short one, with blocks shorter than the lags so that every product straddles block edges
    monkeypatch.setattr(correlations, "_BLOCKED_SAMPLES", 0)
    monkeypatch.setattr(correlations, "_BLOCK", 7)
    signals = _signals(150, 4)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    fast = LagCorrelations(terms, signals, n0, table_degree=table_degree)
    assert len(fast._blocks()) == -(-(150 - n0) // 7)
    ref = DataCorrelations(evaluate_terms(terms, signals, n0), signals["y"][n0:])
    _assert_matches(fast, ref)


def test_blocked_sums_select_the_same_terms_as_one_pass(monkeypatch):
    from fosmodel.models.model import FOSModel

    rng = np.random.default_rng(5)
    y = np.zeros(3000)
    e = rng.standard_normal(3000)
    for n in range(2, 3000):
        y[n] = 0.5 * y[n - 1] - 0.2 * y[n - 2] + 0.1 * y[n - 1] * y[n - 2] + e[n]
    kwargs = dict(max_lag=6, degree=2, max_terms=8, stop="max_terms")
    one_pass = FOSModel(**kwargs).fit(y)
    monkeypatch.setattr(correlations, "_BLOCKED_SAMPLES", 0)
    monkeypatch.setattr(correlations, "_BLOCK", 64)
    blocked = FOSModel(**kwargs).fit(y)
    assert blocked.terms_ == one_pass.terms_
    np.testing.assert_allclose(blocked.coef_, one_pass.coef_, rtol=1e-9)


def test_window_shorter_than_signal_start_uses_only_window_samples():
    # changing samples before the window start only matters through the lags
    spec = CandidateSpec(3, 2)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    signals = _signals(50, 2)
    a = LagCorrelations(terms, signals, 5)
    signals["y"] = signals["y"].copy()
    signals["y"][:2] = 1e3  # before n0 - L = 2: never read
    b = LagCorrelations(terms, signals, 5)
    np.testing.assert_array_equal(a.target, b.target)
    np.testing.assert_array_equal(a.column(4), b.column(4))


def test_pooled_segments_match_reference_on_the_stacked_windows():
    """Each segment keeps its own lag window: the pooled means are those of the stacked rows."""
    spec = SPECS[1]
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    signals = _signals(900, 2)
    pieces = [{k: v[s] for k, v in signals.items()} for s in (slice(0, 300), slice(340, 900))]
    fast = correlations.PooledCorrelations([LagCorrelations(terms, p, n0) for p in pieces])
    ref = DataCorrelations(np.vstack([evaluate_terms(terms, p, n0) for p in pieces]),
                           np.concatenate([p["y"][n0:] for p in pieces]))
    _assert_matches(fast, ref)


@pytest.mark.parametrize("spec", [SPECS[1], SPECS[2], SPECS[4]],
                         ids=lambda s: f"L{s.max_lag}CP{s.degree}")
@pytest.mark.parametrize("blocked", [False, True])
def test_offsets_give_the_sums_of_the_centred_signals_to_the_bit(spec, blocked, monkeypatch):
    # a long window subtracts the offsets block by block (no centred copy of the record), a
    # short one once: either way every mean equals that of the centred signals exactly
    if blocked:
        monkeypatch.setattr(correlations, "_BLOCKED_SAMPLES", 0)
        monkeypatch.setattr(correlations, "_BLOCK", 7)
        monkeypatch.setattr(correlations, "_GEMM_SAMPLES", 0)  # the weighted Gram too
        monkeypatch.setattr(correlations, "_CHUNK", 37)
    signals = _signals(400, 6)
    offsets = {k: float(v.mean()) for k, v in signals.items() if k != "b"}  # b left as it is
    centred = {k: v - offsets.get(k, 0.0) for k, v in signals.items()}
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    lazy = LagCorrelations(terms, signals, n0, offsets=offsets)
    eager = LagCorrelations(terms, centred, n0)
    for name in ("y_mean", "y_mean_sq", "means", "target", "diag"):
        np.testing.assert_array_equal(getattr(lazy, name), getattr(eager, name))
    for j in range(len(terms)):
        np.testing.assert_array_equal(lazy.column(j), eager.column(j))
    if blocked:  # the caller's arrays themselves, no centred copies
        assert all(any(np.shares_memory(u, v) for v in signals.values()) for u in lazy._signals)


@pytest.fixture
def pair_steps_everywhere(monkeypatch):
    """Every new shape of degree 4 summed as pair steps, in chunks and spans of a few samples."""
    monkeypatch.setattr(shapes, "_PAIR_SHAPES", 1)
    monkeypatch.setattr(correlations, "_PAIR_CHUNK", 5)
    monkeypatch.setattr(correlations, "_PAIR_SPAN", 13)
    monkeypatch.setattr(correlations, "_PAIR_VALUES", 40)
    shapes.clear_plans()
    yield
    shapes.clear_plans()


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: f"L{s.max_lag}CP{s.degree}")
@pytest.mark.parametrize("table_degree", [3, 4])
@pytest.mark.parametrize("n", [None, 300])
def test_pair_steps_match_reference(spec, table_degree, n, pair_steps_everywhere):
    n = n or spec.lag_window + 3
    signals = _signals(n, 7)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    fast = LagCorrelations(terms, signals, n0, table_degree=table_degree)
    ref = DataCorrelations(evaluate_terms(terms, signals, n0), signals["y"][n0:])
    _assert_matches(fast, ref)


def test_pair_steps_in_blocked_windows_with_offsets_match_reference(pair_steps_everywhere,
                                                                     monkeypatch):
    monkeypatch.setattr(correlations, "_BLOCKED_SAMPLES", 0)
    monkeypatch.setattr(correlations, "_BLOCK", 11)
    spec = SPECS[4]
    signals = _signals(200, 8)
    offsets = {k: float(v.mean()) for k, v in signals.items()}
    centred = {k: v - offsets[k] for k, v in signals.items()}
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    fast = LagCorrelations(terms, signals, n0, offsets=offsets)
    ref = DataCorrelations(evaluate_terms(terms, centred, n0), centred["y"][n0:])
    _assert_matches(fast, ref)


def test_pair_steps_plan_each_shape_as_head_times_moved_tail():
    # y[t] x[t-1] * (y[t-2] x[t-4]): head (y, x, 1), tail the pair (y, x, 2) moved 2 samples;
    # x[t] y[t-3] y[t-3] x[t-4] (factors out of shift order): head (x, y, 3), tail (y, x, 1)
    ch = np.array([[0, 1, 0, 1], [0, 0, 1, 1]])
    rel = np.array([[0, 1, 2, 4], [3, 3, 0, 4]])
    steps = shapes.pair_steps(ch, rel, np.array([0, 1]))
    pairs = [tuple(p) for p in steps.pairs.tolist()]
    assert pairs == sorted(pairs, key=lambda p: p[2])
    by_shape = {int(s): (q, pairs[h_lo + h], pairs[t_lo + t])
                for q, h_lo, _, t_lo, _, shp, hh, tt in steps.steps for s, h, t in zip(shp, hh, tt)}
    assert by_shape == {0: (2, (0, 1, 1), (0, 1, 2)), 1: (3, (1, 0, 3), (0, 1, 1))}


def test_gram_columns_at_once_equal_them_one_at_a_time(monkeypatch):
    spec = SPECS[1]
    signals = _signals(700, 9)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    at_once = LagCorrelations(terms, signals, n0)
    nonlinear = next(j for j, t in enumerate(terms) if t.degree == 2)
    first = at_once.column(nonlinear)
    assert len(at_once._columns) == len(terms)  # every column came with the first
    monkeypatch.setattr(shapes, "_GRAM_ROWS", 0)
    shapes.gram_columns.cache_clear()
    try:
        one = LagCorrelations(terms, signals, n0)
        np.testing.assert_allclose(first, one.column(nonlinear), rtol=1e-12, atol=1e-14)
        for j in range(len(terms)):
            np.testing.assert_allclose(at_once.column(j), one.column(j), rtol=1e-12, atol=1e-14)
        assert len(one._columns) < len(terms)
    finally:
        shapes.gram_columns.cache_clear()
