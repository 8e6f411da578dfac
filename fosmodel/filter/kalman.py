"""A small linear discrete Kalman filter, for the error models of :mod:`fosmodel.filter.statespace`.

System and measurement::

    x[k] = Phi x[k-1] + B u[k] + G w[k],   var(w) = Q
    z[k] = H x[k] + v[k],                  var(v) = R

The update uses the Joseph form ``P = (I - K H) P (I - K H)' + K R K'``, which keeps ``P``
symmetric and positive semi-definite over long runs with precise measurements.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InputError
from .statespace import StateSpace


def _matrix(value: ArrayLike, shape: tuple[int, int], name: str) -> np.ndarray:
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if arr.shape != shape or not np.isfinite(arr).all():
        raise InputError(f"{name} must be a finite {shape[0]} x {shape[1]} matrix, "
                         f"got shape {arr.shape}")
    return arr


class KalmanFilter:
    """Linear Kalman filter: :meth:`predict` one sample, :meth:`update` with a measurement.

    Parameters
    ----------
    Phi : array-like of shape (n, n)
        State transition.
    G : array-like of shape (n, r)
        Noise input.
    Q : array-like of shape (r, r)
        Driving-noise covariance.
    H : array-like of shape (d, n)
        Measurement matrix.
    R : array-like of shape (d, d)
        Measurement-noise covariance.
    x0 : array-like of shape (n,)
        Initial state estimate.
    P0 : array-like of shape (n, n)
        Its covariance.
    B : array-like of shape (n, m), optional
        Input matrix (no inputs by default).

    Attributes
    ----------
    x, P : ndarray
        The current estimate and its covariance.
    K : ndarray or None
        Gain of the last update.
    """

    def __init__(self, Phi: ArrayLike, G: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike,
                 x0: ArrayLike, P0: ArrayLike, B: ArrayLike | None = None) -> None:
        n = np.atleast_2d(Phi).shape[0]
        self.Phi = _matrix(Phi, (n, n), "Phi")
        self.G = _matrix(G, (n, np.atleast_2d(G).shape[1]), "G")
        self.GQG = self.G @ _matrix(Q, (self.G.shape[1],) * 2, "Q") @ self.G.T
        self.H = _matrix(H, (np.atleast_2d(H).shape[0], n), "H")
        self.R = _matrix(R, (self.H.shape[0],) * 2, "R")
        self.B = np.zeros((n, 0)) if B is None else _matrix(B, (n, np.atleast_2d(B).shape[1]), "B")
        self.x = _matrix(x0, (1, n), "x0")[0].copy()
        self.P = _matrix(P0, (n, n), "P0").copy()
        self.K: np.ndarray | None = None
        self._eye = np.eye(n)

    @classmethod
    def from_state_space(cls, system: StateSpace, R: ArrayLike, x0: ArrayLike,
                         P0: ArrayLike) -> KalmanFilter:
        """Build the filter of a :class:`~fosmodel.filter.statespace.StateSpace`.

        The state is measured through the system's ``H``.
        """
        return cls(system.Phi, system.G, system.Q, system.H, R, x0, P0, system.B)

    def predict(self, u: ArrayLike | None = None) -> None:
        """Propagate to the next sample: ``x = Phi x + B u``, ``P = Phi P Phi' + G Q G'``."""
        self.x = self.Phi @ self.x
        if self.B.shape[1]:
            if u is None:
                raise InputError(f"this filter has {self.B.shape[1]} input(s); u is needed")
            self.x += self.B @ np.asarray(u, dtype=float)
        self.P = self.Phi @ self.P @ self.Phi.T + self.GQG

    def update(self, z: ArrayLike) -> None:
        """Correct the estimate with the measurement ``z`` (Joseph form)."""
        measured = np.atleast_1d(np.asarray(z, dtype=float))
        ph = self.P @ self.H.T
        s = self.H @ ph + self.R
        # a scalar measurement (the usual case) divides; a vector one solves
        self.K = ph / s[0, 0] if s.shape == (1, 1) else np.linalg.solve(s, ph.T).T
        self.x = self.x + self.K @ (measured - self.H @ self.x)
        a = self._eye - self.K @ self.H
        self.P = a @ self.P @ a.T + self.K @ self.R @ self.K.T


class FilterRun(NamedTuple):
    """Estimates after each sample of :func:`run_filter`."""

    x: np.ndarray
    """ndarray of shape (N, n): the state estimates."""
    variance: np.ndarray
    """ndarray of shape (N, n): the diagonals of their covariances."""


def run_filter(kf: KalmanFilter, z: ArrayLike, inputs: ArrayLike | None = None, *,
               engine: str = "numpy") -> FilterRun:
    """Predict each sample, and update where a measurement is given.

    Parameters
    ----------
    kf : KalmanFilter
        Holding the estimate at the sample before the first; it is advanced in place.
    z : array-like of shape (N,) or (N, d)
        Measurements; NaN marks a sample without one (prediction only).
    inputs : array-like of shape (N, m), optional
        ``u`` of each sample, for a filter with inputs.
    engine : {"numpy", "numba", "auto"}
        ``"numba"`` runs the compiled loop of :mod:`fosmodel.filter.kalman_numba` (a scalar
        measurement only; the ``fast`` extra); ``"auto"`` does so where it can (numba
        installed, ``FOSMODEL_NUMBA`` not ``0``, one measurement) and runs the NumPy loop
        otherwise.  Both give the same estimates to rounding (the compiled loop leaves
        ``kf.K`` as it was).

    Returns
    -------
    FilterRun

    Raises
    ------
    InputError
        An unknown engine, ``"numba"`` without numba or with a vector measurement, or
        inputs missing for a filter with inputs.
    """
    if engine not in ("numpy", "numba", "auto"):
        raise InputError(f"engine must be 'numpy', 'numba' or 'auto', got {engine!r}")
    zs = np.asarray(z, dtype=float)
    zs = zs.reshape(len(zs), -1)
    us = None if inputs is None else np.asarray(inputs, dtype=float)
    if engine != "numpy":
        kernel = _compiled_filter()
        usable = kernel is not None and zs.shape[1] == 1
        if engine == "numba" and not usable:
            raise InputError("engine='numba' needs numba (pip install 'fosmodel[fast]') and a "
                             "scalar measurement")
        if usable and kernel is not None:
            return _run_compiled(kernel, kf, zs[:, 0], us)
    xs = np.empty((len(zs), len(kf.x)))
    var = np.empty_like(xs)
    measured = np.isfinite(zs).all(axis=1)
    for k, zk in enumerate(zs):
        kf.predict(None if us is None else us[k])
        if measured[k]:
            kf.update(zk)
        xs[k], var[k] = kf.x, kf.P.diagonal()
    return FilterRun(xs, var)


def _run_compiled(kernel: Callable[..., tuple], kf: KalmanFilter, z: np.ndarray,
                  us: np.ndarray | None) -> FilterRun:
    m = kf.B.shape[1]
    if m and us is None:
        raise InputError(f"this filter has {m} input(s); u is needed")
    u = np.zeros((len(z), 0)) if us is None or not m else np.ascontiguousarray(
        us.reshape(len(z), m))
    xs, var, x, p = kernel(kf.Phi, kf.GQG, np.ascontiguousarray(kf.H[0]), float(kf.R[0, 0]),
                           np.ascontiguousarray(kf.B), kf.x, kf.P, np.ascontiguousarray(z), u)
    kf.x, kf.P = x, p
    return FilterRun(xs, var)


@functools.cache
def _compiled_filter() -> Callable[..., tuple] | None:
    """Return the numba loop, or None without numba or with ``FOSMODEL_NUMBA=0``."""
    if os.environ.get("FOSMODEL_NUMBA", "1") == "0":
        return None
    try:
        from .kalman_numba import scalar_filter
    except ImportError:
        return None
    return scalar_filter
