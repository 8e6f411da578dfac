"""Shapes of lagged products and the data-free plan of a batch of moments.

A moment is the window mean of a product of lagged signals, given row-wise by
(channel, lag) pairs (channel -1: no factor).  Shifting its lags by the row's
smallest lag ``lmin`` gives its *shape*; :class:`Geometry` encodes shapes as
integer keys.  :func:`plan_batch` decides which rows of a batch come from the
shape tables of :class:`fosmodel.core.correlations.LagCorrelations` and which new
shapes the batch adds to them.  None of this depends on the data, so the plan
of the batch every fit starts with is made once per candidate set
(:func:`layout`) and reused by later fits, like an FFT plan.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import ClassVar

import numpy as np

from .candidates import OUTPUT, Factor

_BLOCK = 8192  # most moments in the Gram columns of linear candidates tabulated at once
_PAIR_SHAPES = 64  # fewest new shapes of degree 4 summed as pair steps
_GRAM_ROWS = 2**16  # most moments in the Gram columns of nonlinear candidates tabulated at once


@dataclass(frozen=True)
class Geometry:
    """How shapes over ``n_channels`` signals and lags ``0..n0`` are encoded.

    A factor (channel c, lag shift r) has the code ``c * (n0 + 1) + r + 1``;
    0 is an absent factor.  A shape's key is its sorted codes in base
    ``n_channels * (n0 + 1) + 1``, with as many digits as fit in an int64
    (at least ``table_degree``).

    A worked example: with the output y (channel 0), one input u (channel 1) and
    lags up to ``n0 = 2``, the moments of ``y[n-1] u[n-2]`` and ``y[n-2] u[n-3]``
    shift to the same shape (y lag 0, u lag 1): codes 1 and 5, key
    ``1 + 5 * 7 = 36`` in base 7.  One cross-correlation sum over the record
    serves both; each differs from it by its own end correction (1 and 2 samples).

    >>> import numpy as np
    >>> geometry = Geometry(n0=2, n_channels=2, width=2, table_degree=2)
    >>> lags = np.array([[1, 2], [2, 3]])
    >>> keys, codes = geometry.shape_keys(np.array([[0, 1], [0, 1]]), lags,
    ...                                   np.ones((2, 2), bool), lags.min(axis=1))
    >>> keys.tolist(), codes.tolist()
    ([36, 36], [[1, 5], [1, 5]])
    """

    n0: int
    n_channels: int
    width: int  # most factors in a row
    table_degree: int
    radix: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Set the radix: as many digits of a key's base as fit in an int64."""
        base, digits = self.n_channels * self.stride + 1, self.width
        while digits > self.table_degree and base**digits >= 2**62:
            digits -= 1
        object.__setattr__(self, "radix", base ** np.arange(max(digits, 1), dtype=np.int64))

    @property
    def stride(self) -> int:
        """Codes per channel: one per lag shift ``0 .. n0``."""
        return self.n0 + 1

    def shape_keys(self, ch: np.ndarray, lag: np.ndarray, present: np.ndarray,
                   lmin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the integer key of each row's shape and the row's sorted codes.

        A key is negative where the row has too many factors to encode; absent factors
        come first among the codes.
        """
        code = ch * self.stride + (lag - lmin[:, None] + 1)
        code[~present] = 0
        code.sort(axis=1)
        width = len(self.radix)
        if code.shape[1] <= width:
            return code @ self.radix[width - code.shape[1] :], code
        fits = ~code[:, :-width].any(axis=1)
        code = code[:, -width:]
        return np.where(fits, code @ self.radix, -1 - np.arange(len(code))), code

    def group_by_prefix(self, codes: np.ndarray) -> dict[tuple, dict[tuple, tuple]]:
        """Group shapes by their factors but the last, then by the last factor's channel and power.

        The prefix leaves out the last factor's square if it repeats:
        ``{prefix: {(ch, k): (rows, rels)}}``.

        A prefix is a tuple of ``(channel, lag shift)`` factors; ``rels`` are the
        last factor's lag shifts, ascending; channel -1 is the empty product.
        """
        width = codes.shape[1]
        last = codes[:, -1]
        power = np.ones(len(codes), dtype=np.int64)
        if width > 1:
            power += (codes[:, -2] == last) & (last > 0)
        prefix = codes.copy()
        prefix[:, -1] = 0
        prefix[power == 2, -2] = 0
        prefix.sort(axis=1)
        ch, rel = np.divmod(last - 1, self.stride)
        ch[last == 0] = -1
        key = np.stack([prefix @ self.radix[len(self.radix) - width :], ch, power])
        order = np.lexsort((rel, *key[::-1]))  # lags ascending within a group
        bounds = np.flatnonzero((np.diff(key[:, order], axis=1) != 0).any(axis=0)) + 1
        groups: dict[tuple, dict[tuple, tuple]] = {}
        for rows in np.split(order, bounds):
            i = rows[0]
            name = tuple(divmod(c - 1, self.stride) for c in prefix[i].tolist() if c)
            groups.setdefault(name, {})[(int(ch[i]), int(power[i]))] = (rows, rel[rows])
        return groups

    def factor_index(self, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the (channel, lag shift) of every code.

        An absent factor is channel ``n_channels`` (the ones of the edge tables) at shift 0.
        """
        ch, rel = np.divmod(codes - 1, self.stride)
        ch[codes == 0], rel[codes == 0] = self.n_channels, 0
        return ch, rel


def lookup(keys: np.ndarray, table_keys: np.ndarray, table_slots: np.ndarray) -> np.ndarray:
    """Table row of each shape key, -1 where not tabulated (``table_keys`` sorted)."""
    if not len(table_keys):
        return np.full(len(keys), -1, dtype=np.intp)
    pos = np.minimum(np.searchsorted(table_keys, keys), len(table_keys) - 1)
    return np.where(table_keys[pos] == keys, table_slots[pos], -1)


@dataclass(frozen=True)
class PairSteps:
    """How a batch's new shapes of degree 4 are summed: products of pair products.

    Sorted by lag shift, a shape's factors are a *head*, its first two (the first at
    shift 0), and a *tail*, its last two, moved ``q`` samples (the shift of the third):

        sum_t z_h(t) z_k(t - q),   z(s) = u_c1(s) u_c2(s - d),

    the pair products ``z`` being the rows ``pairs`` = ``(c1, c2, d)``, sorted by ``d``.
    Each step ``(q, h_lo, h_hi, t_lo, t_hi, shapes, h, t)`` is one matrix product of the
    rows ``h_lo..h_hi-1`` (heads) with the rows ``t_lo..t_hi-1`` moved ``q`` samples
    (tails); the new shapes ``shapes`` are its entries ``(h, t)`` (relative to ``h_lo``,
    ``t_lo``).  A head needs ``d <= q`` and a tail ``d <= N0 - q``, so each step's rows
    are the first ones and its products read only samples of the record.
    """

    pairs: np.ndarray
    steps: tuple[tuple[int, int, int, int, int, np.ndarray, np.ndarray, np.ndarray], ...]


@dataclass(frozen=True)
class NewShapes:
    """Shapes a batch adds to the tables, as rows ``base, base + 1, ...``.

    Those in :class:`PairSteps` are summed as they say, the others by the groups of their
    leading factors.
    """

    groups: dict  # Geometry.group_by_prefix of the codes of the shapes not in pair steps
    ch: np.ndarray  # Geometry.factor_index of their codes
    rel: np.ndarray
    pair_steps: PairSteps | None


def new_shapes(geo: Geometry, codes: np.ndarray) -> NewShapes:
    """Plan the sums of the new shapes with these (sorted) codes: pair steps and groups.

    Shapes of degree 4 are pair steps when there are at least ``_PAIR_SHAPES`` of them:
    a few are cheaper as a prefix product and a correlation each.
    """
    ch, rel = geo.factor_index(codes)
    paired = (codes > 0).sum(axis=1) == 4
    if paired.sum() < _PAIR_SHAPES:
        paired[:] = False
    rest = np.flatnonzero(~paired)
    groups = geo.group_by_prefix(codes[rest]) if len(rest) else {}
    for by_last in groups.values():
        for key, (rows, rels) in by_last.items():
            by_last[key] = (rest[rows], rels)
    # the present factors come last among the sorted codes: move them first for pair steps
    present = np.argsort(codes == 0, axis=1, kind="stable")
    steps = (pair_steps(np.take_along_axis(ch, present, 1), np.take_along_axis(rel, present, 1),
                        np.flatnonzero(paired)) if paired.any() else None)
    return NewShapes(groups, ch, rel, steps)


def pair_steps(ch: np.ndarray, rel: np.ndarray, shapes: np.ndarray) -> PairSteps:
    """Plan the shapes ``shapes`` (rows of ``ch``, ``rel``, four factors first) as pair steps."""
    c, r = ch[shapes, :4], rel[shapes, :4]
    order = np.argsort(r * (ch.max() + 1) + c, axis=1, kind="stable")  # by shift
    c, r = np.take_along_axis(c, order, 1), np.take_along_axis(r, order, 1)
    heads = np.column_stack([c[:, 0], c[:, 1], r[:, 1]])
    tails = np.column_stack([c[:, 2], c[:, 3], r[:, 3] - r[:, 2]])
    q = r[:, 2]
    pairs = np.unique(np.vstack([heads, tails]), axis=0)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0], pairs[:, 2]))]  # by shift d
    head_row, tail_row = _row_of(pairs, heads), _row_of(pairs, tails)
    steps = []
    for lag in np.unique(q).tolist():
        at = np.flatnonzero(q == lag)
        h, t = head_row[at], tail_row[at]
        h_lo, t_lo = int(h.min()), int(t.min())
        entries = (shapes[at], h - h_lo, t - t_lo)
        for a in entries:
            a.flags.writeable = False
        steps.append((lag, h_lo, int(h.max()) + 1, t_lo, int(t.max()) + 1, *entries))
    pairs.flags.writeable = False
    return PairSteps(pairs, tuple(steps))


