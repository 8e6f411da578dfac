"""Noise shared by the gyros of an array, correlated across sensors (seed 004).

Seed 004 (sections 6.5-6.6) models an array of same-board MEMS gyros whose
white noises are correlated at equal times: equicorrelated with a factor
``rho`` (``-1/(m-1) <= rho <= 1`` for ``m`` sensors, eq. 6.38) or with a given
correlation matrix.  :class:`CorrelatedWhiteNoise` (ARW) and
:class:`CorrelatedRandomWalk` (RRW, correlated driving noise ``w``) draw all
columns at once from one matrix normal draw.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

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


@dataclass(frozen=True)
class _ArrayNoise(Source):
    channels: tuple[str, ...]
    densities: tuple[float, ...]
    corr: Any = 0.0

    def __post_init__(self):
        channels = tuple(check_column_name(c) for c in self.channels)
        densities = as_float_tuple(self.densities, "densities")
        if len(densities) == 1:
            densities = densities * len(channels)
        if len(densities) != len(channels) or len(set(channels)) != len(channels):
            raise ValueError(f"{self.label}: need distinct channels and one density each")
        corr = correlation(len(channels), self.corr)
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "densities", densities)
        object.__setattr__(self, "corr", tuple(tuple(float(x) for x in row) for row in corr))

    def outputs(self, target):
        return self.channels

    def _draw(self, n, rng):
        return correlated_normal(n, np.asarray(self.corr), rng) * np.asarray(self.densities)

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

    def params(self, rate, units, out):
        p = self._common()
        p["units"] = {"densities": f"{units}/sqrt(Hz)"}
        if units in RATE_UNITS:
            p["arw"] = [density_to_arw(d, units) for d in self.densities]
            p["units"]["arw"] = "deg/sqrt(h)"
        return p


@dataclass(frozen=True)
class CorrelatedRandomWalk(_ArrayNoise):
    """Rate random walks (RRW) on several columns driven by correlated white noise.

    ``densities[j]`` is ``K_j`` in ``[unit]/sqrt(s)``; the increments of all
    columns at one sample have the correlation ``corr`` (seed 004 eq. 6.36).
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
