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
candidate matrix is never formed.

Which moments come from the tables, and how shapes are keyed and grouped,
does not depend on the data: :mod:`fosmodel.core.shapes` plans it, once per
candidate set for the batch every fit starts with.  This module does the sums.

:class:`LagCorrelations` is the fast provider for :func:`fosmodel.core.fos.fos_search`;
the point-by-point reference is :class:`fosmodel.core.fos.DataCorrelations` on the
matrix from :func:`fosmodel.core.candidates.evaluate_terms`.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Iterator, Mapping, Sequence
from functools import lru_cache

import numpy as np

from .blas import one_blas_thread
from .candidates import OUTPUT, Term
from .shapes import Batch, NewShapes, direct_groups, layout, plan_batch

_GEMM_SAMPLES = 200_000  # from this window length, weighted sums of pairs go through BLAS
_CHUNK = 4096  # samples per block of those sums: the block's factors stay in cache
_SCRATCH = threading.local()


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
    """

    def __init__(
        self,
        terms: Sequence[Term],
        signals: Mapping[str, np.ndarray],
        start: int,
        *,
        table_degree: int = 3,
    ) -> None:
        plan = layout(tuple(t.factors for t in terms), start, table_degree)
        n, n0 = len(signals[OUTPUT]), start
        self._n, self._n0 = n, n0
        self.n_samples = n - n0
        self._geometry = plan.geometry
        self._signals = [np.ascontiguousarray(signals[ch], dtype=float) for ch in plan.names]
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
        first, rows = self._apply(plan.first, *plan.rows), plan.first_rows
        self.y_mean, self.y_mean_sq = float(first[rows.y_mean]), float(first[rows.y_mean_sq])
        self.means, self.target, self.diag = first[rows.means], first[rows.target], first[rows.diag]
        self._columns = dict(zip(plan.linear.tolist(),
                                 first[rows.columns].reshape(len(plan.linear), len(terms))))

    def column(self, j: int) -> np.ndarray:
        """mean(p_c p_j) for every candidate c."""
        if j in self._columns:
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
            weight = self._product(*extra)
            out[direct] = self._direct_sums(ch[direct, :-w], lag[direct, :-w], weight)
        return out / self.n_samples

    def _factor(self, ch: int, rel: int, lo: int, hi: int) -> np.ndarray:
        """u_ch(t - rel) for t = lo..hi-1, a view (needs lo >= rel)."""
        return self._signals[ch][lo - rel : hi - rel]

    def _power(self, ch: int | None, rel: int, k: int, lo: int, hi: int) -> np.ndarray:
        """u_ch(t - rel)^k (k = 1 or 2; squares are computed once) for t = lo..hi-1.

        ``ch`` None gives ones (the empty product).
        """
        if ch is None:
            return np.ones(hi - lo)
        if k == 1:
            return self._factor(ch, rel, lo, hi)
        if ch not in self._squares:
            self._squares[ch] = np.square(self._signals[ch])
        return self._squares[ch][lo - rel : hi - rel]

    def _edges(self, lo: int) -> np.ndarray:
        """Return E[ch, i, rel] = u_ch(lo + i - rel) for i < N0, rel <= N0.

        Zero before the record starts, and a last channel of ones.
        """
        n0 = self._n0
        near = np.zeros((len(self._signals) + 1, 2 * n0))  # near[ch, m] = u_ch(lo - N0 + m)
        skip = max(n0 - lo, 0)
        for row, u in zip(near, self._signals):
            row[skip:] = u[lo - n0 + skip : lo + n0]
        near[-1] = 1.0
        return near[:, _edge_index(n0)]

    def _walk(self, prefixes: Iterable[tuple[tuple[int, int], ...]], lo: int, hi: int,
              root: np.ndarray | None = None) -> Iterator[tuple[tuple, np.ndarray | None]]:
        """Yield ``(prefix, product)`` over ``t = lo..hi-1`` for each prefix, in sorted order.

        Partial products start from ``root`` and are shared depth-first;
        ``None`` stands for the empty product.  A yielded product is only
        valid until the next one (buffers are reused); always ``lo = N0``.
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
        n, n0 = self._n, self._n0
        sums = np.empty(len(new.ch))
        # the product of each group's leading factors over the window, shared depth-first
        for prefix, prefix_product in self._walk(new.groups, n0, n):
            for (ch, k), (rows, rels) in new.groups[prefix].items():
                sums[rows] = self._lagged_sums(prefix_product, ch, k, rels)
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

    def _lagged_sums(
        self, weight: np.ndarray | None, ch: int, k: int, rels: np.ndarray,
    ) -> np.ndarray:
        """Return ``sum_t weight(t) u_ch(t - rel)^k`` over the window for each ``rel``.

        ``rel`` ascending; ``weight`` None: ones.  ``weight`` is the product of the
        moment's other factors.

        Several lags of one signal are one correlation (a dot product per lag
        in C) when they fill at least half of their range.
        """
        n0, n = self._n0, self._n
        src = None if ch < 0 else ch
        lo, hi = rels[0].item(), rels[-1].item()
        if weight is None and k == 2 and src is not None:  # sums of squares, without forming them
            return np.array([f @ f for f in (self._factor(src, r, n0, n) for r in rels.tolist())])
        if weight is None or len(rels) == 1 or hi - lo + 1 > 2 * len(rels):
            sums = []
            for r in rels.tolist():
                f = self._power(src, r, k, n0, n)
                sums.append(f.sum() if weight is None else weight @ f)
            return np.array(sums)
        # u(t - hi)^k for t = n0 .. n - 1 + hi - lo: correlation lag j is rel = hi - j
        series = self._power(src, hi, k, n0, n + hi - lo)
        return np.correlate(series, weight, "valid")[hi - rels]

    def _product(self, ch: np.ndarray, lag: np.ndarray) -> np.ndarray:
        """Return the product of the factors (channel, lag) over the window, a new array."""
        out = np.ones(self.n_samples)
        for c, k in zip(ch.tolist(), lag.tolist()):
            if c >= 0:
                out *= self._factor(c, k, self._n0, self._n)
        return out

    def _direct_sums(self, ch: np.ndarray, lag: np.ndarray,
                     weight: np.ndarray | None) -> np.ndarray:
        """Sum each row's product times ``weight`` over the window.

        Partial products are shared, and the lags of a row's last factor are summed as one
        correlation where they are dense.
        """
        if weight is not None and self._use_gram(ch, lag):
            return self._weighted_gram_sums(ch, lag, weight)
        groups = direct_groups(ch, lag)
        out = np.empty(len(ch))
        for prefix, prefix_product in self._walk(groups, self._n0, self._n, weight):
            for (c, k), (rows, lags) in groups[prefix].items():
                out[rows] = self._lagged_sums(prefix_product, c, k, lags)
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
                            weight: np.ndarray) -> np.ndarray:
        """``sum_t w(t) u_a(t - l_a) u_b(t - l_b)`` over the window for each row's two factors.

        The entries of the weighted Gram matrix ``X' diag(w) X`` of the rows'
        distinct factors, accumulated over blocks of ``_CHUNK`` samples.
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
                gram += (x * weight[lo - n0 : hi - n0]) @ x.T
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
