"""Every diagnostic of :mod:`fosmodel.loop.diagnose` on the current model, on its fitting data.

Only the fitting data: a step's time, a drift's time constant, a line's
frequency found on the evaluation segment would fit it, and the evaluation
would then judge its own choice.  The periodic and nonlinearity tests read the
fast part of the residual (and of the lagged outputs): a wandering bias leaves
a steep low-frequency spectrum and products that track it, which are neither a
line nor a nonlinearity.  Every other channel's correlation with the residual
is tested (a companion's is cross-axis noise, a driver's its fast part), and
each driver's forms against the slow part of the output
(:mod:`fosmodel.loop.driver_forms`).  The channels are prepared once: they do
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
    mean_stability,
    nonlinearity,
    periodic,
    trend,
    whiteness,
)
from .driver_forms import DriverForms, driver_first, slow_driver, time_like
from .effects import CandidateFamily
from .record import LoopRecord
from .roles import Roles


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
    """Every diagnostic on the residual of the fitting data ``fit`` (sample ranges).

    One range for a record (its fitting segment), one per session for several: the
    residual of each comes from its own model, and the tests read them end to end.
    """

    def __init__(self, record: LoopRecord, fit: tuple[slice, ...], roles: Roles,
                 config: LoopConfig) -> None:
        self.record, self.fit, self.roles, self.config = record, fit, roles, config
        self.channels = {k: record.channels[k] for k in (*roles.drivers, *roles.companions)}
        self._aux: dict[int, AuxChannels] = {}
        self.forms = DriverForms(record, fit, config.slow_s)
        self.first = {ch for ch in roles.slow if time_like(record, fit, ch, config.slow_s)}

    def __call__(self, model: BoundModel, family: CandidateFamily) -> list[Finding]:
        """Return the findings on ``model`` (of one record), whose family is ``family``."""
        y, n0 = self.record.y, model.lag_window_
        return self.of([residual(model, y, p.stop)[p.start:] for p in self.fit], n0, family)

    def of(self, residuals: list[np.ndarray], n0: int,
           family: CandidateFamily) -> list[Finding]:
        """Return the findings on the residuals of each fitting range from its sample ``n0``.

        ``family`` is the candidate family of the models that left them.
        """
        config, rate, y = self.config, self.config.rate, self.record.y
        parts = [slice(p.start + n0, p.stop) for p in self.fit]
        r = np.concatenate(residuals)
        start = parts[0].start if len(parts) == 1 else 0  # several: time runs on end to end
        t = np.arange(start, start + len(r)) / rate
        fast = fast_part(r, rate, config.slow_s)
        fmin = max(5 * rate / len(r), 1.0 / config.slow_s)
        findings = [whiteness(r, alpha=config.alpha),
                    periodic(fast, t, rate, alpha=config.alpha, fmin_hz=fmin)]
        if self.channels:
            if n0 not in self._aux:
                self._aux[n0] = AuxChannels({k: np.concatenate([v[p] for p in parts])
                                             for k, v in self.channels.items()})
            findings += aux_correlation(r, self._aux[n0], config.aux_max_lag, alpha=config.alpha)
        if n0 >= config.nonlinear_lags:
            findings.append(self._nonlinearity(fast, parts))
        findings += [trend(r, t, alpha=config.alpha), mean_stability(r, alpha=config.alpha),
                     change_point(r, t, alpha=config.alpha), allan(r, rate, alpha=config.alpha)]
        if self.roles.slow:
            comp = family.compensation_series()
            target = y if comp is None else y - comp
            findings += [self._driver(target, ch) for ch in self.roles.slow]
        return findings

    def _driver(self, target: np.ndarray, channel: str) -> Finding:
        """Return the driver test; a time-like driver's without the trend rival if it fails."""
        found = slow_driver(target, channel, self.forms, self.config.alpha)
        if found.fired or channel not in self.first:
            return found
        first = driver_first(target, channel, self.forms, self.config.alpha)
        return first if first.fired else found

    def _nonlinearity(self, fast: np.ndarray, parts: list[slice]) -> Finding:
        """Test the residual for products of the fast parts of the lagged outputs."""
        config, y = self.config, self.record.y
        # filtered one lag at a time into the matrix: the filter of the whole matrix, or a
        # stack of the filtered columns, would hold two copies of it
        lagged = np.empty((len(fast), config.nonlinear_lags))
        row = 0
        for p in parts:
            n = p.stop - p.start
            for k in range(1, config.nonlinear_lags + 1):
                fast_part(y[p.start - k : p.stop - k], config.rate, config.slow_s,
                          out=lagged[row : row + n, k - 1])
            row += n
        return nonlinearity(fast, lagged, alpha=config.alpha)
