"""Products of pair products (large sets of degree 3-4) against the point-by-point reference."""

import numpy as np
import pytest

from fosmodel.core import correlations, pairs
from fosmodel.core.candidates import CandidateSpec, Term, evaluate_terms, generate_terms
from fosmodel.core.correlations import LagCorrelations, fast_correlations
from fosmodel.core.fos import DataCorrelations, StopRule, fos_search
from fosmodel.core.pairs import PairCorrelations, pair_plan
from fosmodel.models.model import FOSModel

SPECS = [
    CandidateSpec(3, 4, {"x": 2}),  # degree 4 over two channels
    CandidateSpec(4, 3, {"x": 1}, columns=["c"]),  # cubic, with a user column entering linearly
    CandidateSpec(5, 2, {"x": 3}),  # degree 2: heads and tails of one factor
    CandidateSpec(6, 1),
    CandidateSpec(6, 4, product_lags=2),  # products of a few lags only: a sparse staircase
]


def _signals(n, seed):
    rng = np.random.default_rng(seed)
    return {"y": np.cumsum(rng.standard_normal(n)) * 0.1 + rng.standard_normal(n) + 3.0,
            "x": rng.uniform(-1, 1, n) + 0.5, "c": np.sin(0.37 * np.arange(n))}


def _terms(spec):
    return [t for t in generate_terms(spec) if not t.is_constant]


def _assert_matches(fast, ref):
    scale = float(np.max(np.abs(ref.diag))) + ref.y_mean_sq
    assert fast.n_samples == ref.n_samples
    for name in ("y_mean", "y_mean_sq", "means", "target", "diag"):
        np.testing.assert_allclose(getattr(fast, name), getattr(ref, name), rtol=1e-10,
                                   atol=1e-10 * scale)
    for j in range(len(ref.means)):
        np.testing.assert_allclose(fast.column(j), ref.column(j), rtol=1e-10, atol=1e-10 * scale)


@pytest.fixture
def small_blocks(monkeypatch):
    # blocks of a few samples and tiles of a few heads: block edges and tile edges everywhere
    monkeypatch.setattr(pairs, "_ROWS", 7)
    monkeypatch.setattr(pairs, "_TILE", 3)
    pair_plan.cache_clear()
    yield
    pair_plan.cache_clear()


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: f"L{s.max_lag}CP{s.degree}")
@pytest.mark.parametrize("blocks", ["default", "small"])
def test_every_mean_and_gram_column_matches_the_reference(spec, blocks, request):
    if blocks == "small":
        request.getfixturevalue("small_blocks")
    n0 = spec.lag_window
    signals = _signals(300, 1)
    terms = _terms(spec)
    ref = DataCorrelations(evaluate_terms(terms, signals, n0), signals["y"][n0:])
    _assert_matches(PairCorrelations(terms, signals, n0), ref)


def test_shortest_window_matches_the_reference():
    spec = SPECS[0]
    n0 = spec.lag_window
    signals = _signals(n0 + 3, 2)
    terms = _terms(spec)
    ref = DataCorrelations(evaluate_terms(terms, signals, n0), signals["y"][n0:])
    _assert_matches(PairCorrelations(terms, signals, n0), ref)


@pytest.mark.parametrize("spec", [SPECS[0], SPECS[1]], ids=lambda s: f"L{s.max_lag}CP{s.degree}")
def test_offsets_give_the_means_of_the_centred_signals(spec):
    signals = _signals(400, 3)
    offsets = {"y": float(signals["y"].mean()), "x": 0.25}  # c left as it is
    centred = {k: v - offsets.get(k, 0.0) for k, v in signals.items()}
    terms = _terms(spec)
    n0 = spec.lag_window
    lazy = PairCorrelations(terms, signals, n0, offsets=offsets)
    ref = DataCorrelations(evaluate_terms(terms, centred, n0), centred["y"][n0:])
    _assert_matches(lazy, ref)


