"""FOS correlations of many products of degree up to 4, as blocked products of pair products.

A candidate set of products of up to four lagged factors (SysIdentPy's degree-4
NARX set over ten output and ten input lags holds 10,626) is too large for the
correlation tables of :mod:`fosmodel.core.correlations`: a Gram column of a
degree-4 term is a moment of degree up to 8 with every candidate, and such
moments rarely share a shape.  Here every candidate ``p_c`` is split into a
*head* and a *tail* of at most two factors each (its factors sorted, padded
with ones in front), so that

    sum_t w(t) p_c(t) = sum_t [w(t) head_c(t)] tail_c(t),

one entry of the weighted product ``(w H)^T T`` of the matrices of head and tail
products.  Heads sorted by their last factor and tails by their first, the
entries the candidates need lie in a staircase; it is covered by *tiles*, one
matrix product per block of heads over the range of tails it needs, so that
the products compute about twice the entries needed instead of every pair.

The window is summed in blocks of ``_ROWS`` samples.  A block holds the factors,
head and tail products of its samples: ``(factors + heads + tails) x _ROWS`` values,
4 MB for 20 factors (231 heads, 230 tails), whatever the record's length; the
tiles hold under twice ``C`` sums, and the search ``C x M`` correlations.  No matrix of
candidates over the samples (``N x C``) is ever formed, and no candidate of
degree 3 or 4 is ever evaluated: the products of degree 2 are built once per
block of each pass.  The point-by-point reference is
:class:`fosmodel.core.fos.DataCorrelations` on the matrix of
:func:`fosmodel.core.candidates.evaluate_terms`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .candidates import OUTPUT, Factor, Term
from .timing import count, part

MAX_DEGREE = 4  # heads and tails of two factors each
_ROWS = 1024  # samples per block: a block's products stay in cache
_TILE = 32  # heads per matrix product


@dataclass(frozen=True)
class PairPlan:
    """The data-free part of :class:`PairCorrelations`: factors, heads, tails and tiles.

    Symbol 0 is the constant one; symbol ``s >= 1`` is channel ``names[ch[s]]`` at lag
    ``lag[s]``.  ``heads`` and ``tails`` hold the symbols of each distinct head and tail
    (``half`` each); ``tiles`` the ranges ``(h_lo, h_hi, t_lo, t_hi)`` of heads and tails
    multiplied together; ``where`` the index of each candidate's sum in the tiles' entries,
    laid out tile after tile, row by row.
    """

    names: tuple[str, ...]
    ch: np.ndarray
    lag: np.ndarray
    symbols: np.ndarray  # (C, 2 * half): each candidate's symbols, sorted, ones first
    heads: np.ndarray
    tails: np.ndarray
    head_groups: tuple[tuple[int, np.ndarray | slice], ...]
    tail_groups: tuple[tuple[int, np.ndarray | slice], ...]
    tiles: tuple[tuple[int, int, int, int], ...]
    where: np.ndarray
    n_entries: int


@lru_cache(maxsize=8)
def pair_plan(factors: tuple[tuple[Factor, ...], ...]) -> PairPlan:
    """Plan the pair products of the candidates with these factors (one tuple each).

    Cached: fits of one candidate set share it (its arrays are read-only).

    Raises
    ------
    ValueError
        A candidate with more than :data:`MAX_DEGREE` factors, or no candidate.
    """
    if not factors:
        raise ValueError("no candidate to plan")
    degree = max(len(fs) for fs in factors)
    if degree > MAX_DEGREE:
        raise ValueError(f"pair products serve degrees up to {MAX_DEGREE}, not {degree}")
    names = (OUTPUT, *sorted({ch for fs in factors for ch, _ in fs} - {OUTPUT}))
    index = {ch: i for i, ch in enumerate(names)}
    distinct = sorted({(index[ch], lag or 0) for fs in factors for ch, lag in fs})
    symbol = {f: s + 1 for s, f in enumerate(distinct)}
    half = 1 if degree <= 2 else 2
    symbols = np.zeros((len(factors), 2 * half), dtype=np.int64)
    for i, fs in enumerate(factors):
        row = sorted(symbol[(index[ch], lag or 0)] for ch, lag in fs)
        if row:
            symbols[i, -len(row):] = row
    # heads by their last symbol, tails by their first: the entries needed form a staircase
    heads, head_of = np.unique(symbols[:, :half], axis=0, return_inverse=True)
    tails, tail_of = np.unique(symbols[:, half:], axis=0, return_inverse=True)
    head_order = np.lexsort(heads.T)  # last symbol first: lexsort's primary key is the last
    tail_order = np.lexsort(tails.T[::-1])
    head_rank, tail_rank = np.empty_like(head_order), np.empty_like(tail_order)
    head_rank[head_order], tail_rank[tail_order] = np.arange(len(heads)), np.arange(len(tails))
    heads, tails = heads[head_order], tails[tail_order]
    h, t = head_rank[head_of.ravel()], tail_rank[tail_of.ravel()]
    tiles, where, start = [], np.empty(len(factors), dtype=np.intp), 0
    for h_lo in range(0, len(heads), _TILE):
        h_hi = min(h_lo + _TILE, len(heads))
        rows = np.flatnonzero((h >= h_lo) & (h < h_hi))
        t_lo, t_hi = int(t[rows].min()), int(t[rows].max()) + 1
        tiles.append((h_lo, h_hi, t_lo, t_hi))
        where[rows] = start + (h[rows] - h_lo) * (t_hi - t_lo) + t[rows] - t_lo
        start += (h_hi - h_lo) * (t_hi - t_lo)
    ch = np.array([-1] + [c for c, _ in distinct], dtype=np.int64)
    lag = np.array([0] + [g for _, g in distinct], dtype=np.int64)
    plan = PairPlan(names, ch, lag, symbols, heads, tails, _groups(heads, -1), _groups(tails, 0),
                    tuple(tiles), where, start)
    for a in (ch, lag, symbols, heads, tails, where):
        a.flags.writeable = False
    return plan


def _groups(pairs: np.ndarray, key: int) -> tuple[tuple[int, np.ndarray | slice], ...]:
    """Consecutive rows of ``pairs`` that share the symbol in column ``key``, and their others.

    ``((symbol, others), ...)``: each group's products are the factor rows ``others`` (a
    slice when they are consecutive symbols) times the row ``symbol``, one broadcast
    product per group.  A single column (degree up to 2) is one group per symbol whose
    other factor is the one.
    """
    if pairs.shape[1] == 1:
        pairs = np.column_stack([np.zeros(len(pairs), dtype=pairs.dtype), pairs])
        key = -1
    other = pairs[:, 0] if key == -1 else pairs[:, -1]
    bounds = np.flatnonzero(np.diff(pairs[:, key])) + 1
    groups: list[tuple[int, np.ndarray | slice]] = []
    for rows in np.split(np.arange(len(pairs)), bounds):
        symbols = other[rows]
        if (np.diff(symbols) == 1).all():
            groups.append((int(pairs[rows[0], key]), slice(int(symbols[0]), int(symbols[-1]) + 1)))
        else:
            symbols.flags.writeable = False
            groups.append((int(pairs[rows[0], key]), symbols))
    return tuple(groups)


class PairCorrelations:
    """Correlations of products of up to four lagged factors over the window ``n = start..N-1``.

    The provider interface of :class:`fosmodel.core.fos.Correlations`, like
    :class:`fosmodel.core.correlations.LagCorrelations`, for candidate sets too large
    for its tables.

    Parameters
    ----------
    terms : sequence of Term
        The candidates, at most :data:`MAX_DEGREE` factors each (lags at most ``start``).
    signals : mapping of str to 1-D array
        ``y`` and every channel or column the terms read, all of length N.
    start : int
        N0, the first sample of the fitting window.
    offsets : mapping of str to float, optional
        Subtracted from the named signals before any product (their centring), block by
        block: no centred copy of a signal is made.
    """

    def __init__(
        self,
        terms: Sequence[Term],
        signals: Mapping[str, np.ndarray],
        start: int,
        *,
        offsets: Mapping[str, float] | None = None,
    ) -> None:
        with part("plan"):  # cached: only a first fit of the set plans
            plan = pair_plan(tuple(t.factors for t in terms))
        self._plan = plan
        self._signals = [np.asarray(signals[ch], dtype=float) for ch in plan.names]
        self._offsets = [float((offsets or {}).get(ch, 0.0)) for ch in plan.names]
        self._n0, self._n = start, len(self._signals[0])
        self.n_samples = self._n - start
        # work arrays of one block, reused: fresh arrays this size pay a page fault per
        # 4 kB on first touch, which costs more than the products written into them
        rows = min(_ROWS, max(self.n_samples, 1))
        self._f = np.empty((len(plan.ch) + 1, rows))
        self._heads = np.empty((len(plan.heads), rows))
        self._tails = np.empty((len(plan.tails), rows))
        y = self._signals[0][start:] - self._offsets[0]
        self.y_mean, self.y_mean_sq = float(y.mean()), float(y @ y) / self.n_samples
        y_row = len(plan.ch)  # a block's factors end with y, which no candidate holds
        with part("first pass"):
            self.means, self.target, self.diag = self._sums(
                [lambda f: None, lambda f: f[y_row]], squares=True)

    def column(self, j: int) -> np.ndarray:
        """mean(p_c p_j) for every candidate c."""
        mine = self._plan.symbols[j]
        with part("Gram columns"):
            (out,) = self._sums([lambda f: np.prod(f[mine], axis=0)])
        return out

    def _factors(self, lo: int, hi: int) -> np.ndarray:
        """Return the factors over ``t = lo..hi-1``: a row per symbol (row 0 ones), then y."""
        plan = self._plan
        f = self._f[:, : hi - lo]
        f[0] = 1.0
        for s in range(1, len(plan.ch)):
            c, lag = int(plan.ch[s]), int(plan.lag[s])
            np.subtract(self._signals[c][lo - lag : hi - lag], self._offsets[c], out=f[s])
        np.subtract(self._signals[0][lo:hi], self._offsets[0], out=f[-1])
        return f

    def _sums(self, weights: list, squares: bool = False) -> list[np.ndarray]:
        """Window means of ``weight(t) p_c(t)`` for each weight, and of ``p_c(t)^2`` if asked.

        Each weight is a function of a block's factors returning the weight over the
        block (None: ones).
        """
        plan = self._plan
        acc = np.zeros((len(weights) + int(squares), plan.n_entries))
        for lo in range(self._n0, self._n, _ROWS):
            hi = min(lo + _ROWS, self._n)
            f = self._factors(lo, hi)
            heads, tails = self._heads[:, : hi - lo], self._tails[:, : hi - lo]
            with part("pair products"):
                _products(f, plan.tail_groups, None, tails)
            for k, weight in enumerate(weights):
                with part("pair products"):
                    _products(f, plan.head_groups, weight(f), heads)
                with part("tile products"):
                    _add_tiles(acc[k], heads, tails, plan.tiles)
            if squares:
                with part("pair products"):
                    f *= f
                    _products(f, plan.tail_groups, None, tails)
                    _products(f, plan.head_groups, None, heads)
                with part("tile products"):
                    _add_tiles(acc[-1], heads, tails, plan.tiles)
            count("tile multiply-adds", (len(weights) + squares) * plan.n_entries * (hi - lo))
        return [a[plan.where] / self.n_samples for a in acc]


def _products(f: np.ndarray, groups: Sequence[tuple[int, np.ndarray | slice]],
              weight: np.ndarray | None, out: np.ndarray) -> None:
    """Write into ``out`` the pair products of the factor rows ``f`` that ``groups`` name.

    A group's rows are ``f[others] * f[symbol]``, times ``weight`` if given: the weight
    multiplies that one row, not every product.
    """
    start = 0
    for symbol, others in groups:
        scale = f[symbol] if weight is None else f[symbol] * weight
        part = f[others]
        np.multiply(part, scale, out=out[start : start + len(part)])
        start += len(part)


def _add_tiles(acc: np.ndarray, left: np.ndarray, right: np.ndarray,
               tiles: Sequence[tuple[int, int, int, int]]) -> None:
    """Add each tile's ``left[h_lo:h_hi] @ right[t_lo:t_hi].T`` to its entries of ``acc``."""
    start = 0
    for h_lo, h_hi, t_lo, t_hi in tiles:
        size = (h_hi - h_lo) * (t_hi - t_lo)
        block = acc[start : start + size].reshape(h_hi - h_lo, t_hi - t_lo)
        block += left[h_lo:h_hi] @ right[t_lo:t_hi].T
        start += size
