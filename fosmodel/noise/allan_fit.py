"""The IEEE Std 952 noise terms and their fit to an Allan deviation.

:func:`fit_noise` fits the IEEE Std 952 model (El-Diasty et al. 2007, section 2.1; Koldbæk and
Totu 2011, eq. 4.17)::

    sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2

with quantization ``Q``, angle/velocity random walk ``N``, bias instability
``B``, rate random walk ``K`` and rate ramp ``R``, plus IEEE Std 952's
sinusoidal term ``S`` (``S^2 (sin^2(pi f0 tau)/(pi f0 tau))^2``) when the
record's spectrum holds a clear line at ``f0`` (a vibration or a pump: it
bends the curve over a decade around ``1/f0``).  The model is linear in the
squared coefficients; they are fitted to the *logarithm* of the deviation,
each point weighted by the inverse of its statistical variance ``1/(2 edf)``
plus a model allowance of :data:`MODEL_ALLOWANCE` squared.  Without the
allowance the shortest taus, with hundreds of thousands of degrees of
freedom, decide the fit, and a real sensor's curve, which the five terms
describe only to some tens of per cent, is missed by a factor of two from
10 s on.  The first few averaging times are left out when the record's own
filtering bends the curve there (:func:`fit_noise`).  Standard errors are
the sandwich of that weighted fit with the true covariance of the estimates:
their strong correlation between neighbouring taus, plus the misfit the
model leaves (estimated from the residuals, Paule-Mandel); terms not
resolved from zero are dropped and the rest refitted.

A bias that is bounded makes the curve rise and fall again, which the five terms cannot do
(their sum's log-log slope only grows with tau).  Beside them a first-order Gauss-Markov
term ``G`` (a bias of standard deviation ``sigma`` and correlation time ``Tc``, Allan variance
``sigma^2 g(tau/Tc)``, :func:`gauss_markov_avar`) is fitted where the record calls for it:
``Tc`` is chosen by the same weighted log fit, and the term is kept when the likelihood ratio
of the two fits (the generalised chi-square of the log deviation under the IEEE fit's
covariance, both refitted by generalised least squares) drops by more than the Bayesian
information criterion's penalty ``2 ln n`` for its two parameters (:func:`fit_noise`).  The
bias instability is then reported as the datasheets read it, from the fitted curve: its
minimum (the in-run bias stability) and that minimum / 0.664 (:meth:`NoiseFit.bias_stability`).

Each term is defined here, at the top: its Allan variance (:func:`_basis`), its rate
spectrum (:func:`_spectrum`, for the covariance of the estimates), its name and its
navigation units.  :class:`NoiseFit` holds a fit's coefficients, errors, limits and
read-offs, and says them (``summary``, ``conventions``, ``to_dict``).

References
----------
.. [1] IEEE Std 952-1997, "IEEE Standard Specification Format Guide and Test Procedure for
   Single-Axis Interferometric Fiber Optic Gyros", IEEE, 1997.
.. [2] M. El-Diasty, A. El-Rabbany and S. Pagiatakis, "Stochastic Characteristics of
   Temperature-Dependent MEMS-Based Inertial Sensor Error", Proceedings of the ION
   National Technical Meeting, San Diego, CA, 2007.
.. [3] S. K. Koldbæk and L.-C. Totu, "Improving MEMS Gyroscope Performance using Homogeneous
   Sensor Fusion", Master's thesis, Department of Electronic Systems, Aalborg University,
   2011.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import allantools
import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.optimize import brentq, least_squares, minimize_scalar, nnls
from scipy.special import digamma

from ..core.exceptions import InputError
from ..core.validation import did_you_mean
from ..typeset.summary import Summary
from .allan import FLICKER_FLOOR, ONE_SIGMA, AllanResult, readoff
from .metrics import STANDARD_GRAVITY, to_si_scale

#: The IEEE Std 952 noise terms, from short to long averaging times.
TERMS = ("Q", "N", "B", "K", "R")
#: With the sinusoid, fitted where the record has a spectral line.
ALL_TERMS = (*TERMS, "S")
#: The first-order Gauss-Markov (bounded bias) term, fitted where the record calls for it.
GAUSS_MARKOV = "G"
_ORDER = (*ALL_TERMS, GAUSS_MARKOV)
#: Averaging time of a Gauss-Markov process's Allan deviation peak, in correlation times, and
#: the peak in its standard deviations (1.89 Tc and 0.618 sigma in the literature).
GM_PEAK_TAU = 1.8926178
GM_PEAK_ADEV = 0.6173643
#: A Gauss-Markov term is sought with its peak at least this many times the first fitted tau
#: and the taus the sensor's filtering may bend (a bend there is the filter's, not a bias),
#: and at most at the last tau.
GM_PEAK_FROM_START = 10.0
#: Relative misfit allowed to the IEEE Std 952 sum at each tau, beside the statistical scatter:
#: real curves bend from the ideal terms by some tens of per cent (temperature cycles, a bias
#: that is bounded), and no decade of the curve may be given up for another.
MODEL_ALLOWANCE = 0.3
#: Rise of the curve's chi-square that keeps an unresolved term in the fit (three sigma of one
#: parameter).
CURVE_CHI2 = 9.0
#: Most leading averaging times (in samples) the sensor's own filtering may bend.
FILTER_SAMPLES = 10
#: A fitted curve off the measured one by more than this factor, beyond the 95 % interval of
#: the measured value, is reported as a miss.
MISS_FACTOR = 1.25
_NAMES = {"Q": "quantization", "B": "bias instability", "R": "rate ramp", "S": "sinusoid",
          "G": "bounded bias (Gauss-Markov)"}
_NAMES_BY_SENSOR = {
    "gyro": {"N": "angle random walk", "K": "rate random walk"},
    "accel": {"N": "velocity random walk", "K": "acceleration random walk"},
    None: {"N": "white noise (ARW/VRW)", "K": "rate random walk"},
}
#: Navigation units per term: (factor from deg/s- or m/s^2-based SI-ish units, label).
_NAV = {
    "gyro": {"Q": (1.0, "deg"), "N": (60.0, "deg/sqrt(h)"), "B": (3600.0, "deg/h"),
             "K": (3600.0 * 60.0, "deg/h/sqrt(h)"), "R": (3600.0**2, "deg/h^2"),
             "S": (3600.0, "deg/h"), "G": (3600.0, "deg/h")},
    "accel": {"Q": (1.0, "m/s"), "N": (60.0, "m/s/sqrt(h)"), "B": (1e3 / STANDARD_GRAVITY, "mg"),
              "K": (3600.0 * 60.0, "m/s/h/sqrt(h)"), "R": (3600.0**2, "m/s/h^2"),
              "S": (1e3 / STANDARD_GRAVITY, "mg"), "G": (1e3 / STANDARD_GRAVITY, "mg")},
}


def gauss_markov_avar(taus: ArrayLike, tc: float) -> np.ndarray:
    """Allan variance of a first-order Gauss-Markov process of unit variance (continuous time).

    ``2/x (1 - (3 - 4 exp(-x) + exp(-2x)) / (2x))`` with ``x = tau/Tc``: rising as ``2x/3``
    (a random walk) well below ``Tc``, falling as ``2/x`` (white noise) well above it, and
    peaking at ``GM_PEAK_ADEV^2`` at ``tau = GM_PEAK_TAU Tc``.  Below ``x = 1e-3`` its series
    ``2x/3 - x^2/2 + 7x^3/30``, where the closed form loses its digits.

    Parameters
    ----------
    taus : array-like
        Averaging times in seconds.
    tc : float
        Correlation time in seconds.

    Returns
    -------
    ndarray

    References
    ----------
    N. El-Sheimy, H. Hou and X. Niu, "Analysis and modeling of inertial sensors using Allan
    variance", *IEEE Trans. Instrum. Meas.* 57(1), 140-149, 2008.
    """
    x = np.asarray(taus, dtype=float) / tc
    small = x < 1e-3
    xs = np.where(small, 1.0, x)
    closed = 2.0 / xs * (1.0 + (4.0 * np.expm1(-xs) - np.expm1(-2.0 * xs)) / (2.0 * xs))
    return np.where(small, 2.0 * x / 3.0 - x**2 / 2.0 + 7.0 * x**3 / 30.0, closed)


def _basis(taus: np.ndarray, terms: tuple[str, ...], line_hz: float | None = None,
           gm_tc: float | None = None) -> np.ndarray:
    """Allan variance of each term per unit squared coefficient, one column per term.

    The sinusoid ``S`` (amplitude ``S`` at ``line_hz``) has IEEE Std 952's
    ``(sin^2(pi f0 tau)/(pi f0 tau))^2``; the Gauss-Markov ``G`` (standard deviation ``G``,
    correlation time ``gm_tc``) :func:`gauss_markov_avar`.
    """
    t = np.asarray(taus, dtype=float)

    def sinusoid() -> np.ndarray:
        if line_hz is None:
            raise ValueError("the sinusoid term S needs its frequency line_hz")
        return (np.sin(np.pi * line_hz * t) ** 2 / (np.pi * line_hz * t)) ** 2

    def gauss_markov() -> np.ndarray:
        if gm_tc is None:
            raise ValueError("the Gauss-Markov term G needs its correlation time gm_tc")
        return gauss_markov_avar(t, gm_tc)

    columns = {"Q": lambda: 3.0 / t**2, "N": lambda: 1.0 / t,
               "B": lambda: np.full_like(t, FLICKER_FLOOR**2), "K": lambda: t / 3.0,
               "R": lambda: t**2 / 2.0, "S": sinusoid, "G": gauss_markov}
    return np.column_stack([columns[k]() for k in terms])


def _spectrum(f: np.ndarray, squared: dict[str, float], rate: float,
              gm_tc: float | None = None) -> np.ndarray:
    """Two-sided rate spectrum of the fitted noise terms (the ramp and the line are left out).

    Quantization (white angle error of variance ``Q^2``) and the random walk
    use their sampled forms; white and flicker noise ``N^2`` and ``B^2/(2 pi f)``; the
    Gauss-Markov ``2 G^2 Tc / (1 + (2 pi f Tc)^2)`` (``2 G^2 Tc`` is its white level, as
    ``N^2`` is white noise's).
    """
    s2 = np.sin(np.pi * f / rate) ** 2
    shapes = {"Q": 4.0 * s2 * rate, "N": np.ones_like(f), "B": 1.0 / (2.0 * np.pi * f),
              "K": 1.0 / (4.0 * rate**2 * s2), "R": np.zeros_like(f), "S": np.zeros_like(f)}
    if gm_tc is not None:
        shapes["G"] = 2.0 * gm_tc / (1.0 + (2.0 * np.pi * f * gm_tc) ** 2)
    return sum((c * shapes[k] for k, c in squared.items()), np.zeros_like(f))


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
        Classic graphical read-offs for comparison (:func:`readoff`): ``N``
        from the -1/2 line at tau = 1 s, ``K`` from the +1/2 line at tau = 3 s,
        ``B`` as the minimum deviation / 0.664, and the minimum itself
        (``min_adev``, the datasheets' "in-run bias stability") at ``min_tau_s``.
    start : int
        Index of the shortest averaging time fitted (the ones before it are
        bent by the sensor's own filtering).
    misfit : float
        Relative misfit of the model beyond the statistical scatter (0 when the
        model explains the curve within it), part of the standard errors.
    gm_tc : float or None
        Correlation time (s) of the Gauss-Markov term ``G`` when it is among ``terms``.
    gauss_markov : dict
        How the Gauss-Markov term was decided (:func:`fit_noise`): the criterion, the drop of
        the generalised chi-square, the penalty, the correlation time tried and whether kept.
    """

    result: AllanResult
    terms: tuple[str, ...]
    coefficients: dict[str, float]
    squared_stderr: dict[str, float]
    resolved: dict[str, bool]
    limits: dict[str, float] = field(default_factory=dict)
    readoff: dict[str, float] = field(default_factory=dict)
    start: int = 0
    misfit: float = 0.0
    gm_tc: float | None = None
    gauss_markov: dict[str, Any] = field(default_factory=dict)

    @property
    def fitted_taus(self) -> np.ndarray:
        """The averaging times the fit used."""
        return self.result.taus[self.start:]

    def misses(self) -> list[tuple[float, float]]:
        """List ``(tau, fit/data)`` where the fit misses the measured deviation.

        A miss is beyond the deviation's 95 % interval and by more than
        :data:`MISS_FACTOR`, over the fitted taus.
        """
        res, out = self.result, []
        ratio = self.model_adev(res.taus) / res.adev
        for i in range(self.start, len(res.taus)):
            lo, hi = allantools.confidence_interval(res.adev[i], res.edf[i], 0.95)
            model = ratio[i] * res.adev[i]
            off = max(ratio[i], 1.0 / ratio[i]) > MISS_FACTOR
            if off and not lo <= model <= hi:
                out.append((float(res.taus[i]), float(ratio[i])))
        return out

    def conservative(self, term: str) -> tuple[float, str]:
        """Return the value of a term to hand to a filter or a configuration, and what it is.

        That is the fitted coefficient where resolved (``"fitted"``), else its upper limit
        (``"upper limit"``), never a silent 0.
        """
        if self.resolved[term]:
            return self.coefficients[term], "fitted"
        return self.limits[term], "upper limit"

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

    def term_adev(self, term: str, taus: ArrayLike) -> np.ndarray:
        """Allan deviation of one fitted term at ``taus`` (seconds)."""
        column = _basis(np.asarray(taus), (term,), self.result.line_hz, self.gm_tc)[:, 0]
        return self.coefficients[term] * np.sqrt(column)

    def model_adev(self, taus: ArrayLike) -> np.ndarray:
        """Allan deviation of the fitted model (all terms) at ``taus``."""
        squared = np.array([self.coefficients[k] ** 2 for k in self.terms])
        basis = _basis(np.asarray(taus, dtype=float), self.terms, self.result.line_hz,
                       self.gm_tc)
        return np.sqrt(basis @ squared)

    def bias_stability(self) -> tuple[float, float]:
        """Return the fitted curve's minimum and its averaging time, over the fitted taus.

        The datasheets' in-run bias stability read on the fit (the measured minimum stays in
        :attr:`readoff`); divided by 0.664 it is the bias instability by their convention.
        ``(nan, nan)`` where the curve has no minimum inside the fitted taus (it still falls
        at the last one, or rises from the first).
        """
        grid = np.geomspace(self.fitted_taus[0], self.fitted_taus[-1], 2000)
        curve = self.model_adev(grid)
        i = int(np.argmin(curve))
        if not 0 < i < len(grid) - 1:
            return math.nan, math.nan
        return float(curve[i]), float(grid[i])

    def fitted_terms(self) -> list[str]:
        """Return the terms in the fitted curve (non-zero), ``G`` with its correlation time."""
        return [k if k != GAUSS_MARKOV else f"G (Tc {self.gm_tc:.3g} s)"
                for k in self.terms if self.coefficients[k] > 0]

    def dominant(self, tau: float) -> str:
        """Return the resolved term with the largest Allan variance at ``tau`` seconds.

        Among all fitted terms if none is resolved.
        """
        terms = [k for k in self.terms if self.resolved[k]] or self.terms
        return max(terms, key=lambda k: self.term_adev(k, [tau])[0])

    def units(self, term: str) -> str:
        """Units of a coefficient in the record's units."""
        u = self.result.units or "units"
        return {"Q": f"{u}*s", "N": f"{u}*sqrt(s)", "B": u, "K": f"{u}/sqrt(s)", "S": u,
                "R": f"{u}/s", "G": u}[term]

    def navigation(self, term: str, value: float | None = None) -> tuple[float, str] | None:
        """Return a coefficient (or ``value`` of that term) in navigation units.

        Those are deg/sqrt(h), deg/h, ... or m/s/sqrt(h), mg, ...

        None unless the record's sensor and units are known.
        """
        sensor, units = self.result.sensor, self.result.units
        if sensor is None or units is None:
            return None
        base = to_si_scale(sensor, units)
        if sensor == "gyro":
            base /= to_si_scale("gyro", "deg/s")
        factor, label = _NAV[sensor][term]
        value = self.coefficients[term] if value is None else value
        return value * base * factor, label

    def _navigation_value(self, term: str, value: float) -> float:
        """Return ``value`` of ``term`` in navigation units (NaN without sensor and units)."""
        navigation = self.navigation(term, value)
        return math.nan if navigation is None else navigation[0]

    def name(self, term: str) -> str:
        """Name of a term for the record's sensor (e.g. "angle random walk")."""
        return _NAMES.get(term) or _NAMES_BY_SENSOR[self.result.sensor][term]

    def summary(self) -> Summary:
        """Summarise the fit: coefficients in record and navigation units, read-offs, setup.

        Beside the classic read-offs, the fit's setup and what it left out.
        """
        res = self.result
        info = [("Samples", f"{res.n_samples}"), ("Rate", f"{res.rate:g} Hz"),
                ("Duration", f"{res.n_samples / res.rate:.6g} s"),
                ("Averaging times", f"{len(res.taus)}"),
                ("Tau range", f"{res.taus[0]:.4g}-{res.taus[-1]:.4g} s"),
                ("Tau range fitted", f"{self.fitted_taus[0]:.4g}-{res.taus[-1]:.4g} s"),
                ("Units", res.units or "not given"), ("Sensor", res.sensor or "not given"),
                ("Terms fitted", ",".join(self.terms))]
        if self.gm_tc is not None:
            info.append(("Gauss-Markov Tc", f"{self.gm_tc:.4g} s"))
        return Summary("Allan variance noise coefficients (IEEE Std 952)", info,
                       self._table(), self._notes())

    def _table(self) -> pd.DataFrame:
        rows = []
        for k in self.terms:
            ok = self.resolved[k]
            lo, hi = self.interval(k)
            read = self.readoff.get(k, math.nan)
            row = {"Term": k, "Noise": self.name(k),
                   "Coefficient": self.coefficients[k] if ok else np.nan,
                   "Std. error": self.stderr[k] if ok else np.nan,
                   "Lower 68 %": lo if ok else np.nan, "Upper 68 %": hi if ok else np.nan,
                   "Upper limit": np.nan if ok else self.limits[k],
                   "Read-off": read, "Units": self.units(k)}
            nav = self.navigation(k)
            if nav is not None:
                row.update({"Navigation": nav[0] if ok else np.nan,
                            "Navigation upper limit": (np.nan if ok else
                                                       self._navigation_value(k, self.limits[k])),
                            "Navigation read-off": self._navigation_value(k, read),
                            "Navigation units": nav[1]})
            row["Resolved"] = "yes" if ok else "no"
            rows.append(row)
        return pd.DataFrame(rows)

    def _notes(self) -> list[str]:
        res = self.result
        notes = [self._model_text() + ", fitted to ln ADEV with weights 1/(1/(2 edf) + "
                 f"{MODEL_ALLOWANCE:g}^2) (statistical scatter plus a model allowance).",
                 self._gauss_markov_text()]
        if self.start:
            notes.append(f"Averaging times below {self.fitted_taus[0]:.3g} s left out: the "
                         "record's own filtering bends the curve there.")
        if "S" in self.terms:
            notes.append(f"A spectral line at {res.line_hz:.4g} Hz is fitted as the sinusoid S "
                         "(its amplitude).")
        notes.append(f"Misfit beyond the statistical scatter: {self.misfit:.1%} per tau "
                     "(in the standard errors).")
        missing = [k for k in self.terms if not self.resolved[k]]
        if missing:
            bounds = ", ".join(f"{k} < {self.limits[k]:.3g} {self.units(k)}" for k in missing)
            notes.append(f"Not resolved (squares within two standard errors of zero; given "
                         f"by their upper limits, and left out of the curve where it fits as "
                         f"well without them): {bounds}.")
        reads = {"N": "-1/2 line at tau = 1 s", "K": "+1/2 line at tau = 3 s",
                 "B": f"minimum / 0.664, at tau = {self.readoff.get('min_tau_s', math.nan):.3g} s"}
        shown = [f"{k} = {self._both(k, self.readoff[k])} ({text})"
                 for k, text in reads.items() if np.isfinite(self.readoff.get(k, math.nan))]
        if shown:
            notes.append("Classic read-offs: " + "; ".join(shown) + ".")
        if np.isfinite(self.readoff.get("min_adev", math.nan)):
            notes.append("Datasheet convention: in-run bias stability = the minimum of the "
                         f"Allan deviation, {self._both('B', self.readoff['min_adev'])} at "
                         f"tau = {self.readoff['min_tau_s']:.3g} s.")
        minimum, at = self.bias_stability()
        notes.append(f"On the fitted curve ({' + '.join(self.fitted_terms())}): in-run bias "
                     f"stability (its minimum) {self._both('B', minimum)} at tau = {at:.3g} "
                     f"s; bias instability (minimum / 0.664) "
                     f"{self._both('B', minimum / FLICKER_FLOOR)}." if math.isfinite(minimum)
                     else f"On the fitted curve ({' + '.join(self.fitted_terms())}): no "
                     "minimum within the fitted taus, so no in-run bias stability.")
        misses = self.misses()
        if misses:
            worst = max(misses, key=lambda m: abs(math.log(m[1])))
            notes.append(f"WARNING: the fit misses the measured deviation beyond its 95 % "
                         f"interval at {len(misses)} averaging time(s), worst fit/data "
                         f"{worst[1]:.2f} at tau = {worst[0]:.3g} s: the IEEE Std 952 terms do "
                         "not describe the curve there.")
        return notes

    def _model_text(self) -> str:
        return ("sigma^2(tau) = 3Q^2/tau^2 + N^2/tau + (2 ln2/pi)B^2 + K^2 tau/3 + R^2 tau^2/2"
                + (" + S^2 (sin^2(pi f0 tau)/(pi f0 tau))^2" if "S" in self.terms else "")
                + (" + G^2 g(tau/Tc)" if GAUSS_MARKOV in self.terms else ""))

    def _gauss_markov_text(self) -> str:
        """Say whether the Gauss-Markov term was fitted, and why."""
        gm = self.gauss_markov
        if "delta_chi2" not in gm:
            return f"Gauss-Markov term G: {gm.get('reason', 'not sought')}."
        why = (f"the generalised chi-square of ln ADEV drops by {gm['delta_chi2']:.3g} with it "
               f"(Tc {gm['tc_s']:.3g} s), against BIC's penalty {gm['penalty']:.3g} (ln n for "
               f"each of {gm['parameters_added']} parameters added)")
        if GAUSS_MARKOV in self.terms:
            return (f"Gauss-Markov term G (a bounded bias) fitted: sigma = "
                    f"{self._both('G', self.coefficients['G'])}, Tc = {self.gm_tc:.3g} s; {why}.")
        return f"Gauss-Markov term G not fitted: {why}."

    def conventions(self) -> dict[str, str]:
        """Return N, B and K fitted beside the classic read-offs, as text in navigation units.

        An upper limit reads ``"< value"``; beside them the datasheets' in-run bias stability
        (``"-"`` where a read-off does not exist).
        """
        read = self.readoff
        minimum = read.get("min_adev", math.nan)
        fit_min, fit_at = self.bias_stability()
        gm = (f"{self._fitted_text('G')}, Tc {self.gm_tc:.3g} s" if GAUSS_MARKOV in self.terms
              else "-")
        return {
            "N fitted": self._fitted_text("N"),
            "N read-off (1 s)": self._nav_text("N", read.get("N", math.nan)),
            "B fitted": self._fitted_text("B"),
            "B read-off (min/0.664)": self._nav_text("B", read.get("B", math.nan)),
            "in-run bias stability (min)": (f"{self._nav_text('B', minimum)} at "
                                            f"{read['min_tau_s']:.3g} s"
                                            if math.isfinite(minimum) else "-"),
            "K fitted": self._fitted_text("K"),
            "K read-off (3 s)": self._nav_text("K", read.get("K", math.nan)),
            "GM fitted (sigma, Tc)": gm,
            "fit: in-run bias stability (min)": (f"{self._nav_text('B', fit_min)} at "
                                                 f"{fit_at:.3g} s" if math.isfinite(fit_min)
                                                 else "-"),
            "fit: B (min/0.664)": self._nav_text("B", fit_min / FLICKER_FLOOR),
            "terms fitted": " ".join(k for k in self.terms if self.coefficients[k] > 0),
        }

    def _fitted_text(self, term: str) -> str:
        value, kind = self.conservative(term)
        return ("< " if kind == "upper limit" else "") + self._nav_text(term, value)

    def _nav_text(self, term: str, value: float) -> str:
        """``value`` of a term in navigation units, in the record's if they are unknown."""
        if not math.isfinite(value):
            return "-"
        nav = self.navigation(term, value)
        return f"{nav[0]:.3g} {nav[1]}" if nav else f"{value:.3g} {self.units(term)}"

    def _both(self, term: str, value: float) -> str:
        """``value`` of a term in the record's units, and in navigation units if known."""
        text = f"{value:.4g} {self.units(term)}"
        nav = self.navigation(term, value)
        return text if nav is None else f"{text} ({nav[0]:.4g} {nav[1]})"

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable coefficients, errors, intervals, units, read-offs (NaN/inf as null)."""
        nav = {k: self.navigation(k) for k in self.terms}
        fit_min, fit_at = self.bias_stability()
        return {
            "model": self._model_text(),
            "terms": list(self.terms),
            "terms_fitted": [k for k in self.terms if self.coefficients[k] > 0],
            "gm_tc_s": self.gm_tc, "gauss_markov": dict(self.gauss_markov),
            "coefficients": dict(self.coefficients),
            "stderr": {k: _finite(v) for k, v in self.stderr.items()},
            "squared_stderr": dict(self.squared_stderr),
            "interval_68": {k: [_finite(v) for v in self.interval(k)] for k in self.terms},
            "resolved": dict(self.resolved), "limits": dict(self.limits),
            "units": {k: self.units(k) for k in self.terms},
            "navigation": {k: None if v is None else {"value": v[0], "units": v[1]}
                           for k, v in nav.items()},
            "readoff": {k: _finite(v) for k, v in self.readoff.items()},
            "datasheet": {"in_run_bias_stability": _finite(self.readoff.get("min_adev",
                                                                            math.nan)),
                          "tau_s": _finite(self.readoff.get("min_tau_s", math.nan)),
                          "fit_in_run_bias_stability": _finite(fit_min),
                          "fit_tau_s": _finite(fit_at),
                          "fit_bias_instability": _finite(fit_min / FLICKER_FLOOR),
                          "convention": "in-run bias stability = the minimum of the Allan "
                                        "deviation (measured, and of the fitted curve); bias "
                                        "instability = that minimum / 0.664"},
            "fit_adev": self.model_adev(self.result.taus).tolist(),
            "fitted_tau_s": [float(self.fitted_taus[0]), float(self.fitted_taus[-1])],
            "line_hz": self.result.line_hz, "misfit": self.misfit,
            "model_allowance": MODEL_ALLOWANCE,
            "misses": [{"tau_s": t, "fit_over_data": r} for t, r in self.misses()],
        }


def _finite(value: float) -> float | None:
    """``value``, or None for NaN and infinity (not JSON)."""
    return float(value) if math.isfinite(value) else None


def fit_noise(result: AllanResult, terms: tuple[str, ...] = TERMS, *,
              min_tau: float | None = None, gauss_markov: bool | None = None) -> NoiseFit:
    """Fit the IEEE Std 952 noise coefficients to an Allan deviation.

    The squared coefficients minimise the weighted squared misfit of the
    *logarithm* of the deviation, ``sum w (ln model - ln adev)^2`` with
    ``w = 1/(1/(2 edf) + MODEL_ALLOWANCE^2)``, subject to being non-negative
    (:func:`_log_fit`).  ``1/(2 edf)`` is the variance of ``ln adev``; the
    allowance stops the taus with the most degrees of freedom from deciding
    the fit alone.  When the record's spectrum holds a clear line
    (``result.line_hz``), IEEE Std 952's sinusoidal term ``S`` is fitted too.

    The shortest averaging times are left out when the record's own
    filtering (an anti-aliasing or averaging filter in the sensor) bends the
    curve below the white-noise line there: among the first
    :data:`FILTER_SAMPLES` samples, the fit starts at the first tau from
    which its misfit per point is within 1.5 times the best start's
    (``min_tau`` sets the start instead).

    Standard errors are the sandwich ``(J'WJ)^-1 J'W C W J (J'WJ)^-1`` of
    that fit, with ``C`` the covariance of the log deviations: the strong
    correlation between overlapping estimates at neighbouring taus
    (:func:`_correlation`, from the fitted model's spectrum; treating them as
    independent would understate the errors two- to three-fold) plus the
    misfit ``s^2`` the model leaves, estimated from the residuals so that
    they match their variances on average (Paule and Mandel).  A term the
    fit put at zero gets the error it would have if it were free.  A term
    whose square is not two standard errors above zero is not resolved and is
    reported by its upper limit (its square plus two standard errors).  The
    weakest such term whose removal leaves the curve as well fitted (its
    generalised chi-square, with the covariance ``C``, up by less than
    :data:`CURVE_CHI2`) is dropped and the rest refitted, until none can go:
    a superfluous term that soaks up scatter pulls the others down, while
    one that shapes the curve stays in it.

    Then the Gauss-Markov term ``G``: its correlation time ``Tc`` is the one whose fit with
    the terms has the least weighted misfit (the same fit), its Allan peak (at
    :data:`GM_PEAK_TAU` ``Tc``) between :data:`GM_PEAK_FROM_START` times the first fitted tau
    (and the :data:`FILTER_SAMPLES` the sensor's filtering may bend) and the last tau.  The
    model with ``G`` holds the terms the IEEE fit kept, ``G``, and any term that fit dropped
    which the curve needs beside ``G`` (so the IEEE model is this one with ``G`` at zero).
    Both models are refitted by generalised least squares on ln ADEV under the covariance
    ``C`` of the IEEE fit (its statistical part and misfit), and ``G`` is kept when the
    generalised chi-square drops by more than ``ln n`` per parameter added (``sigma`` and
    ``Tc``, and a term brought back): the Bayesian information criterion for ``n`` fitted
    taus.  On
    records of white noise, flicker and random walk alone the drop stays below it (a bump of
    one realisation is within the covariance), while a bounded bias's rise and fall exceeds
    it many times.

    Parameters
    ----------
    result : AllanResult
        From :func:`allan_deviation`.
    terms : tuple of str
        Terms to fit among ``"Q", "N", "B", "K", "R"`` (and ``"S"``, which is
        added by itself when the record has a spectral line).
    min_tau : float, optional
        Shortest averaging time to fit, in seconds.
    gauss_markov : bool, optional
        Fit the Gauss-Markov term always (True), never (False), or where the criterion keeps
        it (None, the default).

    Returns
    -------
    NoiseFit

    Raises
    ------
    InputError
        Unknown or repeated terms, more terms than averaging times, a
        sinusoid without a line, or a ``min_tau`` that leaves too few taus.

    References
    ----------
    IEEE Std 952-1997, Annex C (Allan variance, including the sinusoidal term).
    R. C. Paule and J. Mandel, "Consensus values and weighting factors",
    *J. Res. Natl. Bur. Stand.* 87(5), 1982.
    G. Schwarz, "Estimating the dimension of a model", *Ann. Statist.* 6(2), 461-464, 1978.
    """
    terms = _check_terms(terms, len(result.taus), result.line_hz)
    start = _start(result, terms, min_tau)
    kept, squared, se, misfit, cov = _fit_and_drop(result, terms, start)
    gm_tc, choice = None, {"reason": "not sought (gauss_markov=False)"}
    if gauss_markov is not False:
        gm_tc, choice, with_gm = _gauss_markov(result, terms, start, kept, squared, cov,
                                               gauss_markov is True)
    if gm_tc is not None and choice["kept"]:
        _, squared, se, misfit, _ = with_gm
        terms = (*terms, GAUSS_MARKOV)
    else:
        gm_tc = None
    limits = {k: math.sqrt(squared[k] + 2.0 * se[k]) for k in terms
              if not squared[k] > 2.0 * se[k]}
    return NoiseFit(
        result=result, terms=terms,
        coefficients={k: math.sqrt(squared[k]) for k in terms},
        squared_stderr=se, resolved={k: k not in limits for k in terms}, limits=limits,
        readoff=readoff(result), start=start, misfit=misfit, gm_tc=gm_tc, gauss_markov=choice,
    )


def _fit_and_drop(result: AllanResult, terms: tuple[str, ...], start: int,
                  gm_tc: float | None = None) -> tuple[tuple[str, ...], dict, dict, float,
                                                       np.ndarray]:
    """Fit ``terms`` and drop, one at a time, the unresolved ones the curve does not need.

    Return the terms kept, every term's squared coefficient (0 when dropped) and its standard
    error, the misfit and the covariance of the last fit.  ``G`` is never dropped: the
    criterion of :func:`_gauss_markov` kept it.
    """
    kept, (fitted, misfit, resid, cov) = terms, _fit_terms(result, terms, start, gm_tc)
    squared = {k: c for k, (c, _) in fitted.items()}
    se = {k: v for k, (_, v) in fitted.items()}
    while len(kept) > 1:
        dropped = _drop_one(result, kept, start, squared, se, resid, cov, gm_tc)
        if dropped is None:
            break
        weakest, (fitted, misfit, resid, cov) = dropped
        kept = tuple(k for k in kept if k != weakest)
        squared.update({k: c for k, (c, _) in fitted.items()}, **{weakest: 0.0})
        se.update({k: v for k, (_, v) in fitted.items()})
    return kept, squared, se, misfit, cov


def _drop_one(result: AllanResult, kept: tuple[str, ...], start: int, squared: dict,
              se: dict, resid: np.ndarray, cov: np.ndarray,
              gm_tc: float | None = None) -> tuple[str, tuple] | None:
    """Find the weakest unresolved term whose removal leaves the curve as well fitted.

    Return it with the refit without it; None if every unresolved term shapes the curve.
    """
    loose = [k for k in kept if not squared[k] > 2.0 * se[k] and k != GAUSS_MARKOV]
    for term in sorted(loose, key=lambda k: squared[k] / se[k] if se[k] > 0 else -math.inf):
        trial = _fit_terms(result, tuple(k for k in kept if k != term), start, gm_tc)
        if _chi2(trial[2], cov) - _chi2(resid, cov) < CURVE_CHI2:
            return term, trial
    return None


def _gauss_markov(result: AllanResult, terms: tuple[str, ...], start: int,
                  kept: tuple[str, ...], squared: dict, cov: np.ndarray,
                  force: bool = False) -> tuple[float | None, dict[str, Any], tuple]:
    """Decide the Gauss-Markov term beside the IEEE terms (see :func:`fit_noise`).

    ``kept``, ``squared`` and ``cov`` are the IEEE fit's.  Return the correlation time (None
    when the fitted taus leave no room for its peak), what was decided and why, and the fit
    with the term (:func:`_fit_and_drop` of ``terms`` and ``G``).
    """
    taus = result.taus[start:]
    first = max(float(taus[0]), FILTER_SAMPLES / result.rate)
    lo, hi = GM_PEAK_FROM_START * first / GM_PEAK_TAU, taus[-1] / GM_PEAK_TAU
    if lo >= hi or len(taus) < len(terms) + 4:
        return None, {"reason": f"not sought: the fitted taus ({taus[0]:.3g}-{taus[-1]:.3g} s) "
                                "leave no room for its peak"}, ()
    tc = _gauss_markov_tc(result, terms, start, lo, hi)
    with_gm = _with_gauss_markov(result, terms, start, kept, tc)
    adev = _unbiased(result.adev[start:], result.edf[start:])
    whiten = _whitener(cov)
    without = _gls_chi2(_basis(taus, kept, result.line_hz), adev, whiten,
                        np.array([squared[k] for k in kept]))
    gm_kept, gm_squared = with_gm[0], with_gm[1]
    delta = without - _gls_chi2(_basis(taus, gm_kept, result.line_hz, tc), adev, whiten,
                                np.array([gm_squared[k] for k in gm_kept]))
    added = len(gm_kept) + 1 - len(kept)  # G's sigma and Tc, and any term it brings back
    penalty = added * math.log(len(taus))
    return tc, {"criterion": "BIC: generalised chi-square of ln ADEV (the IEEE fit's covariance, "
                             "both models refitted by GLS) against ln n per parameter added",
                "delta_chi2": delta, "penalty": penalty, "parameters_added": added,
                "n_taus": len(taus), "tc_s": tc, "tc_range_s": [lo, hi],
                "kept": bool(force or delta > penalty), "forced": force}, with_gm


def _with_gauss_markov(result: AllanResult, terms: tuple[str, ...], start: int,
                       kept: tuple[str, ...], tc: float) -> tuple:
    """Fit the IEEE fit's terms, ``G`` and any dropped term the curve needs with ``G``.

    The terms the IEEE fit kept stay (so that the models are nested, the IEEE one the model
    with ``G`` at zero); a term it dropped comes back when the fit of every term and ``G``
    keeps it (:func:`_fit_and_drop`).  Return as :func:`_fit_and_drop` does.
    """
    back = _fit_and_drop(result, (*terms, GAUSS_MARKOV), start, tc)
    model = tuple(k for k in (*terms, GAUSS_MARKOV) if k in kept or k in back[0])
    fitted, misfit, _, cov = _fit_terms(result, model, start, tc)
    squared = {k: 0.0 for k in back[1]} | {k: c for k, (c, _) in fitted.items()}
    se = dict(back[2]) | {k: v for k, (_, v) in fitted.items()}
    return model, squared, se, misfit, cov


def _gauss_markov_tc(result: AllanResult, terms: tuple[str, ...], start: int, lo: float,
                     hi: float) -> float:
    """Return the correlation time whose weighted log fit with ``terms`` misfits least.

    A grid of 12 per decade between ``lo`` and ``hi``, then a bounded scalar search around
    its best point.
    """
    def misfit(log_tc: float) -> float:
        resid = _curve_fit(result, (*terms, GAUSS_MARKOV), start, 10.0**log_tc)[2]
        return float(np.mean(_weights(result.edf[start:]) * resid**2))

    grid = np.linspace(math.log10(lo), math.log10(hi),
                       max(int(12 * math.log10(hi / lo)) + 1, 3))
    best = int(np.argmin([misfit(g) for g in grid]))
    found = minimize_scalar(misfit, bounds=(grid[max(best - 1, 0)],
                                            grid[min(best + 1, len(grid) - 1)]),
                            method="bounded", options={"xatol": 1e-3})
    return float(10.0 ** found.x)


def _whitener(cov: np.ndarray) -> np.ndarray:
    """Return ``C^-1/2``: eigenvalues below 1e-12 of the largest (and a 1e-9 ridge) clipped."""
    ridge = 1e-9 * float(np.mean(np.diag(cov))) * np.eye(len(cov))
    values, vectors = np.linalg.eigh(cov + ridge)
    return (vectors / np.sqrt(np.maximum(values, 1e-12 * values.max()))) @ vectors.T


def _gls_chi2(basis: np.ndarray, adev: np.ndarray, whiten: np.ndarray,
              start: np.ndarray) -> float:
    """Return the least generalised chi-square of ln ``adev`` over non-negative squares."""
    tiny = np.finfo(float).tiny
    scale = np.median(adev[:, None] ** 2 / np.maximum(basis, tiny), axis=0)
    design = basis * scale
    fitted = least_squares(lambda x: whiten @ _log_residual(design, x, adev),
                           np.maximum(start / scale, 1e-8), bounds=(0.0, np.inf),
                           x_scale="jac", xtol=1e-12, ftol=1e-12)
    return float(fitted.fun @ fitted.fun)


def _check_terms(terms: tuple[str, ...], n_taus: int, line_hz: float | None) -> tuple[str, ...]:
    terms = tuple(terms)
    for k in terms:
        if k not in ALL_TERMS:
            raise InputError(f"unknown noise term {k!r}{did_you_mean(str(k), ALL_TERMS)}; "
                             f"terms: {', '.join(ALL_TERMS)}")
    if not terms or len(set(terms)) != len(terms):
        raise InputError(f"terms must be distinct names among {', '.join(ALL_TERMS)}, got {terms}")
    if "S" in terms and line_hz is None:
        raise InputError("the sinusoidal term S needs a spectral line, and the record has none")
    if line_hz is not None:
        terms = (*terms, "S")
    if len(set(terms)) > n_taus:
        raise InputError(f"{len(set(terms))} terms cannot be fitted to {n_taus} averaging times")
    return tuple(k for k in ALL_TERMS if k in terms)


def _start(result: AllanResult, terms: tuple[str, ...], min_tau: float | None) -> int:
    """Index of the shortest averaging time fitted (see :func:`fit_noise`)."""
    last = len(result.taus) - len(terms) - 2
    if min_tau is not None:
        start = int(np.searchsorted(result.taus, float(min_tau) * (1.0 - 1e-9)))
        if start > last:
            raise InputError(f"min_tau = {min_tau:g} s leaves {len(result.taus) - start} "
                             f"averaging times for {len(terms)} terms")
        return start
    starts = range(min(int(np.sum(result.taus * result.rate <= FILTER_SAMPLES)), last + 1))
    misfits = []
    for start in starts:
        resid = _curve_fit(result, terms, start)[2]
        misfits.append(float(np.mean(_weights(result.edf[start:]) * resid**2)))
    if not misfits:
        return 0
    return int(np.argmax(np.array(misfits) <= 1.5 * min(misfits)))


def _weights(edf: np.ndarray) -> np.ndarray:
    """Inverse variance of each log deviation with the model allowance."""
    return 1.0 / (0.5 / edf + MODEL_ALLOWANCE**2)


def _unbiased(adev: np.ndarray, edf: np.ndarray) -> np.ndarray:
    """Return ``adev`` scaled so that its logarithm is unbiased.

    ``ln`` of a chi-square variance with ``edf`` degrees of freedom is low by
    ``ln(edf/2) - digamma(edf/2)`` on average (about 1/edf), which would pull a log fit down
    by several per cent where few clusters remain.
    """
    return adev * np.exp(0.5 * (np.log(edf / 2.0) - digamma(edf / 2.0)))


def _log_residual(basis: np.ndarray, squared: np.ndarray, adev: np.ndarray) -> np.ndarray:
    model = np.maximum(basis @ squared, np.finfo(float).tiny)
    return 0.5 * np.log(model) - np.log(adev)


def _log_fit(basis: np.ndarray, adev: np.ndarray, edf: np.ndarray) -> np.ndarray:
    """Non-negative squared coefficients minimising the weighted misfit of ``ln adev``.

    Started from non-negative least squares on the relative misfit of the
    Allan variance, each column scaled to the size of the data (they span
    many decades of tau).
    """
    scale = np.median(adev[:, None] ** 2 / np.maximum(basis, np.finfo(float).tiny), axis=0)
    design = basis * scale / adev[:, None] ** 2
    start = np.maximum(nnls(design, np.ones(len(adev)))[0], 1e-6)
    root_w = np.sqrt(_weights(edf))
    fitted = least_squares(lambda x: root_w * _log_residual(design, x, np.ones(len(adev))),
                           start, bounds=(0.0, np.inf), x_scale="jac", xtol=1e-12, ftol=1e-12)
    return fitted.x * scale


def _curve_fit(result: AllanResult, terms: tuple[str, ...], start: int,
               gm_tc: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the basis from ``start`` on, the squared coefficients fitted there, residuals.

    The coefficients are fitted to the bias-corrected ln ADEV.
    """
    basis = _basis(result.taus[start:], terms, result.line_hz, gm_tc)
    adev = _unbiased(result.adev[start:], result.edf[start:])
    squared = _log_fit(basis, adev, result.edf[start:])
    return basis, squared, _log_residual(basis, squared, adev)


def _fit_terms(result: AllanResult, terms: tuple[str, ...], start: int,
               gm_tc: float | None = None
               ) -> tuple[dict[str, tuple[float, float]], float, np.ndarray, np.ndarray]:
    """Return ``{term: (squared coefficient, its standard error)}`` of one fit, and more.

    Also the misfit, the residuals of ln ADEV and their covariance.
    """
    fitted, edf = slice(start, None), result.edf[start:]
    basis, squared, resid = _curve_fit(result, terms, start, gm_tc)
    variance = 0.5 / edf
    misfit = _paule_mandel(resid, variance, int(np.count_nonzero(squared)))
    rho = _correlation(result, dict(zip(terms, squared)), gm_tc)[fitted, fitted]
    cov = np.sqrt(np.outer(variance, variance)) * rho + misfit**2 * np.eye(len(edf))
    root_w = np.sqrt(_weights(edf))
    jacobian = 0.5 * basis / np.maximum(basis @ squared, np.finfo(float).tiny)[:, None]
    se = _squared_stderr(jacobian * root_w[:, None], cov * np.outer(root_w, root_w),
                         squared > 0)
    return ({k: (float(c), float(v)) for k, c, v in zip(terms, squared, se)}, misfit, resid,
            cov)


def _chi2(resid: np.ndarray, cov: np.ndarray) -> float:
    """Return the generalised chi-square ``r' C^-1 r``.

    A ridge of 1e-9 of the mean variance keeps the nearly singular correlation of
    neighbouring taus invertible.
    """
    ridge = 1e-9 * float(np.mean(np.diag(cov))) * np.eye(len(cov))
    return float(resid @ np.linalg.solve(cov + ridge, resid))


def _paule_mandel(resid: np.ndarray, variance: np.ndarray, n_params: int) -> float:
    """Relative misfit ``s`` with ``sum(resid^2/(variance + s^2)) = n - p`` (0 if none needed)."""
    dof = len(resid) - n_params
    excess = lambda s: float(np.sum(resid**2 / (variance + s**2))) - dof  # noqa: E731
    if dof <= 0 or excess(0.0) <= 0:
        return 0.0
    return float(brentq(excess, 0.0, 10.0 * float(np.max(np.abs(resid))) + 1.0, xtol=1e-6))


def _squared_stderr(x: np.ndarray, cov: np.ndarray, active: np.ndarray) -> np.ndarray:
    """Sandwich standard errors of least squares on the weighted design ``x``.

    ``cov`` is the covariance of the weighted residuals.  Each term's error
    is taken from the fit with the active (non-zero) terms and itself.
    """
    out = np.empty(x.shape[1])
    for k in range(x.shape[1]):
        cols = np.flatnonzero(active | (np.arange(x.shape[1]) == k))
        norms = np.linalg.norm(x[:, cols], axis=0)
        xs = x[:, cols] / norms
        bread = np.linalg.pinv(xs.T @ xs)
        sandwich = bread @ xs.T @ cov @ xs @ bread
        j = int(np.flatnonzero(cols == k)[0])
        out[k] = math.sqrt(max(sandwich[j, j], 0.0)) / norms[j]
    return out


def _correlation(result: AllanResult, squared: dict[str, float],
                 gm_tc: float | None = None) -> np.ndarray:
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
    weight = _spectrum(mid, squared, result.rate, gm_tc) ** 2 * np.diff(edges)
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
