"""Free runs of a fitted FOS expansion: the model fed its own predictions.

In an outage the error model compensates the sensor by its free run: from
the true past up to the outage start, each new sample is the model's own
prediction, and so are the samples its lagged outputs and its local levels
(:mod:`fosmodel.core.levels`) read from then on.  Inputs (other channels, user
columns) are known throughout.

A fitted expansion is split once (:func:`split_expansion`) into

* the weights ``phi`` of the linear output lags and ``w`` of the linear levels,
* the *drive*: every term free of the output (constant, inputs, columns),
* the nonlinear terms: products with at least one output lag or level.

:func:`run_one` is the reference: one run, sample by sample in plain Python
floats.  :func:`run_many` runs many outages at once: a linear model by
superposition (the response to the state at the outage start plus the
response to the drive, both from one pass over the outage length, cached),
a nonlinear one by a recursion vectorised across the outages, compiled by numba
where the ``fast`` extra is installed (:mod:`fosmodel.models.freerun_numba`).  Each is
tested against :func:`run_one`.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import oaconvolve

from ..core.candidates import OUTPUT, Term
from ..core.exceptions import InputError
from ..core.levels import checked_level_tau, is_level, level_gain

_BLOCK = 64  # rows of the response computed one by one; the rest a block at a time


@dataclass(frozen=True)
class NonlinearTerm:
    """A product with output lags or levels: ``coef * rest * prod(y[n-lag]) * prod(level)``.

    ``rest`` is the product of the term's input factors (None: no such factor).
    """

    coef: float
    rest: Term | None
    lags: tuple[int, ...]
    levels: tuple[int, ...]


@dataclass(frozen=True, eq=False)
class Expansion:
    """A fitted expansion in the form a free run needs (see the module docstring).

    Attributes
    ----------
    phi : ndarray of shape (L,)
        Weights of the linear ``y[n-1] .. y[n-L]``.
    gains, weights : ndarray of shape (J,)
        ``a = 1/(tau rate)`` of each level and the weight of its linear term.
    intercept : float
    drive : list of (Term, float)
        Terms free of the output and its levels, with their weights.
    nonlinear : list of NonlinearTerm
    """

    phi: np.ndarray
    gains: np.ndarray
    weights: np.ndarray
    intercept: float
    drive: list[tuple[Term, float]]
    nonlinear: list[NonlinearTerm]
    _responses: dict = field(default_factory=dict, repr=False)

    @property
    def lag_window(self) -> int:
        """Number of output lags the expansion reads (``L``)."""
        return len(self.phi)

    def responses(self, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """``(R, h)`` of the linear part over ``n_steps`` samples (cached).

        With the state ``z[n] = [y[n-1] .. y[n-L], level_1[n] .. level_J[n]]``
        (centred) a linear run is ``y[n] = c z[n] + d[n]`` and
        ``z[n+1] = M z[n] + g d[n]``; so ``y[s+k] = R[k] z[s] + sum_m h[m]
        d[s+k-m]`` with ``R[k] = c M^k``, ``h[0] = 1`` and ``h[m] = c M^(m-1) g``.
        """
        if n_steps not in self._responses:
            self._responses[n_steps] = _responses(self.phi, self.gains, self.weights, n_steps)
        return self._responses[n_steps]


def split_expansion(
    terms: Sequence[Term], coef: Sequence[float] | np.ndarray, intercept: float, max_lag: int,
    level_names: Sequence[str], rate: float | None,
) -> Expansion:
    """Split a fitted model's terms for its free runs."""
    index = {name: j for j, name in enumerate(level_names)}
    gains = np.zeros(len(level_names))
    if level_names:
        if rate is None:
            raise InputError("a model with levels needs its sample rate (rate=...)")
        gains[:] = [level_gain(checked_level_tau(name), rate) for name in level_names]
    phi, weights = np.zeros(max_lag), np.zeros(len(level_names))
    drive, nonlinear = [], []
    for term, c in zip(terms, coef):
        lags, level_channels, rest = _term_parts(term)
        levels = tuple(index[ch] for ch in level_channels)
        if not lags and not levels:
            drive.append((term, float(c)))
        elif term.degree == 1 and lags:
            phi[lags[0] - 1] += c
        elif term.degree == 1:
            weights[levels[0]] += c
        else:
            nonlinear.append(NonlinearTerm(float(c), Term(rest) if rest else None, lags, levels))
    return Expansion(phi, gains, weights, float(intercept), drive, nonlinear)


@functools.lru_cache(maxsize=4096)
def _term_parts(term: Term) -> tuple[tuple[int, ...], tuple[str, ...], tuple]:
    """Return a term's output lags, level channels and other factors.

    Cached: every fit splits its terms, and on a small fit this scan of their factors
    took about 5 % of its time (25 us of 0.5 ms).
    """
    lags = tuple(lag for ch, lag in term.factors if ch == OUTPUT and lag is not None)
    levels = tuple(ch for ch, _ in term.factors if is_level(ch))
    rest = tuple(f for f in term.factors if f[0] != OUTPUT and not is_level(f[0]))
    return lags, levels, rest


