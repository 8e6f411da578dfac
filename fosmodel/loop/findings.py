"""Every diagnostic of :mod:`fosmodel.loop.diagnose` on the current model, on its fitting data.

Only the fitting data: a step's time, a drift's time constant, a line's
frequency found on the evaluation segment would fit it, and the evaluation
would then judge its own choice.  The periodic and nonlinearity tests read the
fast part of the residual (and of the lagged outputs): a wandering bias leaves
a steep low-frequency spectrum and products that track it, which are neither a
line nor a nonlinearity.  Every other channel's correlation with the residual
is tested (a companion's is cross-axis noise, a driver's its fast part), and
each driver's forms against the slow part of the output
(:mod:`fosmodel.loop.slow_driver`).  The channels are prepared once: they do
not change between models.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import uniform_filter1d

from ..models.bound import BoundModel
from .config import LoopConfig
from .diagnose import (
    AuxChannels,
    Finding,
    allan,
    aux_correlation,
    change_point,
    nonlinearity,
    periodic,
    trend,
    whiteness,
)
from .effects import CandidateFamily
from .record import LoopRecord
from .roles import Roles
from .slow_driver import DriverForms, slow_driver


def fast_part(x: np.ndarray, rate: float, slow_s: float,
              out: np.ndarray | None = None) -> np.ndarray:
    """``x`` minus its centred moving mean over ``slow_s`` seconds (written into ``out``).

    The mean is computed into ``out`` (a new array if None) and subtracted there: one
    array of ``x``'s length, not two.
    """
    width = max(3, round(slow_s * rate))
    mean = uniform_filter1d(x, width, mode="nearest", output=out)
    return np.subtract(x, mean, out=mean)


def residual(model: BoundModel, y: np.ndarray, stop: int) -> np.ndarray:
    """One-step residual over the samples before ``stop``, from the lag window on."""
    return (y[:stop] - model.predict(y[:stop]))[model.lag_window_:]


class Diagnostics:
    """Every diagnostic on the residual of the fitting segment ``[0, stop)``."""

    def __init__(self, record: LoopRecord, stop: int, roles: Roles, config: LoopConfig) -> None:
        self.record, self.stop, self.roles, self.config = record, stop, roles, config
        self.channels = {k: record.channels[k] for k in (*roles.drivers, *roles.companions)}
        self._aux: dict[int, AuxChannels] = {}
        self.forms = DriverForms(record, (slice(0, stop),), config.slow_s)

    def __call__(self, model: BoundModel, family: CandidateFamily) -> list[Finding]:
        """Return the findings on ``model``, whose candidate family is ``family``."""
        config, rate, stop, n0 = self.config, self.config.rate, self.stop, model.lag_window_
        y = self.record.y
        r = residual(model, y, stop)
        t = np.arange(n0, stop) / rate
        fast = fast_part(r, rate, config.slow_s)
        fmin = max(5 * rate / len(r), 1.0 / config.slow_s)
        findings = [whiteness(r, alpha=config.alpha),
                    periodic(fast, t, rate, alpha=config.alpha, fmin_hz=fmin)]
        if self.channels:
            if n0 not in self._aux:
                self._aux[n0] = AuxChannels({k: v[n0:stop] for k, v in self.channels.items()})
            findings += aux_correlation(r, self._aux[n0], config.aux_max_lag, alpha=config.alpha)
        if n0 >= config.nonlinear_lags:
            findings.append(self._nonlinearity(fast, n0))
        findings += [trend(r, t, alpha=config.alpha), change_point(r, t, alpha=config.alpha),
                     allan(r, rate, alpha=config.alpha)]
        if self.roles.slow:
            comp = family.compensation_series()
            target = y if comp is None else y - comp
            findings += [slow_driver(target, ch, self.forms, config.alpha)
                         for ch in self.roles.slow]
        return findings

    def _nonlinearity(self, fast: np.ndarray, n0: int) -> Finding:
        """Test the residual for products of the fast parts of the lagged outputs."""
        config, stop = self.config, self.stop
        # filtered one lag at a time into the matrix: the filter of the whole matrix, or a
        # stack of the filtered columns, would hold two copies of it
        lagged = np.empty((stop - n0, config.nonlinear_lags))
        for k in range(1, config.nonlinear_lags + 1):
            fast_part(self.record.y[n0 - k : stop - k], config.rate, config.slow_s,
                      out=lagged[:, k - 1])
        return nonlinearity(fast, lagged, alpha=config.alpha)
