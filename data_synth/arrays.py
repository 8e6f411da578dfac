"""Noise shared across columns: the gyros of an array (Koldbæk and Totu 2011), the axes of one IMU.

Koldbæk and Totu (2011) (sections 6.5-6.6) models an array of same-board MEMS gyros whose
white noises are correlated at equal times: equicorrelated with a factor
``rho`` (``-1/(m-1) <= rho <= 1`` for ``m`` sensors, eq. 6.38) or with a given
correlation matrix.  :class:`CorrelatedWhiteNoise` (ARW),
:class:`CorrelatedGaussMarkov` (a fast error shared by the axes of one IMU) and
:class:`CorrelatedRandomWalk` (RRW, correlated driving noise ``w``) draw all
columns at once from one matrix normal draw.  The stationary ones give their
per-sample cross-column covariance (:meth:`~_ArrayNoise.covariance`), which the
record's truth sums under ``cross_covariance``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy.signal import lfilter

from data_synth.base import Source, as_float_tuple, check_column_name
from data_synth.units import RATE_UNITS, density_to_arw, random_walk_step, rate_factor, white_sigma
from fosmodel.filter.arrays import correlation


def correlated_normal(n: int, corr: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``(n, m)`` standard normal draws whose columns have correlation ``corr``.

    Uses the symmetric square root from the eigendecomposition, so singular
    matrices (``rho = 1`` or ``rho = -1/(m-1)``) work too.
    """
    w, v = np.linalg.eigh(corr)
    root = v * np.sqrt(np.clip(w, 0.0, None))
    return rng.standard_normal((n, corr.shape[0])) @ root.T


def _validated(label, channels, scales, corr):
    """Distinct column names, one scale each (one value for all) and a valid correlation."""
    channels = tuple(check_column_name(c) for c in channels)
    scales = as_float_tuple(scales, "the scales")
    if len(scales) == 1:
        scales = scales * len(channels)
    if len(scales) != len(channels) or len(set(channels)) != len(channels):
        raise ValueError(f"{label}: need distinct channels and one density or sigma each")
    matrix = correlation(len(channels), corr)
    return channels, scales, tuple(tuple(float(x) for x in row) for row in matrix)


@dataclass(frozen=True)
class _ArrayNoise(Source):
    channels: tuple[str, ...]
    densities: tuple[float, ...]
    corr: Any = 0.0

    def __post_init__(self):
        channels, densities, corr = _validated(self.label, self.channels, self.densities,
                                               self.corr)
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "densities", densities)
        object.__setattr__(self, "corr", corr)

    def outputs(self, target):
        return self.channels

    def _draw(self, n, rng):
        return correlated_normal(n, np.asarray(self.corr), rng) * np.asarray(self.densities)

    def covariance(self, rate: float) -> np.ndarray | None:
        """Per-sample covariance of the columns at equal times, None if not stationary."""
        return None

    def _common(self):
        return {
            "channels": list(self.channels),
            "densities": list(self.densities),
            "correlation": [list(r) for r in self.corr],
        }


@dataclass(frozen=True)
class CorrelatedWhiteNoise(_ArrayNoise):
    """White noise (ARW) on several columns with equal-time correlation ``corr``.

    Column ``j`` has the density ``densities[j]`` in ``[unit]/sqrt(Hz)``; ``corr``
    is a scalar ``rho`` (equicorrelation) or an ``m x m`` correlation matrix.
    """

    kind: ClassVar[str] = "correlated_white_noise"

    def generate(self, n, rate, rng, inputs=None):
        return white_sigma(1.0, rate) * self._draw(n, rng)

    def covariance(self, rate):
        """``corr[i, j] * sigma_i * sigma_j`` with ``sigma = density*sqrt(rate)`` per sample."""
        sigma = np.asarray(self.densities) * math.sqrt(rate)
        return np.asarray(self.corr) * np.outer(sigma, sigma)

    def params(self, rate, units, out):
        p = self._common()
        p["covariance"] = self.covariance(rate).tolist()
        p["units"] = {"densities": f"{units}/sqrt(Hz)", "covariance": f"({units})^2"}
        if units in RATE_UNITS:
            p["arw"] = [density_to_arw(d, units) for d in self.densities]
            p["units"]["arw"] = "deg/sqrt(h)"
        return p