def test_staircase_tiles_cover_each_candidate_once_and_little_else():
    plan = pair_plan(tuple(t.factors for t in _terms(CandidateSpec(10, 4, {"x": 9}))))
    assert len(plan.where) == 10_625 == len(np.unique(plan.where))
    assert len(plan.heads) == len(plan.tails) + 1 == 231  # (1, 1) is a head, never a tail
    assert plan.n_entries < 2 * len(plan.where)  # the full product would be 231 x 230
    # every candidate's entry is its head times its tail
    h_of = {tuple(h): i for i, h in enumerate(plan.heads.tolist())}
    t_of = {tuple(t): i for i, t in enumerate(plan.tails.tolist())}
    starts = np.cumsum([0] + [(b - a) * (d - c) for a, b, c, d in plan.tiles])
    for c in (0, 17, 500, 10_624):
        h, t = h_of[tuple(plan.symbols[c, :2])], t_of[tuple(plan.symbols[c, 2:])]
        k = next(i for i, (a, b, _, _) in enumerate(plan.tiles) if a <= h < b)
        a, _, lo, hi = plan.tiles[k]
        assert plan.where[c] == starts[k] + (h - a) * (hi - lo) + t - lo


def test_degree_above_four_is_refused():
    with pytest.raises(ValueError, match="degrees up to 4, not 5"):
        pair_plan(((("y", 1),) * 5,))


def test_fast_correlations_take_pairs_for_large_sets_of_degree_three_or_four(monkeypatch):
    signals = _signals(200, 4)
    big = _terms(CandidateSpec(3, 3, {"x": 2}))
    assert isinstance(fast_correlations(_terms(CandidateSpec(3, 2)), signals, 3), LagCorrelations)
    assert isinstance(fast_correlations(big, signals, 3), LagCorrelations)  # 83 candidates
    monkeypatch.setattr(correlations, "_PAIR_CANDIDATES", len(big))
    assert isinstance(fast_correlations(big, signals, 3), PairCorrelations)
    five = [*big, Term((("y", 1),) * 5)]  # a term of degree 5: tables and direct sums
    assert isinstance(fast_correlations(five, signals, 3), LagCorrelations)


def test_search_on_pairs_selects_the_reference_terms_and_weights(small_blocks):
    spec = SPECS[0]
    n0 = spec.lag_window
    signals = _signals(500, 5)
    x, y = signals["x"], signals["y"]
    y[3:] += 0.8 * x[2:-1] * y[1:-2] - 0.5 * x[1:-2] ** 2 * x[:-3]  # cross-products to find
    terms = _terms(spec)
    rule = StopRule("max_terms", max_terms=8)
    fast = fos_search(PairCorrelations(terms, signals, n0), rule)
    ref = fos_search(DataCorrelations(evaluate_terms(terms, signals, n0), y[n0:]), rule)
    assert fast.support.tolist() == ref.support.tolist()
    np.testing.assert_allclose(fast.coef, ref.coef, rtol=1e-9)


def test_model_fit_on_pairs_equals_the_reference_fit(monkeypatch):
    # the SysIdentPy example system, y[k] = 0.2 y[k-1] + 0.1 y[k-1] x[k-1] + 0.9 x[k-2]
    rng = np.random.default_rng(6)
    n = 1500
    x = rng.uniform(-1, 1, n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.2 * y[k - 1] + 0.1 * y[k - 1] * x[k - 1] + 0.9 * x[k - 2] + 1e-3 * rng.normal()
    monkeypatch.setattr(correlations, "_PAIR_CANDIDATES", 0)
    kwargs = dict(max_lag=3, degree=4, exog_lags={"x": 3}, stop="max_terms", max_terms=6)
    seen = []
    init = PairCorrelations.__init__
    monkeypatch.setattr(PairCorrelations, "__init__",
                        lambda self, *a, **k: seen.append(1) or init(self, *a, **k))
    fast = FOSModel(**kwargs).fit(y, {"x": x})
    ref = FOSModel(**kwargs, correlations="reference").fit(y, {"x": x})
    assert seen  # the fit did run on pair products
    assert fast.terms_ == ref.terms_
    assert set(fast.terms_[:3]) == {"x[n-2]", "y[n-1]", "y[n-1]*x[n-1]"}
    np.testing.assert_allclose(fast.coef_, ref.coef_, rtol=1e-9)
    assert fast.intercept_ == pytest.approx(ref.intercept_, rel=1e-9, abs=1e-12)
