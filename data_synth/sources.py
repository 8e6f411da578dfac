"""Stochastic error sources of a single channel.

All are vectorised: white noise is one normal draw, random walks a cumulative
sum, Gauss-Markov, AR(p) and flicker-like bias instability one
:func:`scipy.signal.lfilter` pass each, started from their stationary
distribution (exact for first order, after a burn-in to 1e-12 otherwise, so
the record has no transient).  The only per-sample Python loop is the nonlinear AR
process, whose cross-product dynamics admit no linear filter; it runs a tight
loop over Python floats (about 0.2 s per million samples).

Densities are in ``[channel unit]/sqrt(Hz)`` (white) and ``[channel
unit]/sqrt(s)`` (random walk); :mod:`data_synth.units` converts datasheet values.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy.signal import lfilter, lfiltic

from data_synth.base import Source, as_float_tuple
from data_synth.terms import OUTPUT, Representation, TermSet, add_term
from data_synth.units import (
    ACCEL_UNIT,
    RATE_UNITS,
    adev_flicker_floor,
    density_to_arw,
    density_to_vrw,
    random_walk_step,
    rate_factor,
    white_sigma,
)


def ar_roots(coefs: tuple[float, ...]) -> np.ndarray:
    """Characteristic roots of ``y[n] = sum_k coefs[k-1] y[n-k] + e[n]``."""
    return np.roots(np.r_[1.0, -np.asarray(coefs, dtype=float)])


def check_stable(coefs: tuple[float, ...], what: str) -> None:
    """Raise ValueError unless every characteristic root is inside the unit circle."""
    if coefs and np.max(np.abs(ar_roots(coefs))) >= 1.0:
        raise ValueError(
            f"{what}: AR coefficients {coefs} are not stationary (root on/outside |z|=1)"
        )


def ar_burn_in(coefs: tuple[float, ...], tol: float = 1e-12) -> int:
    """Samples after which the impulse response of an AR(p) is below ``tol``.

    With ``rho`` the largest root modulus the response is bounded by
    ``k^(p-1) rho^k`` (repeated roots), solved for ``k`` by fixed-point steps.
    """
    rho = float(np.max(np.abs(ar_roots(coefs))))
    if rho == 0.0:
        return len(coefs)
    k = math.log(tol) / math.log(rho)
    for _ in range(4):
        k = (math.log(tol) - (len(coefs) - 1) * math.log(max(k, 1.0))) / math.log(rho)
    return len(coefs) + math.ceil(k)


def ar_variance(coefs: tuple[float, ...], innovation_std: float = 1.0) -> float:
    """Stationary variance of an AR(p): ``innovation_std^2 * sum_k h[k]^2`` (impulse response)."""
    if len(coefs) == 1:
        return innovation_std**2 / (1.0 - coefs[0] ** 2)
    impulse = np.zeros(ar_burn_in(coefs))
    impulse[0] = 1.0
    h = lfilter([1.0], np.r_[1.0, -np.asarray(coefs, dtype=float)], impulse)
    return innovation_std**2 * float(np.dot(h, h))


def ar_filter(
    coefs: tuple[float, ...], innovation_std: float, n: int, rng: np.random.Generator
) -> np.ndarray:
    """``n`` samples of a stationary AR(p) process in one :func:`scipy.signal.lfilter` pass.

    AR(1) starts from an exact stationary draw; higher orders, whose lag-state
    covariance is numerically singular when roots crowd near 1, run
    :func:`ar_burn_in` samples first and drop them (the start is then
    stationary to 1e-12).
    """
    a = np.r_[1.0, -np.asarray(coefs, dtype=float)]
    if len(coefs) == 1:
        past = [math.sqrt(ar_variance(coefs, innovation_std)) * rng.standard_normal()]
        e = innovation_std * rng.standard_normal(n)
        return lfilter([1.0], a, e, zi=lfiltic([1.0], a, past))[0]
    burn = ar_burn_in(coefs)
    return lfilter([1.0], a, innovation_std * rng.standard_normal(n + burn))[burn:]


def _ar_terms(coefs: tuple[float, ...]) -> TermSet:
    terms: TermSet = {}
    for lag, c in enumerate(coefs, start=1):
        add_term(terms, [(OUTPUT, lag)], c)
    return terms


def _noise_units(units: str) -> dict[str, str]:
    return {"density": f"{units}/sqrt(Hz)", "sigma_per_sample": units}


@dataclass(frozen=True)
class WhiteNoise(Source):
    """White Gaussian noise: angle (gyro) or velocity (accelerometer) random walk.

    Parameters
    ----------
    density : float
        One-sided density in ``[unit]/sqrt(Hz)``; per-sample standard deviation
        ``density*sqrt(rate)``.  Use :func:`data_synth.units.arw_to_density` or
        :func:`~data_synth.units.vrw_to_density`.  Its Allan deviation is
        ``density/sqrt(tau)``.
    """

    density: float
    kind: ClassVar[str] = "white_noise"

    def generate(self, n, rate, rng, inputs=None):
        return white_sigma(self.density, rate) * rng.standard_normal(n)

    def params(self, rate, units, out):
        p: dict[str, Any] = {
            "density": self.density,
            "sigma_per_sample": white_sigma(self.density, rate),
            "units": _noise_units(units),
        }
        if units in RATE_UNITS:
            p["arw"] = density_to_arw(self.density, units)
            p["units"]["arw"] = "deg/sqrt(h)"
        elif units == ACCEL_UNIT:
            p["vrw"] = density_to_vrw(self.density)
            p["units"]["vrw"] = "m/s/sqrt(h)"
        return p

    def representation(self, rate, out):
        return Representation({}, white_sigma(self.density, rate))


@dataclass(frozen=True)
class RandomWalk(Source):
    """Rate random walk: a bias ``b[n] = b[n-1] + w[n]`` starting at ``b[0] = w[0]``.

    Parameters
    ----------
    density : float
        ``K`` in ``[unit]/sqrt(s)`` (for a gyro in deg/s: deg/sqrt(s^3), seed
        004 Table 5.1); increments have standard deviation ``K/sqrt(rate)`` and
        the Allan deviation is ``K*sqrt(tau/3)`` (slope +1/2).
    """

    density: float
    kind: ClassVar[str] = "random_walk"

    def generate(self, n, rate, rng, inputs=None):
        return np.cumsum(random_walk_step(self.density, rate) * rng.standard_normal(n))

    def params(self, rate, units, out):
        p: dict[str, Any] = {
            "density": self.density,
            "step_std": random_walk_step(self.density, rate),
            "units": {"density": f"{units}/sqrt(s)", "step_std": units},
        }
        if units in RATE_UNITS:
            p["rrw"] = self.density / rate_factor(units)
            p["units"]["rrw"] = "deg/sqrt(s^3)"
        return p

    def representation(self, rate, out):
        return Representation({((OUTPUT, 1),): 1.0}, random_walk_step(self.density, rate))


@dataclass(frozen=True)
class ARProcess(Source):
    """Stationary AR(p): ``x[n] = sum_k coefs[k-1] x[n-k] + e[n]``, ``e ~ N(0, innovation_std^2)``.

    The coefficients are per sample (they keep their values if the record rate
    changes).  The truth terms ``y[n-k]`` apply to this component alone.
    """

    coefs: tuple[float, ...]
    innovation_std: float
    kind: ClassVar[str] = "ar"

    def __post_init__(self):
        object.__setattr__(self, "coefs", as_float_tuple(self.coefs, "coefs"))
        if not self.coefs or self.innovation_std <= 0:
            raise ValueError(f"{self.label}: need at least one coefficient and innovation_std > 0")
        check_stable(self.coefs, self.label)

    def generate(self, n, rate, rng, inputs=None):
        return ar_filter(self.coefs, self.innovation_std, n, rng)

    def params(self, rate, units, out):
        return {
            "coefs": list(self.coefs),
            "innovation_std": self.innovation_std,
            "stationary_std": math.sqrt(ar_variance(self.coefs, self.innovation_std)),
            "units": {"innovation_std": units, "stationary_std": units},
            "convention": "x[n] = sum_k coefs[k-1]*x[n-k] + e[n] on this component alone",
        }

    def representation(self, rate, out):
        return Representation(_ar_terms(self.coefs), self.innovation_std)


@dataclass(frozen=True)
class GaussMarkov(Source):
    """First- or higher-order Gauss-Markov process with correlation time ``tau_s``.

    Order 1 is ``x[n] = phi x[n-1] + w[n]`` with ``phi = exp(-1/(rate*tau_s))``,
    autocorrelation ``sigma^2 exp(-|t|/tau_s)``.  Order ``m`` cascades ``m``
    identical first-order stages: an AR(m) process with the repeated pole
    ``phi`` (coefficients of ``(1 - phi z^-1)^m``), whose autocorrelation is
    flat at the origin like the higher-order GM of Tamazin et al. (2013) Figure 2.

    Parameters
    ----------
    sigma : float
        Stationary standard deviation of the output, in the channel unit.
    tau_s : float
        Correlation time of each stage in seconds.
    order : int
        Number of stages.
    """

    sigma: float
    tau_s: float
    order: int = 1
    kind: ClassVar[str] = "gauss_markov"

    def __post_init__(self):
        if self.sigma <= 0 or self.tau_s <= 0 or self.order < 1:
            raise ValueError(f"{self.label}: need sigma > 0, tau_s > 0, order >= 1")

    def phi(self, rate: float) -> float:
        """Pole of one stage at ``rate`` Hz."""
        return math.exp(-1.0 / (rate * self.tau_s))

    def coefs(self, rate: float) -> tuple[float, ...]:
        """AR(order) coefficients at ``rate`` Hz."""
        return tuple(float(-c) for c in np.poly([self.phi(rate)] * self.order)[1:])

    def innovation_std(self, rate: float) -> float:
        """Standard deviation of the AR innovation giving the stationary ``sigma``."""
        return self.sigma / math.sqrt(ar_variance(self.coefs(rate)))

    def generate(self, n, rate, rng, inputs=None):
        return ar_filter(self.coefs(rate), self.innovation_std(rate), n, rng)

    def params(self, rate, units, out):
        return {
            "sigma": self.sigma,
            "tau_s": self.tau_s,
            "order": self.order,
            "phi": self.phi(rate),
            "ar_coefs": list(self.coefs(rate)),
            "innovation_std": self.innovation_std(rate),
            "units": {"sigma": units, "tau_s": "s", "innovation_std": units},
            "convention": "x[n] = sum_k ar_coefs[k-1]*x[n-k] + e[n] on this component alone",
        }

    def representation(self, rate, out):
        return Representation(_ar_terms(self.coefs(rate)), self.innovation_std(rate))


@dataclass(frozen=True)
class BiasInstability(Source):
    """Flicker-like bias instability as a sum of first-order Gauss-Markov processes.

    The target is the IEEE Std 952 flicker rate spectrum ``S(f) = B^2/(2 pi f)``
    (two-sided density, the convention in which white noise of per-sample
    standard deviation ``N sqrt(rate)`` has ``S = N^2``), whose Allan deviation
    is flat at ``sqrt(2 ln 2/pi) B ~ 0.664 B``.  It is built from ``per_decade``
    GM processes per decade with correlation times log-spaced from
    ``tau_min_s`` to ``tau_max_s`` (ratio ``r``).  A GM of variance ``s^2`` and
    correlation time ``T`` has ``S(f) = 2 s^2 T/(1 + (2 pi f T)^2)``; summed
    over ``T`` with density ``1/ln r`` per unit of ``ln T`` this is
    ``s^2/(2 f ln r)``, so each GM gets the variance ``B^2 ln(r)/pi`` and the
    sum approximates ``1/f`` between
    ``1/(2 pi tau_max)`` and ``1/(2 pi tau_min)``, so the Allan deviation is flat
    for ``tau`` well inside ``[tau_min_s, tau_max_s]``.

    Parameters
    ----------
    bias_instability : float
        ``B`` in the channel unit.
    tau_min_s, tau_max_s : float
        Band of correlation times in seconds.
    per_decade : int
        GM processes per decade (3 keeps the ripple of the floor within a few %).
    """

    bias_instability: float
    tau_min_s: float
    tau_max_s: float
    per_decade: int = 3
    kind: ClassVar[str] = "bias_instability"

    def __post_init__(self):
        if not 0 < self.tau_min_s < self.tau_max_s or self.per_decade < 1:
            raise ValueError(f"{self.label}: need 0 < tau_min_s < tau_max_s and per_decade >= 1")

    def taus(self) -> np.ndarray:
        """Correlation times of the GM components in seconds."""
        k = max(2, round(self.per_decade * math.log10(self.tau_max_s / self.tau_min_s)) + 1)
        return np.geomspace(self.tau_min_s, self.tau_max_s, k)

    def component_sigma(self) -> float:
        """Standard deviation of each GM component, ``B sqrt(ln(r)/pi)``."""
        taus = self.taus()
        return self.bias_instability * math.sqrt(math.log(taus[1] / taus[0]) / math.pi)

    def generate(self, n, rate, rng, inputs=None):
        sigma = self.component_sigma()
        out = np.zeros(n)
        for tau in self.taus():
            phi = math.exp(-1.0 / (rate * tau))
            out += ar_filter((phi,), sigma * math.sqrt(1.0 - phi * phi), n, rng)
        return out

    def params(self, rate, units, out):
        return {
            "bias_instability": self.bias_instability,
            "adev_floor": adev_flicker_floor(self.bias_instability),
            "tau_min_s": self.tau_min_s,
            "tau_max_s": self.tau_max_s,
            "gm_taus_s": self.taus().tolist(),
            "gm_sigma": self.component_sigma(),
            "units": {"bias_instability": units, "adev_floor": units, "gm_sigma": units},
        }


@dataclass(frozen=True)
class NonlinearAR(Source):
    """AR process with bounded cross-product terms (a quadratic NARX of the component).

    ``x[n] = sum_k coefs[k-1] x[n-k] + sum c x[n-i] x[n-j] + e[n]`` for each
    ``(i, j, c)`` in ``cross``.  A quadratic map escapes to infinity past the
    radius ``R = (1 - sum coefs)/sum |c|``; construction requires ``R`` to be at
    least 8 stationary standard deviations of the linear part, and generation
    raises if the state ever leaves ``R``.  The first samples of a run burn in
    the dynamics from zero (until the linear impulse response decays below 1e-12).

    This is the one source with a per-sample Python loop (over Python floats,
    about 0.2 s per million samples; numba is not available).
    """

    coefs: tuple[float, ...]
    cross: tuple[tuple[int, int, float], ...]
    innovation_std: float
    kind: ClassVar[str] = "nonlinear_ar"

    def __post_init__(self):
        object.__setattr__(self, "coefs", as_float_tuple(self.coefs, "coefs"))
        cross = tuple(
            (min(int(i), int(j)), max(int(i), int(j)), float(c)) for i, j, c in self.cross
        )
        if any(i < 1 for i, _, _ in cross):
            raise ValueError(f"{self.label}: cross-product lags must be >= 1")
        object.__setattr__(self, "cross", cross)
        check_stable(self.coefs, self.label)
        radius, lin_std = self.escape_radius(), self.linear_std()
        if radius < 8 * lin_std:
            raise ValueError(
                f"{self.label}: escape radius {radius:.3g} is under 8 linear std ({lin_std:.3g});"
                " reduce the cross coefficients or the innovation"
            )

    def linear_std(self) -> float:
        """Stationary standard deviation of the linear part alone."""
        if not self.coefs:
            return self.innovation_std
        return math.sqrt(ar_variance(self.coefs, self.innovation_std))

    def escape_radius(self) -> float:
        """``(1 - sum coefs)/sum |c|`` (infinite without cross terms)."""
        total = sum(abs(c) for _, _, c in self.cross)
        return math.inf if total == 0 else (1.0 - sum(self.coefs)) / total

    def burn_in(self) -> int:
        """Samples discarded at the start so the zero initial state is forgotten."""
        return self.max_lag() + (ar_burn_in(self.coefs) if self.coefs else 0)

    def max_lag(self) -> int:
        """Largest lag of any term."""
        return max([len(self.coefs)] + [j for _, j, _ in self.cross] + [1])

    def generate(self, n, rate, rng, inputs=None):
        p, burn = self.max_lag(), self.burn_in()
        y = [0.0] * p + (self.innovation_std * rng.standard_normal(n + burn)).tolist()
        lin = [(k, a) for k, a in enumerate(self.coefs, start=1) if a != 0.0]
        cross = [(i, j, c) for i, j, c in self.cross if c != 0.0]
        for t in range(p, len(y)):
            v = y[t]
            for k, a in lin:
                v += a * y[t - k]
            for i, j, c in cross:
                v += c * y[t - i] * y[t - j]
            y[t] = v
        out = np.array(y[p + burn :])
        if not np.all(np.abs(out) < self.escape_radius()):
            raise RuntimeError(f"{self.label}: the nonlinear AR state left its escape radius")
        return out

    def params(self, rate, units, out):
        return {
            "coefs": list(self.coefs),
            "cross": [{"lags": [i, j], "coef": c} for i, j, c in self.cross],
            "innovation_std": self.innovation_std,
            "linear_std": self.linear_std(),
            "escape_radius": None if math.isinf(self.escape_radius()) else self.escape_radius(),
            "burn_in_samples": self.burn_in(),
            "units": {
                "innovation_std": units,
                "linear_std": units,
                "escape_radius": units,
                "cross": f"1/({units})",
            },
            "convention": "x[n] = sum_k coefs[k-1]*x[n-k] + sum c*x[n-i]*x[n-j] + e[n]",
        }

    def representation(self, rate, out):
        terms = _ar_terms(self.coefs)
        for i, j, c in self.cross:
            add_term(terms, [(OUTPUT, i), (OUTPUT, j)], c)
        return Representation(terms, self.innovation_std)


@dataclass(frozen=True)
class TemperatureWhiteNoise(Source):
    """White noise whose density depends on temperature (El-Diasty et al. 2007, Table 1).

    The density is interpolated linearly in the ``input`` temperature column
    between the points ``(temps_c, densities)`` (held constant outside them).
    """

    temps_c: tuple[float, ...]
    densities: tuple[float, ...]
    input: str = "temp_c"
    kind: ClassVar[str] = "temperature_white_noise"

    def __post_init__(self):
        object.__setattr__(self, "temps_c", as_float_tuple(self.temps_c, "temps_c"))
        object.__setattr__(self, "densities", as_float_tuple(self.densities, "densities"))
        if len(self.temps_c) != len(self.densities) or np.any(np.diff(self.temps_c) <= 0):
            raise ValueError(f"{self.label}: need increasing temps_c, one density each")

    @property
    def requires(self):
        return (self.input,)

    def generate(self, n, rate, rng, inputs: Mapping[str, np.ndarray] | None = None):
        temp = self.need(inputs, self.input, n)
        density = np.interp(temp, self.temps_c, self.densities)
        return density * math.sqrt(rate) * rng.standard_normal(n)

    def params(self, rate, units, out):
        p: dict[str, Any] = {
            "input": self.input,
            "temps_c": list(self.temps_c),
            "densities": list(self.densities),
            "units": {"temps_c": "degC", "densities": f"{units}/sqrt(Hz)"},
        }
        if units in RATE_UNITS:
            p["arw"] = [density_to_arw(d, units) for d in self.densities]
            p["units"]["arw"] = "deg/sqrt(h)"
        elif units == ACCEL_UNIT:
            p["vrw"] = [density_to_vrw(d) for d in self.densities]
            p["units"]["vrw"] = "m/s/sqrt(h)"
        return p