@dataclass(frozen=True)
class CorrelatedRandomWalk(_ArrayNoise):
    """Rate random walks (RRW) on several columns driven by correlated white noise.

    ``densities[j]`` is ``K_j`` in ``[unit]/sqrt(s)``; the increments of all
    columns at one sample have the correlation ``corr`` (Koldbæk and Totu 2011, eq. 6.36).
    """

    kind: ClassVar[str] = "correlated_random_walk"

    def generate(self, n, rate, rng, inputs=None):
        return np.cumsum(random_walk_step(1.0, rate) * self._draw(n, rng), axis=0)

    def params(self, rate, units, out):
        p = self._common()
        p["units"] = {"densities": f"{units}/sqrt(s)"}
        if units in RATE_UNITS:
            p["rrw"] = [d / rate_factor(units) for d in self.densities]
            p["units"]["rrw"] = "deg/sqrt(s^3)"
        return p


@dataclass(frozen=True)
class CorrelatedGaussMarkov(Source):
    """First-order Gauss-Markov errors of several columns whose innovations are correlated.

    Each column is ``x_j[n] = phi x_j[n-1] + w_j[n]`` with one pole
    ``phi = exp(-1/(rate*tau_s))`` and the stationary standard deviation
    ``sigmas[j]``; the innovations of one sample have the correlation ``corr``, so
    the columns have the cross-covariance ``corr[i, j] sigmas[i] sigmas[j] phi^|k|``
    at lag ``k``.  The first sample is drawn from that stationary law.  No column
    enters another: what they share is one disturbance, not a coupling.

    Parameters
    ----------
    channels : sequence of str
        The columns (e.g. the three gyro axes of one IMU).
    sigmas : float or sequence of float
        Stationary standard deviation per column (one value for all), in its unit.
    tau_s : float
        Correlation time in seconds.
    corr : float or array_like
        Equicorrelation ``rho`` or an ``m x m`` correlation matrix.
    """

    channels: tuple[str, ...]
    sigmas: tuple[float, ...]
    tau_s: float
    corr: Any = 0.0
    kind: ClassVar[str] = "correlated_gauss_markov"

    def __post_init__(self):
        channels, sigmas, corr = _validated(self.label, self.channels, self.sigmas, self.corr)
        if not self.tau_s > 0 or min(sigmas) <= 0:
            raise ValueError(f"{self.label}: need tau_s > 0 and sigmas > 0")
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "sigmas", sigmas)
        object.__setattr__(self, "corr", corr)

    def outputs(self, target):
        return self.channels

    def phi(self, rate: float) -> float:
        """The pole at ``rate`` Hz."""
        return math.exp(-1.0 / (rate * self.tau_s))

    def covariance(self, rate: float) -> np.ndarray:
        """Stationary covariance of the columns at equal times (at lag ``k``: times ``phi^k``)."""
        return np.asarray(self.corr) * np.outer(self.sigmas, self.sigmas)

    def generate(self, n, rate, rng, inputs=None):
        z = correlated_normal(n, np.asarray(self.corr), rng) * np.asarray(self.sigmas)
        phi = self.phi(rate)
        z[1:] *= math.sqrt(1.0 - phi * phi)  # z[0] is the stationary start
        return lfilter([1.0], [1.0, -phi], z, axis=0)

    def params(self, rate, units, out):
        return {
            "channels": list(self.channels),
            "sigmas": list(self.sigmas),
            "tau_s": self.tau_s,
            "phi": self.phi(rate),
            "correlation": [list(r) for r in self.corr],
            "covariance": self.covariance(rate).tolist(),
            "units": {"sigmas": units, "tau_s": "s", "covariance": f"({units})^2"},
            "convention": "x_j[n] = phi*x_j[n-1] + w_j[n]; cov(x_i[n], x_j[n-k]) = "
            "covariance[i][j]*phi^|k|",
        }


#: The sources that draw several columns at once.
ARRAY_SOURCES = (_ArrayNoise, CorrelatedGaussMarkov)
