"""The Allan deviation of a rate record, its confidence intervals and its classic read-offs.

:func:`allan_deviation` computes the overlapping Allan deviation of a rate
signal (gyro in deg/s, accelerometer in m/s^2, ...) with :func:`allantools.oadev`
and a 68 % confidence interval per averaging time from Greenhall's equivalent
degrees of freedom (:func:`allantools.edf_greenhall`) and the chi-square
distribution (:func:`allantools.confidence_interval`); :func:`spectral_line`
finds a clear line in the record's spectrum (a vibration, a pump), which the fit
takes as IEEE Std 952's sinusoidal term.  :func:`readoff` gives the classic
graphical read-offs of the curve, for comparison with the fit.

The IEEE Std 952 noise fit is :mod:`fosmodel.noise.allan_fit`; the figure and the
files written, :mod:`fosmodel.noise.allan_report`.

References
----------
.. [1] IEEE Std 952-1997, "IEEE Standard Specification Format Guide and Test Procedure for
   Single-Axis Interferometric Fiber Optic Gyros", IEEE, 1997.
.. [2] M. El-Diasty, A. El-Rabbany and S. Pagiatakis, "Stochastic Characteristics of
   Temperature-Dependent MEMS-Based Inertial Sensor Error", Proceedings of the ION
   National Technical Meeting, San Diego, CA, 2007.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import allantools
import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.ndimage import median_filter
from scipy.signal import welch

from ..core.blas import one_blas_thread
from ..core.exceptions import InputError
from ..core.validation import as_signal, check_positive
from .metrics import to_si_scale

#: Fewest samples analysed: one decade of averaging times (m = 1 .. MIN_SAMPLES // MIN_CLUSTERS).
MIN_SAMPLES = 100
#: Non-overlapping clusters at the longest default tau: 8 Allan differences, edf >= ~7.
MIN_CLUSTERS = 9
# Records over BLOCKED_SAMPLES have their Allan deviation summed over blocks of BLOCK samples
# (cache-sized); shorter ones go through allantools.oadev as they are (bit-identical results).
BLOCKED_SAMPLES = 2**21
BLOCK = 2**16
#: Averages used to identify the noise type at a tau (fewest, most) for the lag-1 autocorrelation.
ID_AVERAGES = (100, 1000)
#: Confidence of the intervals: one standard deviation of a normal distribution.
ONE_SIGMA = allantools.ci.ONE_SIGMA_CI
#: Allan deviation of flicker noise per unit of bias instability, sqrt(2 ln 2/pi) ~ 0.664.
FLICKER_FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: A spectral line this many times the spectrum's running median is fitted as IEEE Std 952's
#: sinusoidal term.
LINE_PROMINENCE = 20.0


@dataclass(frozen=True)
class AllanResult:
    """Overlapping Allan deviation of a rate record.

    Attributes
    ----------
    taus : ndarray
        Averaging times in seconds (multiples of ``1/rate``).
    adev : ndarray
        Overlapping Allan deviation, in the record's units.
    lower, upper : ndarray
        68.27 % chi-square confidence interval of ``adev``.
    counts : ndarray
        Number of overlapping second differences behind each value.
    edf : ndarray
        Greenhall's equivalent degrees of freedom of each Allan variance.
    alpha : ndarray
        Noise type (power-law exponent of the rate spectrum: 2 quantization,
        0 white, -1 flicker, -2 random walk) the ``edf`` was computed for.
    rate : float
        Sample rate in Hz.
    n_samples : int
        Samples in the record.
    units, sensor : str or None
        Units of the record and ``"gyro"`` or ``"accel"``, if known.
    line_hz : float or None
        Frequency of a clear spectral line in the record (see
        :func:`spectral_line`), fitted as the sinusoidal term; None if there is none.
    """

    taus: np.ndarray
    adev: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    counts: np.ndarray
    edf: np.ndarray
    alpha: np.ndarray
    rate: float
    n_samples: int
    units: str | None = None
    sensor: str | None = None
    line_hz: float | None = None

    def to_frame(self) -> pd.DataFrame:
        """One row per tau: tau, ADEV, its confidence interval, counts, edf and noise type."""
        u = self.units or "units"
        return pd.DataFrame({
            "tau (s)": self.taus, f"ADEV ({u})": self.adev, "lower 68 %": self.lower,
            "upper 68 %": self.upper, "differences": self.counts, "edf": self.edf,
            "alpha": self.alpha,
        })

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable copy."""
        return {
            "rate_hz": self.rate, "n_samples": self.n_samples, "units": self.units,
            "sensor": self.sensor, "taus_s": self.taus.tolist(), "adev": self.adev.tolist(),
            "lower": self.lower.tolist(), "upper": self.upper.tolist(),
            "counts": self.counts.tolist(), "edf": self.edf.tolist(),
            "alpha": self.alpha.tolist(), "confidence": ONE_SIGMA, "line_hz": self.line_hz,
        }


