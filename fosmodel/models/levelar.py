"""The AR and Gauss-Markov baselines about the local level, for a fair comparison with FOS.

FOS with level candidates (:mod:`fosmodel.core.levels`) may follow a wandering bias.
The classical estimators cannot take a level as a regressor, but they can be
fitted to the deviation of the record from its local level,
``d[n] = y[n] - level[n]``, which removes the wander the way a navigation
filter's bias state would::

    y[n] = level[n] + mu + sum_k phi_k (y[n-k] - level[n-k] - mu) + e[n],
    level[n+1] = (1 - a) level[n] + a y[n],      a = 1 / (tau * rate).

``phi`` and ``mu`` come from the base estimator (Yule-Walker, covariance, Burg
or Gauss-Markov) on ``d``.  The level is computed from the true past when
predicting one step, and from the model's own output in a free run.  Unlike
FOS, which weighs each level freely, the level here has weight one: this is
the baseline "AR about the local level", and the study's reports say so.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InputError
from ..core.levels import check_level_rate, level_gain, level_series, smooth_after
from ..core.validation import as_signal
from .baselines import ARModel, GaussMarkovModel
from .freerun import linear_responses, superpose


class LocalLevelAR:
    """A fitted-on-demand baseline ``base`` applied to the record minus its local level.

    Parameters
    ----------
    base : ARModel or GaussMarkovModel
        Unfitted; fitted to ``y - level``.
    tau_s : float
        Time constant of the level in seconds.
    rate : float
        Sample rate in Hz.
    """

    def __init__(self, base: ARModel | GaussMarkovModel, tau_s: float, rate: float) -> None:
        check_level_rate([tau_s], rate)
        self.base, self.tau_s, self.rate = base, float(tau_s), float(rate)
        self._responses: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @property
    def lag_window_(self) -> int:
        """Past samples the model reads: the base estimator's."""
        return self.base.lag_window_

    @property
    def n_terms_(self) -> int:
        """Number of fitted weights: the base estimator's and the level's."""
        return self.base.n_terms_ + 1

    def is_stable(self) -> bool:
        """Whether the base estimator's AR part is stable."""
        return self.base.is_stable()

    def _level(self, y: np.ndarray) -> np.ndarray:
        return level_series(y, self.tau_s, self.rate)

    def fit(self, y: ArrayLike) -> LocalLevelAR:
        """Fit the base estimator to ``y`` minus its level.

        From the second sample on: the level starts at ``y[0]``, so the first deviation is
        zero by construction.
        """
        arr = as_signal(y, "y")
        if len(arr) < 2:
            raise InputError("record too short for a level: fewer than 2 samples")
        self.base.fit((arr - self._level(arr))[1:])
        self._responses.clear()
        return self

    def predict(self, y: ArrayLike) -> np.ndarray:
        """One-step prediction from the true past (NaN over the lag window)."""
        arr = as_signal(y, "y")
        level = self._level(arr)
        return level + self.base.predict(arr - level)

    def simulate(self, y_init: ArrayLike, n_steps: int) -> np.ndarray:
        """Free run after ``y_init``: the level follows the model's own output."""
        past = as_signal(y_init, "y_init")
        p = self.lag_window_
        if len(past) < p:
            raise InputError(f"y_init has {len(past)} samples; the model needs at least {p}")
        level = self._level(past)
        state = self._state(past, np.r_[level, smooth_after(past, self._gain())], len(past))
        return self._run(state[None, :], n_steps)[0]

    def free_runs(self, y: ArrayLike, starts: Sequence[int], n_steps: int) -> np.ndarray:
        """``simulate(y[:s], n_steps)`` for each ``s`` in ``starts``, all at once."""
        arr = as_signal(y, "y")
        series, gain = self._level(arr), self._gain()
        # the level after the record from the (cached) series: smooth_after's value, no new pass
        level = np.r_[series, (1.0 - gain) * series[-1] + gain * arr[-1]]
        states = np.array([self._state(arr, level, int(s)) for s in starts])
        return self._run(states.reshape(len(starts), -1), n_steps)

    def _gain(self) -> float:
        return level_gain(self.tau_s, self.rate)

    def _state(self, y: np.ndarray, level: np.ndarray, s: int) -> np.ndarray:
        """``[y[s-1] .. y[s-p], level[s] .. level[s-p]]`` (``level`` one sample longer)."""
        p = self.lag_window_
        return np.r_[y[s - p : s][::-1], level[s - p : s + 1][::-1]]

    def _run(self, states: np.ndarray, n_steps: int) -> np.ndarray:
        if n_steps not in self._responses:
            self._responses[n_steps] = linear_responses(*self._system(), n_steps)
        r, h = self._responses[n_steps]
        phi, mu = self.base.coef_, self.base.mean_
        drive = np.full((len(states), n_steps), mu * (1.0 - phi.sum()))
        return superpose(r, h, states, drive)

    def _system(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``(A, g, c)`` of :func:`~fosmodel.models.freerun.linear_responses`.

        The state is ``[y[n-1] .. y[n-p], level[n] .. level[n-p]]``.
        """
        phi, a, p = self.base.coef_, self._gain(), self.lag_window_
        size = 2 * p + 1
        shift = np.zeros((size, size))
        shift[1:p, : p - 1] = np.eye(p - 1)  # the lags move down
        shift[p + 1 :, p : 2 * p] = np.eye(p)  # so do the past levels
        shift[p, p] = 1.0 - a  # the new level: (1 - a) level + a y (g)
        g = np.zeros(size)
        g[0], g[p] = 1.0, a
        c = np.r_[phi, 1.0, -phi]
        return shift, g, c
