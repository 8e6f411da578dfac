"""Allan variance analysis of rate records and the IEEE Std 952 noise coefficients.

:func:`allan_deviation` computes the overlapping Allan deviation of a rate
signal (gyro in deg/s, accelerometer in m/s^2, ...) with :func:`allantools.oadev`
and a 68 % confidence interval per averaging time from Greenhall's equivalent
degrees of freedom (:func:`allantools.edf_greenhall`) and the chi-square
distribution (:func:`allantools.confidence_interval`).  :func:`fit_noise` fits
the IEEE Std 952 model (seed 001 section 2.1, seed 004 eq. 4.17)::

    sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2

with quantization ``Q``, angle/velocity random walk ``N``, bias instability
``B``, rate random walk ``K`` and rate ramp ``R``.  The model is linear in the
squared coefficients, so it is solved by non-negative least squares on
``sigma^2``.  An Allan variance estimate with ``edf`` degrees of freedom has
the relative variance ``2/edf``, so weighting the residual ``model - sigma^2``
by ``sqrt(edf/2)/model`` is the weighted least squares on the log-log curve to
first order (``ln a - ln b ~ (a - b)/b``); evaluating the weights at the model
rather than at the measured point (iteratively re-weighted) keeps points that
happen to fall low from pulling the fit down.  Standard errors account for
the strong correlation between overlapping estimates at neighbouring taus;
terms not resolved from zero are dropped and the rest refitted.
:func:`readoff` gives the classic graphical read-offs for comparison,
:func:`allan_figure` draws the classic plot and :func:`write_allan` writes the
figure and tables.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import allantools
import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from scipy.optimize import nnls

from .exceptions import InputError
from .metrics import STANDARD_GRAVITY, to_si_scale
from .report import save_figure, write_tables
from .summary import Summary
from .validation import as_signal, did_you_mean

#: The IEEE Std 952 terms, from short to long averaging times.
TERMS = ("Q", "N", "B", "K", "R")
#: Fewest samples analysed: one decade of averaging times (m = 1 .. MIN_SAMPLES // MIN_CLUSTERS).
MIN_SAMPLES = 100
#: Non-overlapping clusters at the longest default tau: 8 Allan differences, edf >= ~7.
MIN_CLUSTERS = 9
#: Averages used to identify the noise type at a tau (fewest, most) for the lag-1 autocorrelation.
ID_AVERAGES = (100, 1000)
#: Confidence of the intervals: one standard deviation of a normal distribution.
ONE_SIGMA = allantools.ci.ONE_SIGMA_CI
#: Allan deviation of flicker noise per unit of bias instability, sqrt(2 ln 2/pi) ~ 0.664.
FLICKER_FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
_MAX_PASSES = 50
_NAMES = {"Q": "quantization", "B": "bias instability", "R": "rate ramp"}
_NAMES_BY_SENSOR = {
    "gyro": {"N": "angle random walk", "K": "rate random walk"},
    "accel": {"N": "velocity random walk", "K": "acceleration random walk"},
    None: {"N": "white noise (ARW/VRW)", "K": "rate random walk"},
}
#: Navigation units per term: (factor from deg/s- or m/s^2-based SI-ish units, label).
_NAV = {
    "gyro": {"Q": (1.0, "deg"), "N": (60.0, "deg/sqrt(h)"), "B": (3600.0, "deg/h"),
             "K": (3600.0 * 60.0, "deg/h/sqrt(h)"), "R": (3600.0**2, "deg/h^2")},
    "accel": {"Q": (1.0, "m/s"), "N": (60.0, "m/s/sqrt(h)"), "B": (1e3 / STANDARD_GRAVITY, "mg"),
              "K": (3600.0 * 60.0, "m/s/h/sqrt(h)"), "R": (3600.0**2, "m/s/h^2")},
}


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
            "alpha": self.alpha.tolist(), "confidence": ONE_SIGMA,
        }


def allan_deviation(
    y: object,
    rate: float,
    *,
    units: str | None = None,
    sensor: str | None = None,
    taus: object | None = None,
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
        navigation units (:func:`fosmodel.metrics.to_si_scale` lists them).
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
    rate = _check_rate(rate)
    _check_units(sensor, units)
    if len(y) < MIN_SAMPLES:
        raise InputError(f"record too short for an Allan variance: {len(y)} samples, need at "
                         f"least {MIN_SAMPLES} (one decade of averaging times)")
    if np.ptp(y) == 0.0:
        raise InputError("the signal is constant: its Allan deviation is zero at every tau")
    ms = _averaging_factors(len(y), rate, taus, per_decade)
    taus_s, adev, _, counts = allantools.oadev(y, rate=rate, data_type="freq", taus=ms / rate)
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
                       n_samples=len(y), units=units, sensor=sensor)


def _check_rate(rate: float) -> float:
    try:
        value = float(rate)
    except (TypeError, ValueError):
        raise InputError(f"rate must be a number in Hz, got {rate!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"rate must be a finite number > 0 Hz, got {rate!r}")
    return value


def _check_units(sensor: str | None, units: str | None) -> None:
    if sensor is None:
        return
    if units is None:
        raise InputError(f"the navigation units of a {sensor} need the units of the record "
                         "(e.g. deg/s or m/s^2)")
    to_si_scale(sensor, units)


def _averaging_factors(n: int, rate: float, taus: object | None, per_decade: int) -> np.ndarray:
    """Averaging factors ``m`` (tau = m/rate), sorted and unique, within 1 .. n // MIN_CLUSTERS."""
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