def allan_deviation(
    y: ArrayLike,
    rate: float,
    *,
    units: str | None = None,
    sensor: str | None = None,
    taus: ArrayLike | None = None,
    per_decade: int = 10,
) -> AllanResult:
    """Overlapping Allan deviation of rate data with 68 % confidence intervals.

    Parameters
    ----------
    y : array-like
        Rate samples (gyro rate, specific force, ...), uniformly spaced.
    rate : float
        Sample rate in Hz.
    units : str, optional
        Units of ``y``; with ``sensor`` they give the coefficients in
        navigation units (:func:`fosmodel.noise.metrics.to_si_scale` lists them).
    sensor : {"gyro", "accel"}, optional
        Kind of sensor; needs ``units``.
    taus : array-like, optional
        Averaging times in seconds, rounded to multiples of ``1/rate``.  The
        default is ``per_decade`` log-spaced values from ``1/rate`` to the
        longest tau that leaves :data:`MIN_CLUSTERS` non-overlapping clusters,
        where the equivalent degrees of freedom are still about 7 or more for
        any noise type (the 68 % interval of the deviation within -19 %/+44 %
        at worst, for a random walk); beyond it the estimate is mostly noise.
    per_decade : int
        Averaging times per decade of the default grid.

    Returns
    -------
    AllanResult

    Raises
    ------
    InputError
        Fewer than :data:`MIN_SAMPLES` samples, non-finite or constant data, a
        rate that is not positive, taus outside the analysable range, or
        unknown sensor/units.
    """
    y = as_signal(y, "signal")
    rate = check_positive(rate, "rate")
    _check_units(sensor, units)
    if len(y) < MIN_SAMPLES:
        raise InputError(f"record too short for an Allan variance: {len(y)} samples, need at "
                         f"least {MIN_SAMPLES} (one decade of averaging times)")
    if np.ptp(y) == 0.0:
        raise InputError("the signal is constant: its Allan deviation is zero at every tau")
    ms = averaging_factors(len(y), rate, taus, per_decade)
    taus_s, adev, counts = _oadev(y, rate, ms)
    ms = np.round(taus_s * rate).astype(int)
    if np.any(adev <= 0.0):
        raise InputError(f"the Allan deviation is zero at tau = {taus_s[adev <= 0][0]:g} s: "
                         "the signal is constant over those averaging times")
    alpha = _noise_types(y, ms)
    edf = np.array([allantools.edf_greenhall(alpha=int(a), d=2, m=int(m), N=len(y) + 1,
                                             overlapping=True) for a, m in zip(alpha, ms)])
    lower, upper = np.array([allantools.confidence_interval(d, e) for d, e in zip(adev, edf)]).T
    return AllanResult(taus=taus_s, adev=adev, lower=lower, upper=upper,
                       counts=counts.astype(int), edf=edf, alpha=alpha, rate=rate,
                       n_samples=len(y), units=units, sensor=sensor,
                       line_hz=spectral_line(y, rate, 1.0 / taus_s[-1]))


