"""Linear AR dynamics shared by every model: one-step prediction, free run, roots.

Convention (one place for all methods): ``y[n] - mu = sum_k phi[k-1] (y[n-k] - mu) + e[n]``,
``phi`` the AR weights with the *positive* sign of a regression (statsmodels' ``burg`` and
``yule_walker`` return them this way; Tamazin et al.'s (2013) ``a_k`` of eq. 3 are ``-phi``).
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import lfilter, lfiltic

from ..core.exceptions import InputError, UnstableModelWarning
from ..core.validation import as_signal

_ROWS = 2**14  # predictions per block: the block's terms stay in the cache


def ar_one_step(phi: np.ndarray, mu: float, y: np.ndarray) -> np.ndarray:
    """One-step predictions of ``y`` from its true past, NaN for the first ``len(phi)`` samples."""
    p = len(phi)
    out = np.full(len(y), np.nan)
    if p == 0:
        out[:] = mu
        return out
    term = np.empty(min(_ROWS, len(y)))
    # mu + sum_k phi[k] (y[n-1-k] - mu), the terms added in the order of k, a block of
    # predictions at a time: two to three times as fast as a product with the lag matrix
    # (copied from a strided view), and on OpenBLAS equal to it to the last bit
    for lo in range(p, len(y), _ROWS):
        hi = min(lo + _ROWS, len(y))
        d = y[lo - p : hi - 1] - mu  # d[i] = y[lo - p + i] - mu
        pred, t = out[lo:hi], term[: hi - lo]
        np.multiply(d[p - 1 :], phi[0], out=pred)
        for k in range(1, p):
            pred += np.multiply(d[p - 1 - k : p - 1 - k + hi - lo], phi[k], out=t)
        pred += mu
    return out


def ar_free_run(phi: np.ndarray, past: np.ndarray, drive: np.ndarray) -> np.ndarray:
    """Continue ``past`` (centred) by ``x[n] = sum_k phi[k-1] x[n-k] + drive[n]``.

    ``past`` needs at least ``len(phi)`` samples; returns ``len(drive)`` samples.
    """
    if len(drive) == 0:
        return np.asarray(drive, dtype=float).copy()
    a = np.r_[1.0, -np.asarray(phi, dtype=float)]
    if len(phi) == 0:
        return np.asarray(drive, dtype=float).copy()
    zi = lfiltic([1.0], a, np.asarray(past, dtype=float)[::-1][: len(phi)])
    return lfilter([1.0], a, drive, zi=zi)[0]


def ar_roots(phi: np.ndarray) -> np.ndarray:
    """Roots of ``z^p - phi_1 z^(p-1) - ... - phi_p`` (trailing zero weights dropped)."""
    a = np.trim_zeros(np.asarray(phi, dtype=float), "b")
    return np.roots(np.r_[1.0, -a]) if len(a) else np.empty(0)


def is_stable(phi: np.ndarray) -> bool:
    """Whether every root lies strictly inside the unit circle."""
    return bool(np.all(np.abs(ar_roots(phi)) < 1.0))


def free_run_inputs(
    y_init: ArrayLike, n_steps: object, noise: ArrayLike | None, lag_window: int
) -> tuple[np.ndarray, np.ndarray]:
    """Return the checked ``(past, drive)`` of a free run of ``n_steps`` samples after ``y_init``.

    Raises
    ------
    InputError
        ``y_init`` shorter than the lag window, ``n_steps`` not a non-negative integer,
        or ``noise`` of another length.
    """
    past = as_signal(y_init, "y_init", last=lag_window)  # only these reach the run
    if len(past) < lag_window:
        raise InputError(f"y_init has {len(past)} samples; the model needs at least {lag_window}")
    if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) or n_steps < 0:
        raise InputError(f"n_steps must be a non-negative integer, got {n_steps!r}")
    drive = np.zeros(int(n_steps)) if noise is None else as_signal(noise, "noise")
    if len(drive) != n_steps:
        raise InputError(f"noise has {len(drive)} samples, n_steps is {n_steps}")
    return past, drive


def warn_if_unstable(phi: np.ndarray, what: str) -> None:
    """Warn :class:`UnstableModelWarning` if the AR weights ``phi`` are unstable."""
    if not is_stable(phi):
        rho = float(np.max(np.abs(ar_roots(phi))))
        warnings.warn(UnstableModelWarning(
            f"{what} is unstable (largest root modulus {rho:.4f}); the free run grows without "
            "bound"), stacklevel=3)


def cut_at_divergence(run: np.ndarray) -> np.ndarray:
    """NaN from the first non-finite sample of a free run on, with a warning; ``run`` itself."""
    bad = np.flatnonzero(~np.isfinite(run))
    if bad.size:
        warnings.warn(UnstableModelWarning(
            f"the free run diverged at step {bad[0]}; later samples are NaN"), stacklevel=3)
        run[bad[0]:] = np.nan
    return run
