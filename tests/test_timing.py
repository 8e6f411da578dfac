"""Timed parts: the kernels report where a fit's time goes, and nothing when not asked."""

import numpy as np

from fosmodel.core import timed_parts
from fosmodel.core.candidates import CandidateSpec, generate_terms
from fosmodel.core.correlations import LagCorrelations
from fosmodel.core.pairs import PairCorrelations, pair_plan
from fosmodel.core.timing import _NOTHING, count, part
from fosmodel.models.model import FOSModel


def _record(n=400, seed=3):
    rng = np.random.default_rng(seed)
    return {"y": np.cumsum(rng.standard_normal(n)) * 0.1 + rng.standard_normal(n),
            "x": rng.uniform(-1, 1, n)}


def _terms(spec):
    return [t for t in generate_terms(spec) if not t.is_constant]


def test_outside_a_timed_block_a_part_is_the_shared_no_op_and_counts_go_nowhere():
    assert part("anything") is _NOTHING
    count("anything", 5)  # no error, nothing kept
    with timed_parts() as parts:
        pass
    assert parts.seconds == {} and parts.counts == {}


def test_parts_nest_under_the_enclosing_name_and_sum_over_runs():
    with timed_parts() as parts:
        for _ in range(3):
            with part("outer"):
                with part("inner"):
                    count("items", 2)
        with part("inner"):
            pass
    assert set(parts.seconds) == {"outer", "outer: inner", "inner"}
    assert parts.seconds["outer"] >= parts.seconds["outer: inner"] > 0
    assert parts.counts == {"outer: inner: items": 6}


def test_an_inner_timed_block_collects_alone_and_the_outer_resumes():
    with timed_parts() as outer:
        with part("a"):
            pass
        with timed_parts() as inner:
            with part("b"):
                pass
        with part("c"):
            pass
    assert set(outer.seconds) == {"a", "c"} and set(inner.seconds) == {"b"}
    assert part("a") is _NOTHING


def test_pair_correlations_report_their_passes_products_and_multiply_adds():
    spec = CandidateSpec(3, 4, {"x": 2})
    signals, n0 = _record(), spec.lag_window
    terms = _terms(spec)
    with timed_parts() as parts:
        corr = PairCorrelations(terms, signals, n0)
        corr.column(len(terms) - 1)
        corr.column(0)
    assert {"plan", "first pass", "first pass: pair products", "first pass: tile products",
            "Gram columns", "Gram columns: pair products",
            "Gram columns: tile products"} <= set(parts.seconds)
    for phase in ("first pass", "Gram columns"):
        inner = parts.seconds[f"{phase}: pair products"] + parts.seconds[f"{phase}: tile products"]
        assert inner <= parts.seconds[phase]
    # the first pass multiplies three sets of entries (means, y, squares), a column one
    entries = pair_plan(tuple(t.factors for t in terms)).n_entries * corr.n_samples
    assert parts.counts == {"first pass: tile multiply-adds": 3 * entries,
                            "Gram columns: tile multiply-adds": 2 * entries}


def test_lag_correlations_report_the_first_pass_and_new_gram_columns_only():
    spec = CandidateSpec(4, 2)
    signals, n0 = _record(), spec.lag_window
    terms = _terms(spec)
    with timed_parts() as parts:
        corr = LagCorrelations(terms, signals, n0)
        corr.column(0)  # a linear term: from the first pass, not timed again
    assert set(parts.seconds) == {"first pass"}
    with timed_parts() as parts:
        corr.column(len(terms) - 1)
    assert set(parts.seconds) == {"Gram columns"}


def test_a_timed_fit_is_the_same_fit():
    signals = _record(600)
    model = FOSModel(max_lag=3, degree=4, exog_lags={"x": 2}, stop="max_terms", max_terms=6)
    plain = model.fit(signals["y"], {"x": signals["x"]})
    terms, weights = list(plain.terms_), plain.coef_.copy()
    with timed_parts() as parts:
        timed = model.fit(signals["y"], {"x": signals["x"]})
    assert parts.seconds
    assert list(timed.terms_) == terms
    np.testing.assert_array_equal(timed.coef_, weights)