def _oadev(y: np.ndarray, rate: float,
           ms: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of the rate data ``y`` at the averaging factors ``ms``.

    :func:`allantools.oadev` (NIST SP 1065 eq. 11) for records up to
    ``BLOCKED_SAMPLES`` samples.  On longer ones its whole-record temporaries
    (a second difference of the phase per tau) make each tau a few passes over
    memory, so the same sums are accumulated over blocks of ``BLOCK`` phase
    samples that stay in the cache: equal to allantools' within rounding.

    Returns
    -------
    taus_s, adev, counts : ndarray
        Averaging times (s), deviations and the number of second differences of each.
    """
    if len(y) <= BLOCKED_SAMPLES:
        # a tenth of a sample above each m: allantools truncates tau*rate (2019.9) or rounds
        # it (2024), and either way gets m back, not m - 1 where m/rate*rate falls just short
        taus_s, adev, _, counts = allantools.oadev(y, rate=rate, data_type="freq",
                                                   taus=(ms + 0.1) / rate)
        return taus_s, adev, counts
    phase = allantools.frequency2phase(y, rate)  # allantools' phase, as oadev makes it
    ms = np.unique(ms)
    counts = len(phase) - 2 * ms
    with one_blas_thread():  # a block's dot product is too short to share between threads
        sums = [_second_difference_sum(phase, int(m), int(count)) for m, count in zip(ms, counts)]
    adev = np.sqrt(np.array(sums) / (2.0 * counts)) / ms * rate
    return ms / rate, adev, counts


def _second_difference_sum(phase: np.ndarray, m: int, count: int) -> float:
    """Sum of ``(x[i + 2m] - 2 x[i + m] + x[i])^2`` for ``i < count``, in blocks of ``BLOCK``."""
    total = 0.0
    work = np.empty(BLOCK)
    for lo in range(0, count, BLOCK):
        hi = min(lo + BLOCK, count)
        v = work[: hi - lo]
        np.multiply(phase[lo + m : hi + m], -2.0, out=v)
        v += phase[lo + 2 * m : hi + 2 * m]
        v += phase[lo:hi]
        total += float(v @ v)
    return total


def spectral_line(y: np.ndarray, rate: float, fmin_hz: float) -> float | None:
    """Frequency of the most prominent spectral line above ``fmin_hz``, if it is clear.

    Welch's periodogram (segments of 2^14 samples at most, a few hundred
    frequencies at least) against its running median over 201 bins; a line
    is clear at :data:`LINE_PROMINENCE` times that median.  A line bends the
    Allan deviation over a decade around ``1/f0`` (IEEE Std 952's sinusoidal
    term), where it would otherwise be read as other noise.
    """
    segment = min(2**14, len(y) // 4)
    if segment < 512:
        return None
    freq, power = welch(y - y.mean(), fs=rate, nperseg=segment)
    floor = median_filter(power, 201, mode="nearest")  # zero padding would make edges "lines"
    prominence = power / np.maximum(floor, np.finfo(float).tiny)
    prominence[(freq < fmin_hz) | (np.arange(len(freq)) < 3)] = 0.0
    best = int(np.argmax(prominence))
    return float(freq[best]) if prominence[best] >= LINE_PROMINENCE else None


def _check_units(sensor: str | None, units: str | None) -> None:
    if sensor is None:
        return
    if units is None:
        raise InputError(f"the navigation units of a {sensor} need the units of the record "
                         "(e.g. deg/s or m/s^2)")
    to_si_scale(sensor, units)


def averaging_factors(n: int, rate: float, taus: ArrayLike | None,
                       per_decade: int) -> np.ndarray:
    """Averaging factors ``m`` (tau = m/rate) of :func:`allan_deviation`, sorted and unique.

    ``taus`` None gives its default grid for a record of ``n`` samples: ``per_decade``
    log-spaced factors from 1 to ``n // MIN_CLUSTERS``; given ``taus`` (seconds) are rounded
    to factors and must lie within that range.  Public so that another Allan tool (allantools,
    a benchmark) can be run on the same averaging times.
    """
    m_max = n // MIN_CLUSTERS
    if taus is None:
        if per_decade < 1:
            raise InputError(f"per_decade must be at least 1, got {per_decade}")
        count = math.ceil(per_decade * math.log10(m_max)) + 1
        return np.unique(np.round(np.geomspace(1, m_max, count))).astype(int)
    ms = np.unique(np.round(as_signal(taus, "taus") * rate))
    if ms.size == 0 or ms[0] < 1 or ms[-1] > m_max:
        raise InputError(f"taus must lie between 1/rate = {1 / rate:g} s and {m_max / rate:g} s "
                         f"({MIN_CLUSTERS} clusters of the {n}-sample record)")
    return ms.astype(int)


def _noise_types(y: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """Power-law noise type at each averaging factor, for the equivalent degrees of freedom.

    Lag-1 autocorrelation identification (:func:`allantools.autocorr_noise_id`,
    Riley & Greenhall) on the first ``ID_AVERAGES[1]`` averages of ``m``
    samples (standard error of the autocorrelation 0.03, a tenth of the gap
    between noise types); taus with fewer than ``ID_AVERAGES[0]`` averages keep
    the type of the last identified one.  The sum of IEEE Std 952 terms has a
    dominant exponent that can only fall as tau grows, so the sequence is made
    non-increasing: a spurious identification at long tau can only lower the
    edf (a wider interval), never inflate it.
    """
    fewest = ID_AVERAGES[0]
    alpha: list[int] = []
    for m in ms:
        if len(y) // m >= fewest:
            alpha.append(_identify(y, int(m)))
        else:
            alpha.append(alpha[-1] if alpha else _identify(y, len(y) // fewest))
    return np.minimum.accumulate(np.array(alpha, dtype=int))


def _identify(y: np.ndarray, m: int) -> int:
    """Noise type from the lag-1 autocorrelation of at most ``ID_AVERAGES[1]`` m-averages.

    White frequency noise (0) where that is undefined: averages without
    variation, as on a record that is constant in stretches.
    """
    k = min(len(y) // m, ID_AVERAGES[1])
    try:
        with np.errstate(invalid="ignore", divide="ignore"):
            alpha = allantools.autocorr_noise_id(y[: k * m], m, data_type="freq")[0]
    except ValueError:  # allantools' int(NaN) on an undefined autocorrelation
        return 0
    return int(np.clip(alpha, -2, 2)) if np.isfinite(alpha) else 0


#: A minimum with no significant rise beyond it is a floor when the curve runs on for this many
#: times its tau without going lower; nearer the end it may still be falling.
MIN_BEYOND = 4.0
#: A read-off's slope must hold over this many decades of tau (a line, not a point's wiggle).
READOFF_SPAN_DECADES = 0.5


def readoff(result: AllanResult, slope_tol: float = 0.25) -> dict[str, float]:
    """Classic graphical read-offs of N, K and B from the Allan deviation curve.

    ``N`` is the -1/2 line through the point whose log-log slope is closest to -1/2, read at
    tau = 1 s (``N/sqrt(tau)`` there is ``N``); ``K`` the +1/2 line through the point closest
    to +1/2, read at tau = 3 s (``K sqrt(tau/3)`` there is ``K``).  The slope is the
    least-squares one over :data:`READOFF_SPAN_DECADES` of the curve centred on the point, so
    that a wiggle of the noisy last taus is no +1/2 line.  ``B`` is the minimum deviation
    divided by 0.664 where the minimum is a true one: the curve falls to it by more than an
    earlier point's 68 % interval, and beyond it either rises by more than a later point's
    interval or runs on for :data:`MIN_BEYOND` times its tau without going lower (a flat floor).
    NaN where no slope is within ``slope_tol`` of the nominal one, or the curve has no true
    minimum (it still falls at its last taus).
    """
    log_t, log_a = np.log10(result.taus), np.log10(result.adev)
    slope = _span_slope(log_t, log_a, READOFF_SPAN_DECADES)
    out = {}
    for term, nominal, at in (("N", -0.5, 1.0), ("K", 0.5, 3.0)):
        if not np.isfinite(slope).any():
            out[term] = math.nan
            continue
        i = int(np.nanargmin(np.abs(slope - nominal)))
        line = 10 ** (log_a[i] + nominal * (math.log10(at) - log_t[i]))
        out[term] = line if abs(slope[i] - nominal) <= slope_tol else math.nan
    i = int(np.argmin(result.adev))
    rises = bool(np.any(result.lower[i + 1:] > result.adev[i]))
    floor = result.taus[-1] >= MIN_BEYOND * result.taus[i]
    true = bool(np.any(result.lower[:i] > result.adev[i])) and (rises or floor)
    out["B"] = result.adev[i] / FLICKER_FLOOR if true else math.nan
    out["min_adev"] = float(result.adev[i]) if true else math.nan
    out["min_tau_s"] = float(result.taus[i]) if true else math.nan
    return out


def _span_slope(log_t: np.ndarray, log_a: np.ndarray, span: float) -> np.ndarray:
    """Return the least-squares log-log slope over ``span`` decades centred on each point.

    NaN where the window reaches beyond the curve or holds fewer than three points.
    """
    out = np.full(log_t.shape, np.nan)
    for i, centre in enumerate(log_t):
        lo, hi = centre - span / 2, centre + span / 2
        if lo < log_t[0] - 1e-9 or hi > log_t[-1] + 1e-9:
            continue
        w = (log_t >= lo - 1e-9) & (log_t <= hi + 1e-9)
        if w.sum() >= 3:
            out[i] = np.polyfit(log_t[w], log_a[w], 1)[0]
    return out
