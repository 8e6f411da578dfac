"""An error model judged in an aided filter: position fixes in cycles, free prediction between.

A static record's error drives a 1-D position/velocity error state (Park 2004, eq. 5.7:
:func:`~fosmodel.filter.statespace.position_velocity_error_model`); the filter gets position
fixes of standard deviation ``sigma`` during the first half of every ``2 * cycle_s`` period
and predicts freely in the second.  The true position error is the double integral of the
compensated error, discretised as the filter propagates it.  What the filter suffers is the
RMS of its position estimate's error; whether it knows it is the ratio of the RMS it claims
(its own sigma) to that, and the normalised estimation error squared (NEES, the error squared
over the filter's variance, averaged: 1 for a consistent filter, well above 1 for an
overconfident one).

:func:`aided_position_run` runs any system whose first state is the position error (a gyro's
tilt chain as well as the accelerometer's), :func:`accelerometer_run` builds the
accelerometer's, and :func:`compare_in_filter` runs several error models on the same record
and fixes.

References
----------
Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to Tracking and
Navigation*, Wiley, 2001, sec. 5.4 (NEES).
M. Park, "Error Analysis and Stochastic Modeling of MEMS based Inertial Sensors for Land
Vehicle Navigation Applications", M.Sc. thesis, UCGE Report 20194, University of Calgary,
2004.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import block_diag

from ..core.exceptions import InputError
from ..core.validation import as_signal
from .kalman import KalmanFilter, run_filter
from .statespace import StateSpace, position_velocity_error_model

__all__ = ["AidedRun", "accelerometer_run", "aided_position_run", "compare_in_filter",
           "integrate", "position_fixes"]


class AidedRun(NamedTuple):
    """The position estimate's error over an aided run, and what the filter claimed."""

    error: np.ndarray
    """Estimated minus true position error at samples 1..N-1."""
    variance: np.ndarray
    """The filter's variance of the position estimate at the same samples."""

    @property
    def rms(self) -> float:
        """RMS of the position estimation error."""
        return float(np.sqrt(np.mean(self.error**2)))

    @property
    def sigma(self) -> float:
        """The RMS the filter claims: the root of its mean variance."""
        return float(np.sqrt(np.mean(self.variance)))

    @property
    def sigma_over_rms(self) -> float:
        """1 for a consistent filter, below 1 for an overconfident one."""
        return self.sigma / self.rms

    @property
    def nees(self) -> float:
        """Mean of the error squared over the variance (1 for a consistent filter)."""
        return float(np.mean(self.error**2 / np.maximum(self.variance, 1e-300)))


def integrate(a: ArrayLike, dt: float) -> np.ndarray:
    """Return the double integral as the filter propagates it: ``v[k] = v[k-1] + dt a[k-1]``."""
    a = np.asarray(a, dtype=float)
    v = dt * np.r_[0.0, np.cumsum(a[:-1])]
    return dt * np.r_[0.0, np.cumsum(v[:-1])]


def position_fixes(n: int, cycle_s: float | None, dt: float) -> np.ndarray:
    """Return where a fix is: everywhere (``cycle_s`` None) or each ``2 cycle_s``'s first half."""
    if cycle_s is None:
        return np.ones(n, dtype=bool)
    if not cycle_s > 0:
        raise InputError(f"cycle_s must be positive, got {cycle_s!r}")
    return (np.arange(n) * dt) % (2 * cycle_s) < cycle_s


def aided_position_run(system: StateSpace, p0: ArrayLike, truth: ArrayLike, noise: ArrayLike,
                       sigma: float, cycle_s: float | None, dt: float,
                       inputs: ArrayLike | None = None, engine: str = "auto") -> AidedRun:
    """Run ``system`` with position fixes ``truth + sigma * noise`` in update/prediction cycles.

    Parameters
    ----------
    system : StateSpace
        Its first state is the position error, measured through ``H = [1, 0, ...]``.
    p0 : array-like of shape (n, n)
        Starting covariance (the state starts at zero).
    truth : array-like of shape (N,)
        The true position error; sample 0 is the start (zero).
    noise : array-like of shape (N,)
        Standard normal draws for the fixes.
    sigma : float
        Standard deviation of a fix.
    cycle_s : float or None
        Seconds of fixes, then as many of prediction; None: a fix at every sample.
    dt : float
        Sampling interval.
    inputs : array-like of shape (N, m), optional
        The system's inputs at samples 0..N-1 (sample 0 is not used).
    engine : str
        :func:`~fosmodel.filter.kalman.run_filter`'s engine.

    Returns
    -------
    AidedRun
    """
    truth = as_signal(truth, "truth")
    noise = as_signal(noise, "noise")
    if len(noise) < len(truth):
        raise InputError(f"noise has {len(noise)} draws for {len(truth)} samples")
    if system.n_inputs and inputs is None:
        raise InputError(f"the system has the input(s) {', '.join(system.input_names)}: "
                         "give inputs")
    kf = KalmanFilter.from_state_space(system, [[sigma**2]], np.zeros(system.n_states), p0)
    z = np.where(position_fixes(len(truth), cycle_s, dt), truth + sigma * noise[: len(truth)],
                 np.nan)
    u = None if not system.n_inputs else np.asarray(inputs, dtype=float)[1:]
    run = run_filter(kf, z[1:], u, engine=engine)
    return AidedRun(run.x[:, 0] - truth[1:], run.variance[:, 0])


def accelerometer_run(error: StateSpace, p0_error: ArrayLike, accel: ArrayLike,
                      noise: ArrayLike, sigma: float, cycle_s: float | None, dt: float,
                      inputs: ArrayLike | None = None, engine: str = "auto") -> AidedRun:
    """:func:`aided_position_run` of an accelerometer error model on a static record.

    ``accel`` is the measured error (the static record itself); the filter starts from
    position and velocity known exactly and the error model's ``p0_error``, and the truth is
    the double integral of ``accel - error.mu`` (the calibrated bias taken out).
    """
    accel = as_signal(accel, "accel")
    system = position_velocity_error_model(error, dt)
    p0 = block_diag(np.zeros((2, 2)), np.asarray(p0_error, dtype=float))
    return aided_position_run(system, p0, integrate(accel - error.mu, dt), noise, sigma,
                              cycle_s, dt, inputs, engine)


def compare_in_filter(models: Mapping[str, tuple[StateSpace, ArrayLike]], accel: ArrayLike,
                      sigma: float, cycle_s: float | None, dt: float, seed: int = 0,
                      inputs: Mapping[str, ArrayLike] | None = None) -> dict[str, AidedRun]:
    """Run each accelerometer error model ``name: (error, p0_error)`` on the same fixes.

    ``inputs`` gives the input matrix of each model that has inputs.
    """
    accel = as_signal(accel, "accel")
    noise = np.random.default_rng(seed).standard_normal(len(accel))
    return {name: accelerometer_run(error, p0, accel, noise, sigma, cycle_s, dt,
                                    (inputs or {}).get(name))
            for name, (error, p0) in models.items()}
