"""Korenberg's speed-up: FOS correlations of lagged candidates from correlation tables.

Every quantity FOS needs is the mean, over the fitting window ``n = N0..N-1``,
of a product of lagged signals ``u_c1(n - l1) u_c2(n - l2) ...`` (a *moment*).
Shifting all lags by their minimum ``lmin`` gives the moment's *shape*; a
shape's sum over the whole record is computed once, and each moment with that
shape is then the shape's sum plus an end correction of at most ``lmin`` samples
at each end of the window.  The second-order shapes are the auto- and
cross-correlations of the signals; third-order shapes serve the cross-products
of degree 2.  So an AR(L) search costs L+1 dot products of length N however
many terms it selects, instead of a dot product per Gram entry.

Moments of a degree above ``table_degree`` (e.g. a product of two
cross-products) have few repeated shapes; they are summed directly over the
window, sharing partial products through a prefix tree, so that the N x C
candidate matrix is never formed.  When a search first needs the Gram column
of a cross-product, the columns of every candidate are tabulated at once if
the set is small (CP = 2 up to L = 21 on one signal): then all shapes of degree 4
over the lags are summed as *pair steps*, one matrix product of pair
products ``u(t) u(t-d)`` per lag shift (:class:`fosmodel.core.shapes.PairSteps`).

Large sets of products of degree 3 and 4 (thousands of candidates over 20
lags and more) have their own provider, :mod:`fosmodel.core.pairs`;
:func:`fast_correlations` picks the provider for a candidate set.

Which moments come from the tables, and how shapes are keyed and grouped,
does not depend on the data: :mod:`fosmodel.core.shapes` plans it, once per
candidate set for the batch every fit starts with.  This module does the sums.

:class:`LagCorrelations` is the fast provider for :func:`fosmodel.core.fos.fos_search`;
the point-by-point reference is :class:`fosmodel.core.fos.DataCorrelations` on the
matrix from :func:`fosmodel.core.candidates.evaluate_terms`.

References
----------
.. [1] M. J. Korenberg, "Identifying nonlinear difference equation and functional expansion
   representations: the fast orthogonal algorithm", Annals of Biomedical Engineering 16,
   123-142, 1988.
.. [2] M. J. Korenberg, "A robust orthogonal algorithm for system identification and
   time-series analysis", Biological Cybernetics 60(4), 267-276, 1989.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Iterator, Mapping, Sequence
from functools import lru_cache

import numpy as np

from .blas import one_blas_thread
from .candidates import OUTPUT, Term
from .pairs import MAX_DEGREE, PairCorrelations
from .shapes import (
    Batch,
    NewShapes,
    PairSteps,
    direct_groups,
    gram_columns,
    layout,
    plan_batch,
)
from .timing import part

_GEMM_SAMPLES = 200_000  # from this window length, weighted sums of pairs go through BLAS
_CHUNK = 4096  # samples per block of those sums: the block's factors stay in cache
# Windows longer than this are summed in blocks of _BLOCK samples: a block's products and
# correlations stay in the cache (one pass over a whole record is bound by memory traffic,
# ~5x slower at 1e7 samples) and the work arrays hold a block, not the record.  Shorter
# windows keep their single pass, so their sums (and the fits on them) stay bit-identical.
_BLOCKED_SAMPLES = 2**21
_BLOCK = 2**16
_SCRATCH = threading.local()
# Shapes summed as pair steps: their rows are formed over spans of at most _PAIR_SPAN samples
# and _PAIR_VALUES values, and multiplied _PAIR_CHUNK samples at a time (on 36,000 samples
# 8,192 took 0.56 ms for the 220 shapes of degree 4 over 10 lags, 4,096 0.64 ms, the
# whole window 1.4 ms).
_PAIR_SPAN = 2**16
_PAIR_VALUES = 2**19
_PAIR_CHUNK = 8192


def _scratch(depth: int, size: int) -> np.ndarray:
    """Return a work array of ``size`` floats for one prefix depth, reused by this thread.

    Fresh arrays of this size come from mmap and pay a page fault per 4 kB on
    first touch, which costs more than the products written into them.
    """
    buffers = getattr(_SCRATCH, "buffers", None)
    if buffers is None:
        buffers = _SCRATCH.buffers = {}
    buf = buffers.get(depth)
    if buf is None or len(buf) != size:
        buf = buffers[depth] = np.empty(size)
    return buf


@lru_cache(maxsize=64)
def _edge_index(n0: int) -> np.ndarray:
    """``N0 + i - rel`` for i < N0 (rows) and rel <= N0 (columns)."""
    index = n0 + np.arange(n0)[:, None] - np.arange(n0 + 1)
    index.flags.writeable = False
    return index


class LagCorrelations:
    """Correlations of lagged-product candidates over the window ``n = start..N-1``.

    Parameters
    ----------
    terms : sequence of Term
        The candidates (their lags must not exceed ``start``).
    signals : mapping of str to 1-D array
        ``y`` and every channel or column the terms read, all of length N.
    start : int
        N0, the first sample of the fitting window.
    table_degree : int
        Moments up to this degree come from shape tables; higher ones are
        summed directly.  0 sums everything directly.
    offsets : mapping of str to float, optional
        Subtracted from the named signals before any product (their centring).
        A window summed in blocks subtracts them block by block, so that no
        centred copy of a record-long signal is made; a shorter window centres
        each signal once.  Either way the products, and the sums, are the same
        as from the centred signals.
    """

    def __init__(
        self,
        terms: Sequence[Term],
        signals: Mapping[str, np.ndarray],
        start: int,
        *,
        table_degree: int = 3,
        offsets: Mapping[str, float] | None = None,
    ) -> None:
        self._plan_key = (tuple(t.factors for t in terms), start, table_degree)
        plan = layout(*self._plan_key)
        n, n0 = len(signals[OUTPUT]), start
        self._n, self._n0 = n, n0
        self.n_samples = n - n0
        self._geometry = plan.geometry
        self._signals = [np.ascontiguousarray(signals[ch], dtype=float) for ch in plan.names]
        shift = [float((offsets or {}).get(ch, 0.0)) for ch in plan.names]
        if self.n_samples > _BLOCKED_SAMPLES:
            self._offsets = shift
        else:
            self._signals = [u - m if m else u for u, m in zip(self._signals, shift)]
            self._offsets = [0.0] * len(shift)
        self._centred_block: tuple[int, int, dict[int, np.ndarray]] = (0, 0, {})
        self._cand_ch, self._cand_lag, self._cand_lmin = plan.ch, plan.lag, plan.lmin
        self._squares: dict[int, np.ndarray] = {}
        self._table_keys = np.empty(0, dtype=np.int64)  # tabulated shape keys, sorted
        self._table_slots = np.empty(0, dtype=np.intp)  # their rows in the tables
        self._sums = np.empty(0)
        self._head_sums = np.empty((0, n0 + 1))
        self._tail_sums = np.empty((0, n0 + 1))
        # the signals near each end of the window, E[ch, i, rel] = u_ch(lo + i - rel), with
        # one more "channel" of ones for absent factors
        self._head_edges, self._tail_edges = self._edges(0), self._edges(n - n0)
        self._gram_rows: tuple[np.ndarray, np.ndarray] | None = None  # rows of a Gram column
        # everything the search needs before its first step, in one planned batch
        with part("first pass"):
            first, rows = self._apply(plan.first, *plan.rows), plan.first_rows
        self.y_mean, self.y_mean_sq = float(first[rows.y_mean]), float(first[rows.y_mean_sq])
        self.means, self.target, self.diag = first[rows.means], first[rows.target], first[rows.diag]
        self._columns = dict(zip(plan.linear.tolist(),
                                 first[rows.columns].reshape(len(plan.linear), len(terms))))

    def column(self, j: int) -> np.ndarray:
        """mean(p_c p_j) for every candidate c."""
        if j in self._columns:
            return self._columns[j]
        with part("Gram columns"):
            return self._new_column(j)

    def _new_column(self, j: int) -> np.ndarray:
        """Gram column ``j`` from new sums."""
        # the first column asked for that the first batch left out: all of them at once if
        # planned (the tables are still those of the first batch), else this one alone
        gram = gram_columns(*self._plan_key)
        if gram is not None:
            values = self._apply(gram.batch, *gram.rows).reshape(len(gram.columns), -1)
            self._columns.update(zip(gram.columns.tolist(), values))
            return self._columns[j]
        width = self._cand_ch.shape[1]
        if self._gram_rows is None:  # every candidate's factors, then room for candidate j's
            pad = np.full((len(self._cand_ch), width), -1, dtype=np.int64)
            self._gram_rows = (np.hstack([self._cand_ch, pad]),
                               np.hstack([self._cand_lag, np.zeros_like(pad)]))
        ch, lag = self._gram_rows
        ch[:, -width:], lag[:, -width:] = self._cand_ch[j], self._cand_lag[j]
        lmin = np.minimum(self._cand_lmin, self._cand_lmin[j])
        batch = plan_batch(self._geometry, ch, lag, lmin, self._table_keys, self._table_slots)
        return self._apply(batch, ch, lag, extra=(self._cand_ch[j], self._cand_lag[j]))

    # -- moments ---------------------------------------------------------------------------

    def _apply(self, batch: Batch, ch: np.ndarray, lag: np.ndarray,
               extra: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """Window means of the products given row-wise by (channel, lag), as ``batch`` plans.

        ``extra`` is the factor row ``(channels, lags)`` common to every product
        (the selected term of a Gram column), in the last slots of each row;
        directly summed rows use it as a shared weight.
        """
        if batch.new is not None:
            self._add_shapes(batch, batch.new)
        table, s = batch.table, batch.slot
        lo = batch.lmin[table]
        tabulated = self._sums[s] + self._head_sums[s, self._n0 - lo] - self._tail_sums[s, lo]
        if table.all():
            return tabulated / self.n_samples
        out = np.empty(len(ch))
        out[table] = tabulated
        direct = ~table
        if extra is None:
            out[direct] = self._direct_sums(ch[direct], lag[direct], None)
        else:
            w = len(extra[0])
            out[direct] = self._direct_sums(ch[direct, :-w], lag[direct, :-w], extra)
        return out / self.n_samples

    def _factor(self, ch: int, rel: int, lo: int, hi: int) -> np.ndarray:
        """u_ch(t - rel) for t = lo..hi-1 (needs lo >= rel), a view: do not write into it.

        A signal with an offset is centred once per block of the window (see
        :meth:`_enter_block`), the view taken from that; a range outside the block, anew.
        """
        values, offset = self._signals[ch][lo - rel : hi - rel], self._offsets[ch]
        if not offset:
            return values
        start, stop, centred = self._centred_block
        if not start <= lo - rel <= hi - rel <= stop:
            return values - offset
        if ch not in centred:
            centred[ch] = self._signals[ch][start:stop] - offset
        return centred[ch][lo - rel - start : hi - rel - start]

    def _enter_block(self, lo: int, hi: int) -> None:
        """Make the block ``lo..hi-1`` (and the lag window before it) the one centred."""
        self._centred_block = (max(lo - self._n0, 0), hi, {})

    def _power(self, ch: int | None, rel: int, k: int, lo: int, hi: int) -> np.ndarray:
        """u_ch(t - rel)^k (k = 1 or 2) for t = lo..hi-1.

        ``ch`` None gives ones (the empty product).  The squares of a whole
        signal are computed once; on a window summed in blocks, a block's each
        time (they are cheap, and a record-long array per channel is what
        blocks avoid).
        """
        if ch is None:
            return np.ones(hi - lo)
        if k == 1:
            return self._factor(ch, rel, lo, hi)
        if self.n_samples > _BLOCKED_SAMPLES:
            return np.square(self._factor(ch, rel, lo, hi))
        if ch not in self._squares:
            self._squares[ch] = np.square(self._signals[ch])
        return self._squares[ch][lo - rel : hi - rel]

    def _blocks(self) -> list[tuple[int, int]]:
        """Return the ranges ``lo..hi-1`` of the window over which sums are accumulated.

        The whole window when it is at most ``_BLOCKED_SAMPLES`` long, else
        blocks of ``_BLOCK`` samples.
        """
        n0, n = self._n0, self._n
        if n - n0 <= _BLOCKED_SAMPLES:
            return [(n0, n)]
        return [(lo, min(lo + _BLOCK, n)) for lo in range(n0, n, _BLOCK)]

    def _edges(self, lo: int) -> np.ndarray:
        """Return E[ch, i, rel] = u_ch(lo + i - rel) for i < N0, rel <= N0.

        Zero before the record starts, and a last channel of ones.
        """
        n0 = self._n0
        near = np.zeros((len(self._signals) + 1, 2 * n0))  # near[ch, m] = u_ch(lo - N0 + m)
        skip = max(n0 - lo, 0)
        for row, u, offset in zip(near, self._signals, self._offsets):
            row[skip:] = u[lo - n0 + skip : lo + n0] - offset
        near[-1] = 1.0
        return near[:, _edge_index(n0)]

    def _walk(self, prefixes: Iterable[tuple[tuple[int, int], ...]], lo: int, hi: int,
              root: np.ndarray | None = None) -> Iterator[tuple[tuple, np.ndarray | None]]:
        """Yield ``(prefix, product)`` over ``t = lo..hi-1`` for each prefix, in sorted order.

        Partial products start from ``root`` and are shared depth-first;
        ``None`` stands for the empty product.  A yielded product is only
        valid until the next one (buffers are reused); ``lo >= N0``.
        """
        stack: list[tuple[tuple, np.ndarray | None]] = [((), root)]
        for prefix in sorted(set(prefixes)):
            while stack[-1][0] != prefix[: len(stack[-1][0])]:
                stack.pop()
            while len(stack[-1][0]) < len(prefix):
                depth = len(stack[-1][0])
                f = self._factor(*prefix[depth], lo, hi)
                if stack[-1][1] is None:
                    prod = f
                else:  # one buffer per depth: a product lives only while its prefix is on the stack
                    prod = np.multiply(stack[-1][1], f, out=_scratch(depth, hi - lo))
                stack.append((prefix[: depth + 1], prod))
            yield prefix, stack[-1][1]

    def _add_shapes(self, batch: Batch, new: NewShapes) -> None:
        """Tabulate the batch's new shapes: their sum over the window and near each end."""
        n0 = self._n0
        sums = np.zeros(len(new.ch))
        # the product of each group's leading factors over a block, shared depth-first
        for lo, hi in self._blocks():
            self._enter_block(lo, hi)
            for prefix, prefix_product in self._walk(new.groups, lo, hi):
                for (ch, k), (rows, rels) in new.groups[prefix].items():
                    sums[rows] += self._lagged_sums(prefix_product, ch, k, rels, lo, hi)
            if new.pair_steps is not None:
                self._add_pair_steps(sums, new.pair_steps, lo, hi)
        # near the ends: products of every shape at once, then cumulative sums
        head = np.zeros((len(sums), n0 + 1))  # head[a] = sum_{t=a}^{N0-1}
        head[:, :n0] = np.cumsum(
            self._head_edges[new.ch, :, new.rel].prod(axis=1)[:, ::-1], axis=1)[:, ::-1]
        tail = np.zeros((len(sums), n0 + 1))  # tail[b] = sum_{t=N-b}^{N-1}
        tail[:, 1:] = np.cumsum(self._tail_edges[new.ch, :, new.rel].prod(axis=1)[:, ::-1], axis=1)
        self._sums = np.concatenate([self._sums, sums])
        self._head_sums = np.concatenate([self._head_sums, head])
        self._tail_sums = np.concatenate([self._tail_sums, tail])
        self._table_keys, self._table_slots = batch.keys, batch.slots

    def _add_pair_steps(self, sums: np.ndarray, plan: PairSteps, lo: int, hi: int) -> None:
        """Add to ``sums`` the shapes of ``plan`` summed over ``t = lo..hi-1``.

        The pair products are formed over spans of at most ``_PAIR_SPAN`` samples (and
        the ``N0`` before each, the tails' lags), at most ``_PAIR_VALUES`` values at a
        time; each step is one matrix product per ``_PAIR_CHUNK`` samples of a span,
        which keeps its rows in cache.
        """
        n0 = self._n0
        span = max(_PAIR_CHUNK, min(_PAIR_SPAN, _PAIR_VALUES // len(plan.pairs)))
        acc = [np.zeros((h_hi - h_lo, t_hi - t_lo)) for _, h_lo, h_hi, t_lo, t_hi, *_ in plan.steps]
        rows = np.empty((len(plan.pairs), min(span, hi - lo) + n0))
        for a in range(lo, hi, span):
            b = min(a + span, hi)
            z = rows[:, : b - a + n0]  # z[:, i] is at sample a - N0 + i
            for i, (c1, c2, d) in enumerate(plan.pairs.tolist()):
                skip = max(d - (a - n0), 0)  # before the record: never read (see PairSteps)
                z[i, :skip] = 0.0
                np.multiply(self._factor(c1, 0, a - n0 + skip, b),
                            self._factor(c2, d, a - n0 + skip, b), out=z[i, skip:])
            for c in range(n0, b - a + n0, _PAIR_CHUNK):
                d = min(c + _PAIR_CHUNK, b - a + n0)
                for (q, h_lo, h_hi, t_lo, t_hi, *_), out in zip(plan.steps, acc):
                    out += z[h_lo:h_hi, c:d] @ z[t_lo:t_hi, c - q : d - q].T
        for (*_, shapes, h, t), out in zip(plan.steps, acc):
            sums[shapes] += out[h, t]

    def _lagged_sums(
        self, weight: np.ndarray | None, ch: int, k: int, rels: np.ndarray, lo: int, hi: int,
    ) -> np.ndarray:
        """Return ``sum_t weight(t) u_ch(t - rel)^k`` over ``t = lo..hi-1`` for each ``rel``.

        ``rel`` ascending; ``weight`` None: ones.  ``weight`` is the product of the
        moment's other factors over those samples.

        Several lags of one signal are one correlation (a dot product per lag
        in C) when they fill at least half of their range.
        """
        src = None if ch < 0 else ch
        first, last = rels[0].item(), rels[-1].item()
        if weight is None and k == 2 and src is not None:  # sums of squares, without forming them
            return np.array([f @ f for f in (self._factor(src, r, lo, hi) for r in rels.tolist())])
        if weight is None or len(rels) == 1 or last - first + 1 > 2 * len(rels):
            sums = []
            for r in rels.tolist():
                f = self._power(src, r, k, lo, hi)
                sums.append(f.sum() if weight is None else weight @ f)
            return np.array(sums)
        # u(t - last)^k for t = lo .. hi - 1 + last - first: correlation lag j is rel = last - j
        series = self._power(src, last, k, lo, hi + last - first)
        return np.correlate(series, weight, "valid")[last - rels]

    def _product(self, ch: np.ndarray, lag: np.ndarray, lo: int, hi: int) -> np.ndarray:
        """Return the product of the factors (channel, lag) over ``t = lo..hi-1``, a new array."""
        out = np.ones(hi - lo)
        for c, k in zip(ch.tolist(), lag.tolist()):
            if c >= 0:
                out *= self._factor(c, k, lo, hi)
        return out

    def _direct_sums(self, ch: np.ndarray, lag: np.ndarray,
                     weight: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray:
        """Sum each row's product times the product of the factors ``weight`` over the window.

        Partial products are shared, and the lags of a row's last factor are summed as one
        correlation where they are dense.  ``weight`` None: ones.
        """
        if weight is not None and self._use_gram(ch, lag):
            return self._weighted_gram_sums(ch, lag, weight)
        groups = direct_groups(ch, lag)
        out = np.zeros(len(ch))
        for lo, hi in self._blocks():
            self._enter_block(lo, hi)
            root = None if weight is None else self._product(*weight, lo, hi)
            for prefix, prefix_product in self._walk(groups, lo, hi, root):
                for (c, k), (rows, lags) in groups[prefix].items():
                    out[rows] += self._lagged_sums(prefix_product, c, k, lags, lo, hi)
        return out

    def _use_gram(self, ch: np.ndarray, lag: np.ndarray) -> bool:
        """Whether :meth:`_weighted_gram_sums` beats one dot product per row.

        On a long window the dot products are bound by memory traffic (each
        reads two arrays larger than the cache); a blocked weighted Gram
        matrix works in cache and is several times faster, when every row is
        a product of two factors and the rows fill a good part of the matrix.
        """
        if self.n_samples < _GEMM_SAMPLES or ch.shape[1] < 2 or (ch[:, 2:] >= 0).any():
            return False
        if (ch[:, :2] < 0).any():
            return False
        n_factors = len(np.unique(ch[:, :2] * self._geometry.stride + lag[:, :2]))
        return 4 * len(ch) >= n_factors**2

    def _weighted_gram_sums(self, ch: np.ndarray, lag: np.ndarray,
                            weight: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """``sum_t w(t) u_a(t - l_a) u_b(t - l_b)`` over the window for each row's two factors.

        ``w`` is the product of the factors ``weight``.  The entries of the
        weighted Gram matrix ``X' diag(w) X`` of the rows' distinct factors,
        accumulated over blocks of ``_CHUNK`` samples.
        """
        pairs = np.stack([ch[:, :2], lag[:, :2]], axis=-1)  # (rows, 2 factors, (ch, lag))
        factors, index = np.unique(pairs.reshape(-1, 2), axis=0, return_inverse=True)
        index = index.reshape(-1, 2)
        gram = np.zeros((len(factors), len(factors)))
        n0, n = self._n0, self._n
        with one_blas_thread():  # threads only slow products this small
            for lo in range(n0, n, _CHUNK):
                hi = min(lo + _CHUNK, n)
                x = np.stack([self._factor(c, k, lo, hi) for c, k in factors.tolist()])
                gram += (x * self._product(*weight, lo, hi)) @ x.T
        return gram[index[:, 0], index[:, 1]]


class PooledCorrelations:
    """Correlations over several windows: the contiguous segments of a record with gaps.

    Each part gives means over its own window (each segment with its own lag
    window, so no lag reaches across a gap); their sample-weighted average is
    the mean over all the windows together.
    """

    def __init__(self, parts: Sequence) -> None:
        weights = np.array([p.n_samples for p in parts], dtype=float)
        self._parts, self._w = parts, weights / weights.sum()
        self.n_samples = int(weights.sum())
        self.y_mean = float(sum(w * p.y_mean for w, p in zip(self._w, parts)))
        self.y_mean_sq = float(sum(w * p.y_mean_sq for w, p in zip(self._w, parts)))
        self.means = sum(w * p.means for w, p in zip(self._w, parts))
        self.target = sum(w * p.target for w, p in zip(self._w, parts))
        self.diag = sum(w * p.diag for w, p in zip(self._w, parts))

    def column(self, j: int) -> np.ndarray:
        """Return Gram column ``j``: the parts' columns, weighted by their samples."""
        return sum(w * p.column(j) for w, p in zip(self._w, self._parts))


# From this many candidates of degree 3 or 4, the blocked products of pair products
# (fosmodel.core.pairs) beat the tables and direct sums here, first fits and later ones (on
# 20,000 samples: 1,770 cubic candidates over 20 lags about even, 10,625 of degree 4 over
# 20 lags and inputs 1.3 to 2.2 times faster).  Below it the tables' shared shapes win.
_PAIR_CANDIDATES = 2000


def fast_correlations(
    terms: Sequence[Term], signals: Mapping[str, np.ndarray], start: int, *,
    offsets: Mapping[str, float] | None = None,
) -> LagCorrelations | PairCorrelations:
    """Return the fast correlation provider for these candidates over the window ``start..N-1``.

    :class:`fosmodel.core.pairs.PairCorrelations` for large sets of products of degree
    3 or 4, :class:`LagCorrelations` otherwise; both exact, with the parameters of
    :class:`LagCorrelations` (its default table degree).
    """
    degree = max((t.degree for t in terms), default=0)
    if 3 <= degree <= MAX_DEGREE and len(terms) >= _PAIR_CANDIDATES:
        return PairCorrelations(terms, signals, start, offsets=offsets)
    return LagCorrelations(terms, signals, start, offsets=offsets)