def _responses(phi: np.ndarray, gains: np.ndarray, weights: np.ndarray,
               n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    p, j = len(phi), len(gains)
    m = np.zeros((p + j, p + j))
    if p:
        m[1:p, : p - 1] = np.eye(p - 1)
    m[p:, p:] = np.diag(1.0 - gains)
    g = np.zeros(p + j)
    if p:
        g[0] = 1.0
    g[p:] = gains
    return linear_responses(m, g, np.r_[phi, weights], n_steps)


def linear_responses(m: np.ndarray, g: np.ndarray, c: np.ndarray,
                     n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the responses ``(R, h)`` of a linear recursion over ``n_steps`` samples.

    The recursion is ``y[n] = c z[n] + d[n]``, ``z[n+1] = A z[n] + g y[n]`` with ``m = A``:
    ``R[k] = c M^k``, ``h[0] = 1``, ``h[k] = c M^(k-1) g`` with ``M = A + g c``, and a run
    is ``R z[s] + h * d``.
    """
    m = m + np.outer(g, c)
    r = np.empty((n_steps, len(c)))
    row = np.asarray(c, dtype=float).copy()
    block = min(n_steps, _BLOCK)
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(block):
            r[k] = row
            row = row @ m
        power = np.linalg.matrix_power(m, block)
        for k in range(block, n_steps, block):  # a block of rows at a time: R[k+j] = R[j] M^k
            stop = min(k + block, n_steps)
            r[k:stop] = r[k - block : stop - block] @ power
    h = np.empty(n_steps)
    if n_steps:
        h[0] = 1.0
        h[1:] = r[:-1] @ g
    return r, h


def superpose(r: np.ndarray, h: np.ndarray, state: np.ndarray, drive: np.ndarray) -> np.ndarray:
    """Run linearly from the states (K, D) with the drives (K, H): ``R z + h * d``.

    A row is NaN from its first non-finite sample on.
    """
    n_steps = drive.shape[1]
    with np.errstate(over="ignore", invalid="ignore"):
        out = state @ r[:n_steps].T
        if np.ptp(drive, axis=1).max(initial=0.0) == 0.0:  # a constant drive: the step response
            out += drive[:, :1] * np.cumsum(h[:n_steps])
        else:
            out += oaconvolve(drive, h[None, :n_steps], axes=1)[:, :n_steps]
    bad = ~np.isfinite(out)
    if bad.any():
        out[np.cumsum(bad, axis=1) > 0] = np.nan
    return out


def run_one(ex: Expansion, past: np.ndarray, levels: np.ndarray, drive: np.ndarray,
            rests: Sequence[np.ndarray | None]) -> np.ndarray:
    """One free run, sample by sample (the reference).

    Parameters
    ----------
    past : ndarray
        The centred output before the run, at least ``ex.lag_window`` samples.
    levels : ndarray of shape (J,)
        The levels at the first sample of the run.
    drive : ndarray of shape (H,)
        The drive terms, intercept and any noise at each sample of the run.
    rests : sequence of (ndarray of shape (H,) or None)
        Each nonlinear term's input factors over the run.

    Returns
    -------
    ndarray of shape (H,)
        Centred output; NaN from a non-finite sample on.
    """
    p = ex.lag_window
    out = past[len(past) - p:].tolist() if p else []
    lv = [float(v) for v in levels]
    lags = [(k + 1, float(ex.phi[k])) for k in np.flatnonzero(ex.phi)]
    linear_levels = [(j, float(ex.weights[j]), float(ex.gains[j])) for j in range(len(lv))]
    nonlinear = [(t.coef, None if r is None else r.tolist(), t.lags, t.levels)
                 for t, r in zip(ex.nonlinear, rests)]
    values = []
    for step, d in enumerate(drive.tolist()):
        n = p + step
        value = d + sum(c * out[n - k] for k, c in lags)
        value += sum(w * lv[j] for j, w, _ in linear_levels)
        for c, rest, t_lags, t_levels in nonlinear:
            prod = c if rest is None else c * rest[step]
            for k in t_lags:
                prod *= out[n - k]
            for j in t_levels:
                prod *= lv[j]
            value += prod
        if not math.isfinite(value):
            values.extend([math.nan] * (len(drive) - step))
            break
        values.append(value)
        out.append(value)
        lv = [v + a * (value - v) for v, (_, _, a) in zip(lv, linear_levels)]
    return np.asarray(values, dtype=float)


def run_many(ex: Expansion, past: np.ndarray, levels: np.ndarray, drive: np.ndarray,
             rests: Sequence[np.ndarray | None]) -> np.ndarray:
    """Many free runs at once: :func:`run_one` for each row of the arguments.

    ``past`` (K, >= L), ``levels`` (K, J), ``drive`` (K, H), each of ``rests``
    (K, H) or None.  Returns (K, H), NaN in a row from its first non-finite sample.
    """
    past = np.asarray(past, dtype=float)
    p = ex.lag_window
    hist = past[:, past.shape[1] - p:] if p else np.zeros((len(past), 0))
    with np.errstate(over="ignore", invalid="ignore"):
        if ex.nonlinear:
            out = _recursion(ex, hist, np.asarray(levels, dtype=float), drive, rests)
        else:
            out = _superposition(ex, hist, np.asarray(levels, dtype=float), drive)
    bad = ~np.isfinite(out)
    if bad.any():
        out[np.cumsum(bad, axis=1) > 0] = np.nan
    return out


def _superposition(ex: Expansion, hist: np.ndarray, levels: np.ndarray,
                   drive: np.ndarray) -> np.ndarray:
    """Linear runs: ``R z[s]`` plus the drive convolved with ``h``."""
    r, h = ex.responses(drive.shape[1])
    return superpose(r, h, np.hstack([hist[:, ::-1], levels]), drive)


def _recursion(ex: Expansion, hist: np.ndarray, levels: np.ndarray, drive: np.ndarray,
               rests: Sequence[np.ndarray | None]) -> np.ndarray:
    """Nonlinear runs: the recursion of :func:`run_one`, compiled where numba is installed.

    Without numba (or with ``FOSMODEL_NUMBA=0`` in the environment) it is
    :func:`_recursion_numpy`, the reference the compiled one is tested against.
    """
    index, coef = _factor_columns(ex, hist.shape[1], levels.shape[1])
    rest = np.ones((drive.shape[0], len(rests), drive.shape[1]))  # (K, T, H): 1 without inputs
    for t, factors in enumerate(rests):
        if factors is not None:
            rest[:, t] = factors
    phi = ex.phi[::-1].copy()  # against the window y[n-p .. n-1]
    kernel = _compiled_recursion()
    if kernel is None:
        return _recursion_numpy(ex, hist, levels, drive, rest, phi, index, coef)
    return kernel(np.ascontiguousarray(hist, dtype=float), np.ascontiguousarray(levels),
                  np.ascontiguousarray(drive, dtype=float), rest, phi,
                  np.asarray(ex.weights, dtype=float), np.asarray(ex.gains, dtype=float),
                  index, coef)


@functools.cache
def _compiled_recursion() -> Callable[..., np.ndarray] | None:
    """Return the numba kernel, or None without numba or with ``FOSMODEL_NUMBA=0``."""
    if os.environ.get("FOSMODEL_NUMBA", "1") == "0":
        return None
    try:
        from .freerun_numba import recursion
    except ImportError:
        return None
    return recursion


def _factor_columns(ex: Expansion, p: int, j: int) -> tuple[np.ndarray, np.ndarray]:
    """Where each nonlinear term's factors are, and its weight.

    Factor f of term t reads column ``index[t, f]`` of ``[y[n-p] .. y[n-1], levels, 1]``
    (the 1 where a term has fewer factors than the widest).
    """
    width = max(len(t.lags) + len(t.levels) for t in ex.nonlinear)
    index = np.full((len(ex.nonlinear), width), p + j)
    for t, term in enumerate(ex.nonlinear):
        cols = [p - lag for lag in term.lags] + [p + i for i in term.levels]
        index[t, : len(cols)] = cols
    return index, np.array([t.coef for t in ex.nonlinear])


def _recursion_numpy(ex: Expansion, hist: np.ndarray, levels: np.ndarray, drive: np.ndarray,
                     rest: np.ndarray, phi: np.ndarray, index: np.ndarray,
                     coef: np.ndarray) -> np.ndarray:
    """Run the recursion of :func:`run_one` one sample of every run at a time.

    Each step is a few array operations whatever the number of terms: the
    linear lags and levels as two products, the nonlinear terms as a gather
    of their factors (output lags, levels, or ones where a term has fewer)
    multiplied column by column.  ``rest`` (K, T, H) holds each term's input
    factors, ``phi`` the weights of the window ``y[n-p] .. y[n-1]``.
    """
    k, n_steps = drive.shape
    p, j = hist.shape[1], levels.shape[1]
    y = np.hstack([hist, np.empty((k, n_steps))])
    lv = levels.copy()
    state = np.ones((k, p + j + 1))
    for step in range(n_steps):
        n = p + step
        state[:, :p], state[:, p : p + j] = y[:, n - p : n], lv
        value = drive[:, step] + state[:, :p] @ phi
        if j:
            value += lv @ ex.weights
        prod = rest[:, :, step] * coef
        for f in range(index.shape[1]):
            prod *= state[:, index[:, f]]
        value += prod.sum(axis=1)
        y[:, n] = value
        lv += ex.gains * (value[:, None] - lv)
    return y[:, p:]
