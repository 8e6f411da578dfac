"""Before/after ratios with confidence intervals, from the windows' long-run variance.

Each ratio compares two models on the same windows of the prediction
segment: the one-step squared errors sample by sample, the residual's means
over windows of each length, each outage window's mean square and position
error.  The ratio of mean squares ``R = mean(b^2) / mean(a^2)`` (its square
root for an RMS) is, to first order, ``log R = mean(z)`` with
``z = b^2 / mean(b^2) - a^2 / mean(a^2)`` per window (the delta method).
Consecutive windows of a slow error are correlated, so the variance of
``mean(z)`` is its long-run variance, not ``var(z) / n``: the Bartlett lag
window estimate of it is what the moving-block bootstrap of the pairs gives,
in closed form (Kuensch 1989, sec. 3: the block bootstrap's variance of a mean
is the Bartlett-window spectral estimate at frequency zero, the block length
its lag window).  The lag window follows the data (Andrews 1991's rule for an
AR(1) of ``z``), the variance is scaled by ``n / (n - l - 1)`` for the means it
subtracts, and the quantile is Student's with a degree of freedom per lag
window less one, as for batch means (Schmeiser 1982): with the few windows of a
long outage, a normal quantile, or a resampling, gives intervals too narrow.
Measured on AR(1) windows (400 replicates each), a 95 % interval covers
93-96 % of 60-200 windows with a lag-one correlation up to 0.5, 89-90 % of 20-40
windows or of a correlation of 0.8, where a percentile block bootstrap covers
60-90 %.  No resampling: the same windows always give the same interval.

A ratio is *better* when its interval lies below 1, *worse* when it lies
above, and *undetermined* when it spans 1 or when fewer than
:data:`fosmodel.loop.judge.MIN_INTERVAL_WINDOWS` windows hold it: too few to tell.

References
----------
H. R. Kuensch, "The jackknife and the bootstrap for general stationary
observations", *Annals of Statistics* 17(3), 1989.
D. W. K. Andrews, "Heteroskedasticity and autocorrelation consistent
covariance matrix estimation", *Econometrica* 59(3), 1991.
B. Schmeiser, "Batch size effects in the analysis of simulation output",
*Operations Research* 30(3), 1982.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats

from .judge import MIN_INTERVAL_WINDOWS
from .scores import Scores


@dataclass(frozen=True)
class Ratio:
    """A before/after ratio with its interval and what it says.

    ``verdict`` is ``"better"``, ``"worse"``, ``"undetermined"`` or ``"unchanged"`` (the
    same model's errors); ``why`` says why a ratio is undetermined.
    """

    name: str
    key: str
    value: float
    low: float
    high: float
    windows: int
    verdict: str
    why: str | None = None

    def short(self) -> str:
        """``30 s bias RMS x0.82 (0.74-0.91)``: the ratio and its interval."""
        interval = "" if math.isnan(self.low) else f" ({self.low:.3g}-{self.high:.3g})"
        return f"{self.name} x{self.value:.3g}{interval}"

    def text(self) -> str:
        """``30 s bias RMS x0.82 (0.74-0.91): better``: the ratio and what it says."""
        if self.verdict == "unchanged":
            return f"{self.name} unchanged"
        return self.short() + ": " + (self.verdict if self.why is None
                                      else f"undetermined, {self.why}")

    def to_dict(self) -> dict[str, Any]:
        """Return the ratio as JSON."""
        return {"value": self.value, "interval": [self.low, self.high], "windows": self.windows,
                "verdict": self.verdict, "why": self.why}


def lag_window(z: np.ndarray) -> int:
    """Return the Bartlett lag window of Andrews (1991) for an AR(1) ``z``, at least 1.

    ``1.1447 (alpha n)^(1/3)`` with ``alpha = 4 rho^2 / (1 - rho^2)^2`` and ``rho`` the
    lag-one autocorrelation of ``z`` (held within 0-0.97), below ``n``.
    """
    n = len(z)
    zz = float(z @ z)
    rho = min(max(float(z[1:] @ z[:-1]) / zz, 0.0), 0.97) if zz > 0 and n > 1 else 0.0
    alpha = 4 * rho**2 / (1 - rho**2) ** 2
    return int(min(max(n - 1, 1), max(1, math.ceil(1.1447 * (alpha * n) ** (1 / 3)))))


def ratio_interval(a: np.ndarray, b: np.ndarray, confidence: float,
                   power: float = 1.0) -> tuple[float, float, float]:
    """``(mean(b^2) / mean(a^2))^power`` and its interval at ``confidence``.

    ``a`` and ``b`` are the two models' values on the same windows, in order.
    """
    a2, b2 = np.square(np.asarray(a, float)), np.square(np.asarray(b, float))
    n = len(a2)
    ratio_ = float(b2.mean() / a2.mean())
    z = b2 / b2.mean() - a2 / a2.mean() if b2.mean() > 0 else -a2 / a2.mean()
    z = z - z.mean()
    lags = lag_window(z)
    gamma = [float(z[k:] @ z[: n - k]) / n for k in range(lags + 1)]
    variance = gamma[0] + 2 * sum((1 - k / (lags + 1)) * gamma[k] for k in range(1, lags + 1))
    se = math.sqrt(max(variance, 0.0) / max(n - lags - 1, 1))
    t = float(stats.t.ppf((1 + confidence) / 2, max(1, n // (lags + 1) - 1)))
    return (ratio_**power, (ratio_ * math.exp(-t * se)) ** power,
            (ratio_ * math.exp(t * se)) ** power)


def ratio(name: str, key: str, a: np.ndarray, b: np.ndarray, confidence: float,
          power: float = 1.0, least: int = MIN_INTERVAL_WINDOWS) -> Ratio:
    """Return the :class:`Ratio` of ``b`` to ``a`` over their windows, with what it says."""
    windows = len(a)
    if np.array_equal(a, b):
        return Ratio(name, key, 1.0, 1.0, 1.0, windows, "unchanged")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))) or not np.any(a):
        return Ratio(name, key, math.nan, math.nan, math.nan, windows, "undetermined",
                     "a free run diverged" if np.any(np.isfinite(a)) else "no errors")
    if windows < least:
        value = float((np.sum(np.square(b)) / np.sum(np.square(a))) ** power)
        return Ratio(name, key, value, math.nan, math.nan, windows, "undetermined",
                     f"only {windows} windows, fewer than the {least} an interval needs")
    value, low, high = ratio_interval(a, b, confidence, power)
    if high < 1:
        return Ratio(name, key, value, low, high, windows, "better")
    if low > 1:
        return Ratio(name, key, value, low, high, windows, "worse")
    return Ratio(name, key, value, low, high, windows, "undetermined",
                 f"the {confidence:.0%} interval spans 1")


def ratios(before: Scores, after: Scores, confidence: float) -> list[Ratio]:
    """Return every before/after ratio of two models' scores on the same segment.

    The one-step MSE, and at every horizon the bias RMS, the outage MSE and the outage
    position error (where the sensor and units give it).
    """
    out = [ratio("one-step MSE", "mse", before.errors, after.errors, confidence)]
    for h, a in before.outages.items():
        b = after.outages[h]
        out.append(ratio(f"{h:g} s bias RMS", f"bias_rms_{h:g}s", a.bias, b.bias, confidence,
                         power=0.5))
        out.append(ratio(f"{h:g} s outage MSE", f"outage_mse_{h:g}s", np.sqrt(a.mse),
                         np.sqrt(b.mse), confidence))
        if a.position is not None and b.position is not None:
            out.append(ratio(f"{h:g} s outage position error", f"outage_position_{h:g}s",
                             a.position, b.position, confidence, power=0.5))
    return out
