"""The nonlinear free-run recursion compiled with numba (the ``fast`` extra).

:func:`fosmodel.models.freerun.run_many` uses :func:`recursion` when numba can be
imported and its NumPy recursion otherwise; the two are tested against each other and
against the sample-by-sample reference :func:`~fosmodel.models.freerun.run_one`.  The NumPy
recursion spends its time in the overhead of a dozen small array operations per sample of
an outage (3,000 samples for 30 s at 100 Hz); compiled, a sample is a few multiplications,
and a model-order study with nonlinear models about the level takes about a sixth less time.

This module imports numba: import it only where numba is installed.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def recursion(hist: np.ndarray, levels: np.ndarray, drive: np.ndarray, rest: np.ndarray,
              phi: np.ndarray, weights: np.ndarray, gains: np.ndarray, index: np.ndarray,
              coef: np.ndarray) -> np.ndarray:
    """Run each row of ``drive`` (K, H) from its state (the NumPy recursion's arguments).

    ``hist`` (K, p) the centred outputs before the run, oldest first; ``levels`` (K, J);
    ``rest`` (K, T, H) each nonlinear term's input factors; ``phi`` the weights of the
    window ``y[n-p] .. y[n-1]``; ``index`` (T, F) the column of ``[window, levels, 1]``
    that factor F of term T reads; ``coef`` (T,).
    """
    k, n_steps = drive.shape
    p, j = hist.shape[1], levels.shape[1]
    n_terms, width = index.shape
    out = np.empty((k, n_steps))
    state = np.empty(p + j + 1)  # [y[n-p] .. y[n-1], levels, 1]
    y = np.empty(p + n_steps)
    for row in range(k):
        y[:p] = hist[row]
        state[p : p + j] = levels[row]
        state[p + j] = 1.0
        for step in range(n_steps):
            n = p + step
            state[:p] = y[n - p : n]
            value = drive[row, step]
            for i in range(p):
                value += state[i] * phi[i]
            for i in range(j):
                value += state[p + i] * weights[i]
            for t in range(n_terms):
                prod = rest[row, t, step] * coef[t]
                for f in range(width):
                    prod *= state[index[t, f]]
                value += prod
            y[n] = value
            for i in range(j):
                state[p + i] += gains[i] * (value - state[p + i])
        out[row] = y[p:]
    return out
