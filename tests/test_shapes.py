"""Shape keys, batch plans and the cached layout of a candidate set."""

import numpy as np
import pytest

from fosmodel.core.candidates import CandidateSpec, evaluate_terms, generate_terms
from fosmodel.core.correlations import LagCorrelations
from fosmodel.core.fos import DataCorrelations
from fosmodel.core.shapes import Geometry, direct_groups, layout, lookup, plan_batch


def _rows(*products):
    """(ch, lag) row arrays from products given as lists of (channel, lag), padded with -1."""
    width = max(len(p) for p in products)
    ch = np.full((len(products), width), -1, dtype=np.int64)
    lag = np.zeros_like(ch)
    for i, p in enumerate(products):
        for j, (c, k) in enumerate(p):
            ch[i, j], lag[i, j] = c, k
    return ch, lag


def _keys(geo, ch, lag):
    present = ch >= 0
    lmin = np.where(present, lag, geo.n0).min(axis=1)
    return geo.shape_keys(ch, lag, present, lmin)[0]


def test_shifted_products_share_a_key_and_others_do_not():
    geo = Geometry(n0=5, n_channels=2, width=3, table_degree=3)
    ch, lag = _rows([(0, 1), (0, 3)], [(0, 3), (0, 5)], [(0, 2), (0, 0)],  # one shape, 3 times
                    [(0, 1), (1, 3)], [(1, 1), (0, 3)], [(0, 1), (0, 1), (0, 2)], [(0, 4)])
    keys = _keys(geo, ch, lag)
    assert keys[0] == keys[1] == keys[2]
    assert len(set(keys[2:].tolist())) == 5
    assert (keys >= 0).all()


def test_rows_too_wide_to_encode_get_distinct_negative_keys():
    # base 3 * 201 + 1 = 604: 604^8 > 2^62, so keys have fewer digits than 8 factors
    geo = Geometry(n0=200, n_channels=3, width=8, table_degree=3)
    assert 3 <= len(geo.radix) < 8
    wide = [(0, k) for k in range(8)]
    ch, lag = _rows(wide, wide, [(0, 1), (0, 2)])
    keys = _keys(geo, ch, lag)
    assert keys[0] < 0 and keys[1] < 0 and keys[0] != keys[1] and keys[2] >= 0


def test_group_by_prefix_rebuilds_every_shape():
    geo = Geometry(n0=4, n_channels=2, width=4, table_degree=4)
    ch, lag = _rows([(0, 0), (0, 2)], [(0, 0), (0, 3)], [(0, 0), (0, 3), (0, 3)],
                    [(0, 0), (1, 1), (1, 2)], [(0, 0)], [(1, 0), (1, 0)])
    present = ch >= 0
    lmin = np.where(present, lag, geo.n0).min(axis=1)
    _, codes = geo.shape_keys(ch, lag, present, lmin)
    rebuilt = {}
    for prefix, lasts in geo.group_by_prefix(codes).items():
        for (c, k), (rows, rels) in lasts.items():
            assert list(rels) == sorted(rels)
            for row, rel in zip(rows.tolist(), rels.tolist()):
                rebuilt[row] = sorted([*prefix, *[(c, rel)] * k])
    for i, row in enumerate(codes.tolist()):
        assert rebuilt[i] == sorted(divmod(x - 1, geo.stride) for x in row if x)


def test_direct_groups_rebuild_every_row_and_sort_the_last_lags():
    wide = [(0, k) for k in range(8)]  # too wide for a shape key: grouped all the same
    ch, lag = _rows([(0, 3), (0, 9)], [(0, 3), (0, 4)], [(0, 3), (0, 3)], [(0, 3)],
                    [(1, 2), (0, 7), (0, 3)], wide, [(1, 5), (1, 5), (0, 1)], [])
    groups = direct_groups(ch, lag)
    rebuilt = {}
    for prefix, lasts in groups.items():
        for (c, k), (rows, lags) in lasts.items():
            assert list(lags) == sorted(lags) and not rows.flags.writeable
            for row, g in zip(rows.tolist(), lags.tolist()):
                rebuilt[row] = sorted([*prefix, *[(c, g)] * k]) if c >= 0 else list(prefix)
    for i, (r_ch, r_lag) in enumerate(zip(ch.tolist(), lag.tolist())):
        assert rebuilt[i] == sorted((c, g) for c, g in zip(r_ch, r_lag) if c >= 0)
    assert groups[((0, 3),)][(0, 1)][1].tolist() == [4, 9]  # y(t-3) y(t-4), y(t-3) y(t-9)
    assert direct_groups(ch, lag) is groups  # cached


def test_plan_tabulates_low_degree_and_repeated_shapes_only():
    geo = Geometry(n0=6, n_channels=1, width=4, table_degree=3)
    once = [(0, 1), (0, 2), (0, 4), (0, 6)]  # degree 4, its shape appears once
    twice = [[(0, 0), (0, 0), (0, 1), (0, 1)], [(0, 2), (0, 2), (0, 3), (0, 3)]]
    ch, lag = _rows([(0, 1), (0, 2)], [(0, 2), (0, 3)], once, *twice)
    empty = np.empty(0, dtype=np.int64), np.empty(0, dtype=np.intp)
    batch = plan_batch(geo, ch, lag, None, *empty)
    assert batch.table.tolist() == [True, True, False, True, True]
    assert len(batch.new.ch) == 2  # two shapes: (0, 1) and (0, 0, 1, 1)
    assert list(batch.keys) == sorted(batch.keys)
    keys = _keys(geo, ch, lag)
    assert (lookup(keys[batch.table], batch.keys, batch.slots) == batch.slot).all()
    # planned again against the grown tables, nothing is new
    again = plan_batch(geo, ch, lag, None, batch.keys, batch.slots)
    assert again.new is None and (again.slot == batch.slot).all()


def test_layout_is_cached_and_read_only():
    terms = [t for t in generate_terms(CandidateSpec(3, 2, {"temp": 1})) if not t.is_constant]
    factors = tuple(t.factors for t in terms)
    first = layout(factors, 3, 3)
    assert layout(factors, 3, 3) is first
    assert layout(factors, 4, 3) is not first
    assert first.names == ("y", "temp")
    with pytest.raises(ValueError):
        first.ch[0, 0] = 1


@pytest.mark.parametrize("spec", [CandidateSpec(5, 2), CandidateSpec(3, 3, {"temp": 2})],
                         ids=["L5CP2", "L3CP3x"])
def test_a_reused_layout_gives_the_reference_on_other_data(spec):
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    n0 = spec.lag_window
    layout.cache_clear()
    for n, seed in ((400, 0), (913, 1), (n0 + 4, 2)):  # cold, then the cached layout twice
        rng = np.random.default_rng(seed)
        signals = {"y": rng.standard_normal(n) + 2.0, "temp": rng.uniform(15, 30, n)}
        fast = LagCorrelations(terms, signals, n0)
        ref = DataCorrelations(evaluate_terms(terms, signals, n0), signals["y"][n0:])
        scale = float(np.max(np.abs(ref.diag))) + ref.y_mean_sq
        for got, want in ((fast.target, ref.target), (fast.diag, ref.diag),
                          (fast.means, ref.means)):
            np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10 * scale)
        for j in range(0, len(terms), 3):
            np.testing.assert_allclose(fast.column(j), ref.column(j), rtol=1e-10,
                                       atol=1e-10 * scale)
    assert layout.cache_info().hits >= 2