def _basis(taus: np.ndarray, terms: tuple[str, ...]) -> np.ndarray:
    """Allan variance of each term per unit squared coefficient, one column per term."""
    t = np.asarray(taus, dtype=float)
    columns = {"Q": 3.0 / t**2, "N": 1.0 / t, "B": np.full_like(t, FLICKER_FLOOR**2),
               "K": t / 3.0, "R": t**2 / 2.0}
    return np.column_stack([columns[k] for k in terms])


@dataclass(frozen=True)
class NoiseFit:
    """IEEE Std 952 noise coefficients fitted to an Allan deviation.

    Attributes
    ----------
    result : AllanResult
        The Allan deviation that was fitted.
    terms : tuple of str
        Fitted terms among :data:`TERMS`.
    coefficients : dict of str to float
        ``Q`` (units*s), ``N`` (units*sqrt(s)), ``B`` (units), ``K``
        (units/sqrt(s)) and ``R`` (units/s), in the record's units; 0 for the
        terms that are not resolved (unless none is).
    squared_stderr : dict of str to float
        Standard error of each squared coefficient (``Q^2``, ``N^2``, ...),
        the quantities the fit is linear in; see :func:`fit_noise`.  For a
        term that is not resolved, from the last fit it was free in.
    resolved : dict of str to bool
        True when the squared coefficient is more than two standard errors
        above zero; other terms are reported as not resolved.
    limits : dict of str to float
        Upper limits of the terms that are not resolved: the square root of
        their fitted square plus two standard errors of it.
    readoff : dict of str to float
        Classic graphical read-offs for comparison: ``N`` from the -1/2 line at
        tau = 1 s, ``K`` from the +1/2 line at tau = 3 s, ``B`` as the minimum
        deviation / 0.664 (NaN where the curve has no such part).
    """

    result: AllanResult
    terms: tuple[str, ...]
    coefficients: dict[str, float]
    squared_stderr: dict[str, float]
    resolved: dict[str, bool]
    limits: dict[str, float] = field(default_factory=dict)
    readoff: dict[str, float] = field(default_factory=dict)

    @property
    def stderr(self) -> dict[str, float]:
        """Standard error of each coefficient, ``se(c^2)/(2c)``; NaN where the fit put zero."""
        return {k: self.squared_stderr[k] / (2.0 * c) if c > 0 else math.nan
                for k, c in self.coefficients.items()}

    def interval(self, term: str, confidence: float = ONE_SIGMA) -> tuple[float, float]:
        """Confidence interval of a coefficient (NaN where the fit put zero).

        Treats the squared coefficient like an Allan variance with
        ``edf = 2 (c^2/se(c^2))^2`` degrees of freedom (the chi-square whose
        relative standard deviation is that of the estimate), so that poorly
        determined terms get the skewed interval a variance has, through
        :func:`allantools.confidence_interval`.
        """
        c, se = self.coefficients[term], self.squared_stderr[term]
        if not (c > 0 and se > 0):
            return math.nan, math.nan
        with np.errstate(divide="ignore"):  # an upper bound of inf when edf is tiny
            lo, hi = allantools.confidence_interval(c, 2.0 * (c**2 / se) ** 2, confidence)
        return float(lo), float(hi)

    def term_adev(self, term: str, taus: object) -> np.ndarray:
        """Allan deviation of one fitted term at ``taus`` (seconds)."""
        return self.coefficients[term] * np.sqrt(_basis(np.asarray(taus), (term,))[:, 0])

    def model_adev(self, taus: object) -> np.ndarray:
        """Allan deviation of the fitted model (all terms) at ``taus``."""
        squared = np.array([self.coefficients[k] ** 2 for k in self.terms])
        return np.sqrt(_basis(np.asarray(taus, dtype=float), self.terms) @ squared)

    def dominant(self, tau: float) -> str:
        """The resolved term with the largest Allan variance at ``tau`` seconds.

        Among all fitted terms if none is resolved.
        """
        terms = [k for k in self.terms if self.resolved[k]] or self.terms
        return max(terms, key=lambda k: self.term_adev(k, [tau])[0])

    def units(self, term: str) -> str:
        """Units of a coefficient in the record's units."""
        u = self.result.units or "units"
        return {"Q": f"{u}*s", "N": f"{u}*sqrt(s)", "B": u, "K": f"{u}/sqrt(s)",
                "R": f"{u}/s"}[term]

    def navigation(self, term: str) -> tuple[float, str] | None:
        """A coefficient in navigation units (deg/sqrt(h), deg/h, ... or m/s/sqrt(h), mg, ...).

        None unless the record's sensor and units are known.
        """
        sensor, units = self.result.sensor, self.result.units
        if sensor is None or units is None:
            return None
        base = to_si_scale(sensor, units)
        if sensor == "gyro":
            base /= to_si_scale("gyro", "deg/s")
        factor, label = _NAV[sensor][term]
        return self.coefficients[term] * base * factor, label

    def name(self, term: str) -> str:
        """Name of a term for the record's sensor (e.g. "angle random walk")."""
        return _NAMES.get(term) or _NAMES_BY_SENSOR[self.result.sensor][term]

    def summary(self) -> Summary:
        """Coefficients in record and navigation units, the fit's setup and the read-offs."""
        res = self.result
        info = [("Samples", f"{res.n_samples}"), ("Rate", f"{res.rate:g} Hz"),
                ("Duration", f"{res.n_samples / res.rate:.6g} s"),
                ("Averaging times", f"{len(res.taus)}"),
                ("Tau range", f"{res.taus[0]:.4g}-{res.taus[-1]:.4g} s"),
                ("Units", res.units or "not given"), ("Sensor", res.sensor or "not given"),
                ("Terms fitted", ",".join(self.terms))]
        return Summary("Allan variance noise coefficients (IEEE Std 952)", info,
                       self._table(), self._notes())

    def _table(self) -> pd.DataFrame:
        rows = []
        for k in self.terms:
            ok = self.resolved[k]
            lo, hi = self.interval(k)
            row = {"Term": k, "Noise": self.name(k),
                   "Coefficient": self.coefficients[k] if ok else np.nan,
                   "Std. error": self.stderr[k] if ok else np.nan,
                   "Lower 68 %": lo if ok else np.nan, "Upper 68 %": hi if ok else np.nan,
                   "Units": self.units(k)}
            nav = self.navigation(k)
            if nav is not None:
                row.update({"Navigation": nav[0] if ok else np.nan, "Navigation units": nav[1]})
            row["Resolved"] = "yes" if ok else "no"
            rows.append(row)
        return pd.DataFrame(rows)

    def _notes(self) -> list[str]:
        notes = ["sigma^2(tau) = 3Q^2/tau^2 + N^2/tau + (2 ln2/pi)B^2 + K^2 tau/3 + R^2 tau^2/2, "
                 "non-negative least squares on sigma^2 weighted by sqrt(edf/2)/model "
                 "(weighted least squares on the log-log curve to first order)."]
        missing = [k for k in self.terms if not self.resolved[k]]
        if missing:
            bounds = ", ".join(f"{k} < {self.limits[k]:.3g} {self.units(k)}" for k in missing)
            notes.append(f"Not resolved (within two standard errors of zero in sigma^2, "
                         f"dropped and the rest refitted): {bounds}.")
        reads = {"N": "-1/2 line at tau = 1 s", "K": "+1/2 line at tau = 3 s",
                 "B": "minimum / 0.664"}
        shown = [f"{k} = {v:.4g} {self.units(k)} ({reads[k]})"
                 for k, v in self.readoff.items() if np.isfinite(v)]
        if shown:
            notes.append("Classic read-offs: " + "; ".join(shown) + ".")
        return notes

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable coefficients, errors, intervals, units, read-offs (NaN/inf as null)."""
        nav = {k: self.navigation(k) for k in self.terms}
        return {
            "model": "sigma^2 = 3Q^2/tau^2 + N^2/tau + (2ln2/pi)B^2 + K^2tau/3 + R^2tau^2/2",
            "terms": list(self.terms),
            "coefficients": dict(self.coefficients),
            "stderr": {k: _finite(v) for k, v in self.stderr.items()},
            "squared_stderr": dict(self.squared_stderr),
            "interval_68": {k: [_finite(v) for v in self.interval(k)] for k in self.terms},
            "resolved": dict(self.resolved), "limits": dict(self.limits),
            "units": {k: self.units(k) for k in self.terms},
            "navigation": {k: None if v is None else {"value": v[0], "units": v[1]}
                           for k, v in nav.items()},
            "readoff": {k: _finite(v) for k, v in self.readoff.items()},
        }


def _finite(value: float) -> float | None:
    """``value``, or None for NaN and infinity (not JSON)."""
    return float(value) if math.isfinite(value) else None


def fit_noise(result: AllanResult, terms: tuple[str, ...] = TERMS) -> NoiseFit:
    """Fit the IEEE Std 952 noise coefficients to an Allan deviation.

    The squared coefficients come from non-negative weighted least squares
    (:func:`_weighted_nnls`).  Their standard errors are those of that
    estimator: the sandwich ``(X'X)^-1 X' C X (X'X)^-1`` of the weighted design
    ``X``, with ``C`` the correlation between the Allan variance estimates at
    different taus.  The overlapping estimates are strongly correlated (about
    0.5 between neighbouring octaves of white noise, 0.9 for a random walk),
    so treating them as independent would understate the errors two- to
    three-fold; ``C`` is computed from the fitted model's spectrum
    (:func:`_correlation`).  A term the fit put at zero gets the error it
    would have if it were free.  Terms whose square is not two standard errors
    above zero are dropped, the weakest first, and the rest refitted until
    every term left is resolved: a superfluous term that the non-negative fit lets soak up
    scatter would otherwise pull the others down.  The rate ramp is treated as
    a noise in the weights, as IEEE Std 952 does; for a strictly deterministic
    ramp its error is overstated.

    Parameters
    ----------
    result : AllanResult
        From :func:`allan_deviation`.
    terms : tuple of str
        Terms to fit among ``"Q", "N", "B", "K", "R"``.

    Returns
    -------
    NoiseFit

    Raises
    ------
    InputError
        Unknown or repeated terms, or more terms than averaging times.
    """
    terms = _check_terms(terms, len(result.taus))
    kept, squared, se, limits = terms, {}, {}, {}
    while True:
        fitted = _fit_terms(result, kept)
        squared.update({k: c for k, (c, _) in fitted.items()})
        se.update({k: v for k, (_, v) in fitted.items()})
        weakest = min(kept, key=lambda k: squared[k] / se[k] if se[k] > 0 else math.inf)
        if squared[weakest] > 2.0 * se[weakest]:
            break
        limits[weakest] = math.sqrt(squared[weakest] + 2.0 * se[weakest])
        if len(kept) == 1:
            break
        kept = tuple(k for k in kept if k != weakest)
        squared[weakest] = 0.0
    return NoiseFit(
        result=result, terms=terms,
        coefficients={k: math.sqrt(squared[k]) for k in terms},
        squared_stderr=se, resolved={k: k not in limits for k in terms}, limits=limits,
        readoff=readoff(result),
    )


def _fit_terms(result: AllanResult, terms: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    """``{term: (squared coefficient, its standard error)}`` of one weighted NNLS fit."""
    basis = _basis(result.taus, terms)
    squared, weights = _weighted_nnls(basis, result.adev**2, result.edf)
    rho = _correlation(result, dict(zip(terms, squared)))
    se = _squared_stderr(basis * weights[:, None], rho, squared > 0)
    return {k: (float(c), float(v)) for k, c, v in zip(terms, squared, se)}


def _check_terms(terms: tuple[str, ...], n_taus: int) -> tuple[str, ...]:
    terms = tuple(terms)
    for k in terms:
        if k not in TERMS:
            raise InputError(f"unknown noise term {k!r}{did_you_mean(str(k), TERMS)}; "
                             f"terms: {', '.join(TERMS)}")
    if not terms or len(set(terms)) != len(terms):
        raise InputError(f"terms must be distinct names among {', '.join(TERMS)}, got {terms}")
    if len(terms) > n_taus:
        raise InputError(f"{len(terms)} terms cannot be fitted to {n_taus} averaging times")
    return tuple(k for k in TERMS if k in terms)


def _weighted_nnls(
    basis: np.ndarray, avar: np.ndarray, edf: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Squared coefficients minimising ``sum(edf/2 ((basis @ c - avar)/model)^2)``, ``c >= 0``.

    Iteratively re-weighted: the first pass divides by the measured Allan
    variance, later ones by the model of the previous pass, until it settles.
    Columns are scaled to unit norm for the solver (their magnitudes span many
    decades of tau).  Returns the squared coefficients and the final weights
    ``sqrt(edf/2)/model``, the inverse standard deviation of each Allan variance.
    """
    model, squared = avar, np.zeros(basis.shape[1])
    for _ in range(_MAX_PASSES):
        w = np.sqrt(edf / 2.0) / model
        a = basis * w[:, None]
        norms = np.linalg.norm(a, axis=0)
        new = nnls(a / norms, avar * w)[0] / norms
        settled = np.allclose(new, squared, rtol=1e-8, atol=0.0)
        squared, model = new, basis @ new
        if settled:
            break
    return squared, np.sqrt(edf / 2.0) / model


def _squared_stderr(x: np.ndarray, rho: np.ndarray, active: np.ndarray) -> np.ndarray:
    """Sandwich standard errors of least squares on the weighted design ``x``.

    The weighted residuals have unit variance and correlation ``rho``.  Each
    term's error is taken from the fit with the active (non-zero) terms and itself.
    """
    out = np.empty(x.shape[1])
    for k in range(x.shape[1]):
        cols = np.flatnonzero(active | (np.arange(x.shape[1]) == k))
        norms = np.linalg.norm(x[:, cols], axis=0)
        xs = x[:, cols] / norms
        bread = np.linalg.pinv(xs.T @ xs)
        cov = bread @ xs.T @ rho @ xs @ bread
        j = int(np.flatnonzero(cols == k)[0])
        out[k] = math.sqrt(max(cov[j, j], 0.0)) / norms[j]
    return out


def _spectrum(f: np.ndarray, squared: dict[str, float], rate: float) -> np.ndarray:
    """Two-sided rate spectrum of the fitted noise terms (the rate ramp is deterministic).

    Quantization (white angle error of variance ``Q^2``) and the random walk
    use their sampled forms; white and flicker noise ``N^2`` and ``B^2/(2 pi f)``.
    """
    s2 = np.sin(np.pi * f / rate) ** 2
    shapes = {"Q": 4.0 * s2 * rate, "N": np.ones_like(f), "B": 1.0 / (2.0 * np.pi * f),
              "K": 1.0 / (4.0 * rate**2 * s2), "R": np.zeros_like(f)}
    return sum(c * shapes[k] for k, c in squared.items())


def _correlation(result: AllanResult, squared: dict[str, float]) -> np.ndarray:
    """Correlation of the overlapping Allan variance estimates at ``result.taus``.

    For a Gaussian process of spectrum ``S`` the estimates at taus i and j,
    each a mean of squared filter outputs, have (record long against tau)
    ``cov ~ integral S^2 |H_i|^2 |H_j|^2 df`` with ``|H_m|^2 = 2 sin^4(pi f tau)
    /(m^2 sin^2(pi f/rate))`` the Allan filter; the shorter of two sums shares
    ``sqrt(counts_j/counts_i)`` of the longer.  The integral runs on a
    logarithmic grid (100 cells per decade) with ``sin^4`` (and ``sin^8`` on
    the diagonal) averaged exactly over each cell, so the fast oscillations of
    long taus at high frequency are integrated, not aliased.
    """
    taus, m = result.taus, np.round(result.taus * result.rate)
    top = result.rate / 2.0
    edges = np.geomspace(1e-3 / taus[-1], top, int(100 * math.log10(1e3 * top * taus[-1])) + 1)
    mid = np.sqrt(edges[1:] * edges[:-1])
    s2 = np.sin(np.pi * mid / result.rate)[:, None] ** 2
    u = [np.pi * f[:, None] * taus for f in (edges[:-1], edges[1:], mid)]
    gain = 2.0 * _cell_mean(_sin4_integral, 4, *u) / (m**2 * s2)
    gain2 = 4.0 * _cell_mean(_sin8_integral, 8, *u) / (m**4 * s2**2)
    weight = _spectrum(mid, squared, result.rate) ** 2 * np.diff(edges)
    cov = (gain * weight[:, None]).T @ gain
    np.fill_diagonal(cov, weight @ gain2)
    sd = np.sqrt(np.diag(cov))
    if not np.all(sd > 0):  # only the (deterministic) ramp fitted: no model of the scatter
        return np.eye(len(taus))
    n = result.counts.astype(float)
    return cov / np.outer(sd, sd) * np.sqrt(np.minimum.outer(n, n) / np.maximum.outer(n, n))


def _sin4_integral(u: np.ndarray) -> np.ndarray:
    """Antiderivative of sin^4."""
    return 3.0 * u / 8.0 - np.sin(2.0 * u) / 4.0 + np.sin(4.0 * u) / 32.0


def _sin8_integral(u: np.ndarray) -> np.ndarray:
    """Antiderivative of sin^8."""
    return (35.0 * u / 128.0 - 7.0 * np.sin(2.0 * u) / 32.0 + 7.0 * np.sin(4.0 * u) / 128.0
            - np.sin(6.0 * u) / 96.0 + np.sin(8.0 * u) / 1024.0)


def _cell_mean(antiderivative: Callable[[np.ndarray], np.ndarray], power: int, lo: np.ndarray,
               hi: np.ndarray, mid: np.ndarray) -> np.ndarray:
    """Mean of ``sin(u)^power`` over each cell ``[lo, hi]``; the midpoint value on narrow cells.

    Below 0.1 rad the difference of the antiderivative loses its digits to
    cancellation, and the midpoint is exact to a fraction of a per cent.
    """
    width = hi - lo
    wide = width > 0.1
    mean = (antiderivative(hi) - antiderivative(lo)) / np.where(wide, width, 1.0)
    return np.where(wide, mean, np.sin(mid) ** power)


def readoff(result: AllanResult, slope_tol: float = 0.25) -> dict[str, float]:
    """Classic graphical read-offs of N, K and B from the Allan deviation curve.

    ``N`` is the -1/2 line through the point whose local log-log slope is
    closest to -1/2, read at tau = 1 s (``N/sqrt(tau)`` there is ``N``); ``K``
    the +1/2 line through the point closest to +1/2, read at tau = 3 s
    (``K sqrt(tau/3)`` there is ``K``); ``B`` the minimum deviation divided by
    0.664 when the minimum is inside the curve.  NaN where no local slope is
    within ``slope_tol`` of the nominal one (or the minimum is at an end).
    """
    log_t, log_a = np.log10(result.taus), np.log10(result.adev)
    slope = np.gradient(log_a, log_t)
    out = {}
    for term, nominal, at in (("N", -0.5, 1.0), ("K", 0.5, 3.0)):
        i = int(np.argmin(np.abs(slope - nominal)))
        line = 10 ** (log_a[i] + nominal * (math.log10(at) - log_t[i]))
        out[term] = line if abs(slope[i] - nominal) <= slope_tol else math.nan
    i = int(np.argmin(result.adev))
    out["B"] = result.adev[i] / FLICKER_FLOOR if 0 < i < len(result.adev) - 1 else math.nan
    return out


def allan_figure(result: AllanResult, fit: NoiseFit, title: str) -> Figure:
    """Log-log Allan deviation with its 68 % band, each fitted term's line and their sum."""
    fig = Figure(figsize=(7.5, 5.2), layout="constrained")
    ax = fig.subplots()
    ax.fill_between(result.taus, result.lower, result.upper, color="C0", alpha=0.25,
                    label="68 % confidence interval")
    ax.loglog(result.taus, result.adev, "o", color="C0", ms=3.5, label="overlapping ADEV")
    grid = np.geomspace(result.taus[0], result.taus[-1], 200)
    for i, k in enumerate(fit.terms):
        if fit.coefficients[k] > 0:
            ax.loglog(grid, fit.term_adev(k, grid), "--" if fit.resolved[k] else ":",
                      color=f"C{i + 1}", label=_legend(fit, k))
    ax.loglog(grid, fit.model_adev(grid), "-", color="k", lw=1.2, label="fitted sum")
    ax.set_ylim(result.lower.min() / 3.0, result.upper.max() * 3.0)
    ax.set_xlabel(r"averaging time $\tau$ (s)")
    ax.set_ylabel(f"Allan deviation ({result.units or 'units'})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title(title)
    return fig


def _legend(fit: NoiseFit, term: str) -> str:
    nav = fit.navigation(term)
    value, units = nav if nav is not None else (fit.coefficients[term], fit.units(term))
    text = f"{term} {fit.name(term)} = {value:.3g} {units}"
    return text if fit.resolved[term] else f"{text} (not resolved)"


def write_allan(result: AllanResult, fit: NoiseFit, out_dir: Path, title: str) -> list[Path]:
    """``allan.png/svg``, ``allan.md/csv/tex`` (the deviation) and ``noise.md/csv/tex``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = save_figure(allan_figure(result, fit, title), out_dir, "allan")
    paths += write_tables(result.to_frame(), out_dir, "allan")
    return paths + write_tables(fit.summary().to_frame(), out_dir, "noise")