def _row_of(table: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Index in ``table`` of each row of ``rows`` (every one of which is in ``table``)."""
    keys = {tuple(row): i for i, row in enumerate(table.tolist())}
    return np.array([keys[tuple(row)] for row in rows.tolist()], dtype=np.intp)


@dataclass(frozen=True)
class Batch:
    """The plan of one batch of moments against the tables as they were before it."""

    lmin: np.ndarray  # each row's smallest lag
    table: np.ndarray  # rows read from the tables (the others are summed directly)
    slot: np.ndarray  # table row of each row read from the tables
    new: NewShapes | None
    keys: np.ndarray  # tabulated shape keys after the batch, sorted
    slots: np.ndarray  # their table rows


def plan_batch(geo: Geometry, ch: np.ndarray, lag: np.ndarray, lmin: np.ndarray | None,
               table_keys: np.ndarray, table_slots: np.ndarray) -> Batch:
    """Plan which rows come from the tables, and which shapes the batch tabulates first.

    A product comes from the tables if its degree is at most
    ``geo.table_degree``, or if its shape is already tabulated or repeats
    within the batch; otherwise it is summed directly.  ``lmin`` (each row's smallest lag)
    is computed from the rows when None.
    """
    present = ch >= 0
    degree = present.sum(axis=1)
    if lmin is None:
        lmin = np.where(present, lag, geo.n0).min(axis=1)
    keys, codes = geo.shape_keys(ch, lag, present, lmin)
    slot = lookup(keys, table_keys, table_slots)
    table = slot >= 0
    new = None
    if not table.all():
        table |= degree <= geo.table_degree
        maybe = ~table & (degree <= len(geo.radix))
        if maybe.any():  # tabulate a high-degree shape only if it serves several products
            uniq, counts = np.unique(keys[maybe], return_counts=True)
            table |= np.isin(keys, uniq[counts > 1])
        fresh = table & (slot < 0)
        if fresh.any():
            uniq, first = np.unique(keys[fresh], return_index=True)
            codes = codes[fresh][first]
            new = new_shapes(geo, codes)
            base = len(table_keys)
            all_keys = np.concatenate([table_keys, uniq])
            all_slots = np.concatenate([table_slots, base + np.arange(len(uniq))])
            order = np.argsort(all_keys, kind="stable")
            table_keys, table_slots = all_keys[order], all_slots[order]
            slot = lookup(keys, table_keys, table_slots)
    return Batch(lmin, table, slot[table], new, table_keys, table_slots)


@dataclass(frozen=True)
class FirstRows:
    """Where each quantity sits among the rows of the batch a fit starts with.

    Row 0 is mean(y), row 1 mean(y^2); then ``n_candidates`` rows each of
    mean(p_c), mean(y p_c) and mean(p_c^2); then the Gram columns mean(p_c p_j)
    of the ``n_linear`` tabulated linear candidates j, ``n_candidates`` rows each.
    """

    n_candidates: int
    n_linear: int
    y_mean: ClassVar[int] = 0
    y_mean_sq: ClassVar[int] = 1

    def _block(self, i: int) -> slice:
        k = self.n_candidates
        return slice(2 + i * k, 2 + (i + 1) * k)

    @property
    def means(self) -> slice:
        """Rows of mean(p_c), one per candidate."""
        return self._block(0)

    @property
    def target(self) -> slice:
        """Rows of mean(y p_c), one per candidate."""
        return self._block(1)

    @property
    def diag(self) -> slice:
        """Rows of mean(p_c^2), one per candidate."""
        return self._block(2)

    @property
    def columns(self) -> slice:
        """Rows of the tabulated linear candidates' Gram columns, ``n_candidates`` each."""
        return slice(self.diag.stop, self.n_rows)

    @property
    def n_rows(self) -> int:
        """Number of rows of the first batch."""
        return 2 + (3 + self.n_linear) * self.n_candidates


@dataclass(frozen=True)
class Layout:
    """Everything about a candidate set's correlations that does not depend on the data.

    ``ch``, ``lag``: the candidates' factors, one row each (channel index into
    ``names``, -1 for none); ``first``: the plan of the batch a fit starts
    with, whose rows are ``rows`` (laid out as ``first_rows`` says); ``linear``:
    the linear candidates whose Gram columns that batch includes.
    """

    names: tuple[str, ...]
    geometry: Geometry
    ch: np.ndarray
    lag: np.ndarray
    lmin: np.ndarray
    linear: np.ndarray
    rows: tuple[np.ndarray, np.ndarray]
    first_rows: FirstRows
    first: Batch


@lru_cache(maxsize=16)
def layout(factors: tuple[tuple[Factor, ...], ...], n0: int, table_degree: int) -> Layout:
    """Lay out the candidates with these factors (one tuple per candidate).

    The first batch holds, in order (:class:`FirstRows`): mean(y), mean(y^2),
    mean(p_c), mean(y p_c), mean(p_c^2) for every candidate c, then the Gram
    columns of the linear candidates when they are few (see
    :func:`_linear_rows`).  Each row is a product of at most ``2 * width``
    factors (channel, lag): a candidate's factors in the first half, the
    second factor of the moment (y, or the candidate again) in the second.
    Cached: fits of one candidate set share it (its arrays are read-only).
    """
    names = (OUTPUT, *sorted({ch for fs in factors for ch, _ in fs} - {OUTPUT}))
    index = {ch: i for i, ch in enumerate(names)}
    width = max([len(fs) for fs in factors] + [1])
    k = len(factors)
    ch = np.full((k, width), -1, dtype=np.int64)
    lag = np.zeros((k, width), dtype=np.int64)
    for i, fs in enumerate(factors):
        for j, (name, lg) in enumerate(fs):
            ch[i, j], lag[i, j] = index[name], lg or 0
    geo = Geometry(n0, len(names), 2 * width, table_degree)
    linear, ch_lin, lag_lin = _linear_rows(ch, lag, table_degree)
    rows = FirstRows(k, len(linear))
    first_ch = np.full((rows.n_rows, 2 * width), -1, dtype=np.int64)
    first_lag = np.zeros_like(first_ch)
    first_ch[rows.y_mean, 0] = first_ch[rows.y_mean_sq, :2] = 0  # y is channel 0 at lag 0
    for block in (rows.means, rows.target, rows.diag):
        first_ch[block, :width], first_lag[block, :width] = ch, lag
    first_ch[rows.target, width] = 0  # times y
    first_ch[rows.diag, width:], first_lag[rows.diag, width:] = ch, lag  # times itself
    first_ch[rows.columns, : width + 1] = ch_lin
    first_lag[rows.columns, : width + 1] = lag_lin
    empty_keys, empty_slots = np.empty(0, dtype=np.int64), np.empty(0, dtype=np.intp)
    first = plan_batch(geo, first_ch, first_lag, None, empty_keys, empty_slots)
    lmin = np.where(ch >= 0, lag, n0).min(axis=1)
    out = Layout(names, geo, ch, lag, lmin, linear, (first_ch, first_lag), rows, first)
    for a in (ch, lag, lmin, linear, first_ch, first_lag, *_arrays(first)):
        a.flags.writeable = False
    return out


@dataclass(frozen=True)
class GramColumns:
    """The batch of the Gram columns of every nonlinear candidate (:func:`gram_columns`).

    ``columns``: the candidates j whose columns it holds, ``len(columns)`` blocks of one row
    per candidate c, in order; ``rows``: their (channel, lag) factors, c's then j's.
    """

    columns: np.ndarray
    rows: tuple[np.ndarray, np.ndarray]
    batch: Batch


@lru_cache(maxsize=16)
def gram_columns(factors: tuple[tuple[Factor, ...], ...], n0: int,
                 table_degree: int) -> GramColumns | None:
    """Plan every Gram column the first batch of :func:`layout` leaves out, as one batch.

    When a search first asks for the column of a nonlinear candidate, the moments of all
    those columns are tabulated together, if the candidates are products of at most two
    factors (the moments have at most four, all tabulated: the shapes of degree 4 over the
    lags, 220 at L = 10 and 1,540 at L = 20, as pair steps) and the columns hold at most
    ``_GRAM_ROWS`` moments (at L = 20 on 36,000 samples, three cross-products in a search
    already cost more one column at a time).
    Otherwise (None) the search fetches the columns one at a time.  Planned against the
    tables of the first batch, as the search finds them at that point.  Cached.
    """
    plan = layout(factors, n0, table_degree)
    k, width = plan.ch.shape
    columns = np.setdiff1d(np.arange(k), plan.linear)
    geo = replace(plan.geometry, table_degree=4)
    if (width > 2 or not 0 < len(columns) * k <= _GRAM_ROWS
            or not np.array_equal(geo.radix, plan.geometry.radix)):
        return None
    ch = np.hstack([np.tile(plan.ch, (len(columns), 1)), np.repeat(plan.ch[columns], k, axis=0)])
    lag = np.hstack([np.tile(plan.lag, (len(columns), 1)),
                     np.repeat(plan.lag[columns], k, axis=0)])
    batch = plan_batch(geo, ch, lag, None, plan.first.keys, plan.first.slots)
    for a in (columns, ch, lag, *_arrays(batch)):
        a.flags.writeable = False
    return GramColumns(columns, (ch, lag), batch)


def _arrays(batch: Batch) -> list[np.ndarray]:
    arrays = [batch.lmin, batch.table, batch.slot, batch.keys, batch.slots]
    if batch.new is not None:
        arrays += [batch.new.ch, batch.new.rel]
        if batch.new.pair_steps is not None:
            arrays.append(batch.new.pair_steps.pairs)
    return arrays


def _linear_rows(ch: np.ndarray, lag: np.ndarray, table_degree: int):
    """Return the linear candidates whose Gram columns are tabulated at once, and their rows.

    A linear candidate's column holds moments of degree at most width + 1,
    all table lookups when that is within ``table_degree``; while all those
    columns hold at most ``_BLOCK`` moments, one batch costs less than a call
    per search step (measured up to L = 50 at CP = 1 and L = 20 at CP = 2,
    even when the search selects a few of them).  With more, the search
    fetches the columns it needs.  Returns the candidates' indices and the
    (channel, lag) rows of their columns, ``width + 1`` factors each.
    """
    k, width = ch.shape
    linear = np.flatnonzero((ch >= 0).sum(axis=1) == 1)
    if width + 1 > table_degree or not 0 < len(linear) * k <= _BLOCK:
        empty = np.empty((0, width + 1), dtype=np.int64)
        return linear[:0], empty, empty
    rows_ch = np.empty((len(linear) * k, width + 1), dtype=np.int64)
    rows_lag = np.empty_like(rows_ch)
    rows_ch[:, :width] = np.tile(ch, (len(linear), 1))
    rows_lag[:, :width] = np.tile(lag, (len(linear), 1))
    rows_ch[:, width] = np.repeat(ch[linear, 0], k)
    rows_lag[:, width] = np.repeat(lag[linear, 0], k)
    return linear, rows_ch, rows_lag


def direct_groups(ch: np.ndarray, lag: np.ndarray) -> dict[tuple, dict[tuple, tuple]]:
    """Rows summed directly, grouped as :meth:`Geometry.group_by_prefix` groups shapes.

    ``{prefix: {(ch, k): (rows, lags)}}``: a row's sorted factors (channel,
    lag) but the last (its square, ``k = 2``, if it repeats) form the prefix;
    ``lags`` are the last factor's lags, ascending; channel -1 is the empty
    product.  Unlike shapes, these rows may be too wide to encode as keys,
    so they are grouped by their factors.  Cached: a Gram column's directly
    summed rows are the same in every fit of a candidate set (read-only).
    """
    ch, lag = np.asarray(ch, dtype=np.int64), np.asarray(lag, dtype=np.int64)
    return _direct_groups(ch.tobytes(), lag.tobytes(), ch.shape)


@lru_cache(maxsize=4096)
def _direct_groups(ch_bytes: bytes, lag_bytes: bytes, shape: tuple[int, int]) -> dict:
    # reshape(rows, columns): numpy's stubs take reshape(shape) of a tuple for a 0-d array
    ch = np.frombuffer(ch_bytes, dtype=np.int64).reshape(shape[0], shape[1])
    lag = np.frombuffer(lag_bytes, dtype=np.int64).reshape(shape[0], shape[1])
    groups: dict[tuple, dict[tuple, tuple[list, list]]] = {}
    for i, (r_ch, r_lag) in enumerate(zip(ch.tolist(), lag.tolist())):
        row = sorted((c, g) for c, g in zip(r_ch, r_lag) if c >= 0)
        k = 2 if len(row) > 1 and row[-2] == row[-1] else 1
        c, g = row[-1] if row else (-1, 0)
        rows, lags = groups.setdefault(tuple(row[:-k]), {}).setdefault((c, k), ([], []))
        rows.append(i)
        lags.append(g)
    out: dict[tuple, dict[tuple, tuple]] = {}
    for prefix, by_last in groups.items():
        out[prefix] = {}
        for key, (rows, lags) in by_last.items():
            order = np.argsort(lags, kind="stable")
            pair = np.asarray(rows, dtype=np.intp)[order], np.asarray(lags, dtype=np.int64)[order]
            for a in pair:
                a.flags.writeable = False
            out[prefix][key] = pair
    return out


def clear_plans() -> None:
    """Forget the cached layouts and direct groups (to time a first fit, as benchmarks do)."""
    layout.cache_clear()
    gram_columns.cache_clear()
    _direct_groups.cache_clear()
