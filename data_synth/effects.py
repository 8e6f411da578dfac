"""Deterministic and input-driven effects, and the output quantizer.

Biases, scale factor and lagged inputs from other columns have exact lag
representations (constant ``1``, ``temp_c[n-0]^k``, ``accel_x[n-3]``...).
Functions of time (vibration sinusoids, bias steps, drifts) have none: their
truth gives the parameters (frequency, amplitude, phase, step time...) and
``terms: null``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.polynomial import Polynomial
from scipy.signal import lfilter

from data_synth.base import Source, as_float_tuple
from data_synth.terms import Representation, TermSet, add_term


def _time(n: int, rate: float) -> np.ndarray:
    return np.arange(n) / rate


@dataclass(frozen=True)
class ConstantBias(Source):
    """Constant (calibration-residual) bias ``value`` in the channel unit."""

    value: float
    kind: ClassVar[str] = "constant_bias"
    constant: ClassVar[bool] = True

    def generate(self, n, rate, rng, inputs=None):
        return np.full(n, float(self.value))

    def params(self, rate, units, out):
        return {"value": self.value, "units": {"value": units}}

    def representation(self, rate, out):
        return Representation({(): float(self.value)})


@dataclass(frozen=True)
class TurnOnBias(Source):
    """Run-to-run (turn-on) bias: one constant per record drawn from ``N(0, sigma^2)``.

    The drawn value is in the truth (``params.value`` and the ``1`` term).
    """

    sigma: float
    kind: ClassVar[str] = "turn_on_bias"
    constant: ClassVar[bool] = True

    def generate(self, n, rate, rng, inputs=None):
        return np.full(n, self.sigma * rng.standard_normal())

    def params(self, rate, units, out):
        return {
            "sigma": self.sigma,
            "value": float(out[0]),
            "units": {"sigma": units, "value": units},
        }

    def representation(self, rate, out):
        return Representation({(): float(out[0])})


@dataclass(frozen=True)
class ScaleFactorError(Source):
    """Scale-factor error ``scale * u[n]`` under the true rate or specific force column ``input``.

    ``scale`` is a fraction (Park 2004, Table 4.2: -0.3984 % is ``-0.003984``).
    """

    scale: float
    input: str
    kind: ClassVar[str] = "scale_factor"

    @property
    def requires(self):
        return (self.input,)

    def generate(self, n, rate, rng, inputs: Mapping[str, np.ndarray] | None = None):
        return self.scale * self.need(inputs, self.input, n)

    def params(self, rate, units, out):
        return {
            "input": self.input,
            "scale": self.scale,
            "scale_percent": 100.0 * self.scale,
            "units": {"scale": "1", "scale_percent": "%"},
        }

    def representation(self, rate, out):
        return Representation({((self.input, 0),): self.scale})


@dataclass(frozen=True)
class AuxInput(Source):
    """Another column entering through lags: ``sum_k gains[k] * u[n-k]``.

    Parameters
    ----------
    input : str
        The column ``u`` (e.g. ``accel_x``: a gyro's g-sensitivity).
    gains : mapping of int to float
        ``{lag: gain}``, lags >= 0, gains in channel unit per input unit.
        Samples before the start of the record repeat ``u[0]``.
    """

    input: str
    gains: Mapping[int, float]
    kind: ClassVar[str] = "aux_input"

    def __post_init__(self):
        gains = {int(k): float(v) for k, v in dict(self.gains).items()}
        if not gains or min(gains) < 0:
            raise ValueError(f"{self.label}: need at least one gain at a lag >= 0")
        object.__setattr__(self, "gains", dict(sorted(gains.items())))

    @property
    def requires(self):
        return (self.input,)

    def generate(self, n, rate, rng, inputs: Mapping[str, np.ndarray] | None = None):
        u = self.need(inputs, self.input, n)
        lmax = max(self.gains)
        padded = np.concatenate([np.full(lmax, u[0] if n else 0.0), u])
        return sum(g * padded[lmax - lag : lmax - lag + n] for lag, g in self.gains.items())

    def params(self, rate, units, out):
        return {
            "input": self.input,
            "gains": [{"lag": k, "gain": g} for k, g in self.gains.items()],
            "delays_s": [k / rate for k in self.gains],
            "units": {"gain": f"{units} per unit of {self.input}", "delays_s": "s"},
        }

    def representation(self, rate, out):
        return Representation({((self.input, k),): g for k, g in self.gains.items()})


@dataclass(frozen=True)
class TemperatureBias(Source):
    """Temperature-dependent bias ``sum_k coefs[k] * (T - t_ref_c)^k`` of the column ``input``.

    ``T`` is the column itself, or with ``lag_s > 0`` the sensor's own temperature
    following it through a first-order thermal lag,
    ``T[n] = phi T[n-1] + (1 - phi) u[n]``, ``phi = exp(-1/(rate*lag_s))``, settled
    at ``u[0]`` before the start (the convention of
    :class:`~data_synth.profiles.StepProfile`).  The truth gives the coefficients
    about ``t_ref_c`` and, without a lag, as terms, the same polynomial expanded in
    powers of the raw column: ``1``, ``temp_c[n-0]``, ``temp_c[n-0]^2``...; a lagged
    bias has no finite lag form (its terms are null).
    """

    coefs: tuple[float, ...]
    t_ref_c: float = 25.0
    input: str = "temp_c"
    lag_s: float = 0.0
    kind: ClassVar[str] = "temperature_bias"

    def __post_init__(self):
        object.__setattr__(self, "coefs", as_float_tuple(self.coefs, "coefs"))
        if not (math.isfinite(self.lag_s) and self.lag_s >= 0):
            raise ValueError(f"{self.label}: lag_s must be >= 0, got {self.lag_s!r}")

    @property
    def requires(self):
        return (self.input,)

    def raw_coefs(self) -> tuple[float, ...]:
        """Coefficients of the polynomial in ``T`` itself (power 0 first)."""
        shifted = Polynomial(self.coefs)(Polynomial([-self.t_ref_c, 1.0]))
        raw = np.zeros(len(self.coefs))
        raw[: len(shifted.coef)] = shifted.coef
        return tuple(float(c) for c in raw)

    def sensor_temperature(self, temp: np.ndarray, rate: float) -> np.ndarray:
        """The temperature the bias follows: ``temp`` itself, or through the thermal lag."""
        if self.lag_s == 0:
            return temp
        phi = math.exp(-1.0 / (rate * self.lag_s))
        return lfilter([1.0 - phi], [1.0, -phi], temp, zi=[phi * temp[0]])[0]

    def generate(self, n, rate, rng, inputs: Mapping[str, np.ndarray] | None = None):
        temp = self.sensor_temperature(self.need(inputs, self.input, n), rate)
        return Polynomial(self.coefs)(temp - self.t_ref_c)

    def params(self, rate, units, out):
        return {
            "input": self.input,
            "t_ref_c": self.t_ref_c,
            "coefs": list(self.coefs),
            "raw_coefs": list(self.raw_coefs()),
            "lag_s": self.lag_s,
            "formula": "sum_k coefs[k]*(T - t_ref_c)^k, T = the input column, or with lag_s > 0 "
            "T[n] = phi*T[n-1] + (1 - phi)*input[n], phi = exp(-1/(rate_hz*lag_s)), "
            "T[-1] = input[0]",
            "units": {
                "t_ref_c": "degC",
                "coefs": f"{units}/degC^k (k = index)",
                "raw_coefs": f"{units}/degC^k (k = index)",
                "lag_s": "s",
            },
        }

    def representation(self, rate, out):
        if self.lag_s > 0:
            return None
        terms: TermSet = {}
        for k, c in enumerate(self.raw_coefs()):
            add_term(terms, [(self.input, 0)] * k, c)
        return Representation(terms)


@dataclass(frozen=True)
class Vibration(Source):
    """Periodic vibration: ``sum_h amplitudes[h-1] sin(2 pi h freq_hz t + phases_rad[h-1])``.

    Harmonic ``h`` runs at ``h*freq_hz``; ``t = n/rate``.  The truth lists each
    harmonic's frequency, amplitude, phase and FFT bin position
    ``h*freq_hz*N/rate`` (an integer means on the FFT grid).
    """

    freq_hz: float
    amplitudes: tuple[float, ...]
    phases_rad: tuple[float, ...] | None = None
    kind: ClassVar[str] = "vibration"

    def __post_init__(self):
        object.__setattr__(self, "amplitudes", as_float_tuple(self.amplitudes, "amplitudes"))
        object.__setattr__(self, "phases_rad", as_float_tuple(self.phases, "phases_rad"))
        if len(self.phases) != len(self.amplitudes) or self.freq_hz <= 0:
            raise ValueError(f"{self.label}: need freq_hz > 0 and one phase per amplitude")

    @property
    def phases(self) -> tuple[float, ...]:
        """The phase of each harmonic in radians: ``phases_rad``, zeros if none were given."""
        return (0.0,) * len(self.amplitudes) if self.phases_rad is None else self.phases_rad

    def generate(self, n, rate, rng, inputs=None):
        t = _time(n, rate)
        out = np.zeros(n)
        for h, (amp, phase) in enumerate(zip(self.amplitudes, self.phases), start=1):
            out += amp * np.sin(2 * math.pi * h * self.freq_hz * t + phase)
        return out

    def params(self, rate, units, out):
        n = len(out)
        return {
            "freq_hz": self.freq_hz,
            "harmonics": [
                {
                    "harmonic": h,
                    "freq_hz": h * self.freq_hz,
                    "amplitude": a,
                    "phase_rad": ph,
                    "fft_bin": h * self.freq_hz * n / rate,
                }
                for h, (a, ph) in enumerate(zip(self.amplitudes, self.phases), start=1)
            ],
            "formula": "sum_h amplitude*sin(2*pi*freq_hz*t + phase_rad), t = n/rate_hz",
            "units": {"freq_hz": "Hz", "amplitude": units, "phase_rad": "rad"},
        }


@dataclass(frozen=True)
class BiasStep(Source):
    """Bias steps: ``amplitudes[i]`` added from time ``times_s[i]`` on."""

    times_s: tuple[float, ...]
    amplitudes: tuple[float, ...]
    kind: ClassVar[str] = "bias_step"

    def __post_init__(self):
        object.__setattr__(self, "times_s", as_float_tuple(self.times_s, "times_s"))
        object.__setattr__(self, "amplitudes", as_float_tuple(self.amplitudes, "amplitudes"))
        if len(self.times_s) != len(self.amplitudes):
            raise ValueError(f"{self.label}: need one amplitude per step time")

    def samples(self, n: int, rate: float) -> list[int]:
        """Index of the first sample at or after each step time."""
        return [int(i) for i in np.searchsorted(_time(n, rate), self.times_s, side="left")]

    def generate(self, n, rate, rng, inputs=None):
        out = np.zeros(n)
        for start, amp in zip(self.samples(n, rate), self.amplitudes):
            out[start:] += amp
        return out

    def params(self, rate, units, out):
        return {
            "steps": [
                {"time_s": t, "sample": s, "amplitude": a}
                for t, s, a in zip(self.times_s, self.samples(len(out), rate), self.amplitudes)
            ],
            "units": {"time_s": "s", "amplitude": units},
        }


@dataclass(frozen=True)
class Drift(Source):
    """Linear and exponential (warm-up) drift ``slope_per_h*t/3600 + A (1 - exp(-t/tau))``.

    ``t`` is the time since ``start_s`` (0 before it): a warm-up that starts late, as a
    sensor's heater switched on some minutes into the record.
    """

    slope_per_h: float = 0.0
    warmup_amplitude: float = 0.0
    warmup_tau_s: float = 1.0
    start_s: float = 0.0
    kind: ClassVar[str] = "drift"

    def __post_init__(self):
        if self.warmup_tau_s <= 0:
            raise ValueError(f"{self.label}: warmup_tau_s must be > 0")
        if not (math.isfinite(self.start_s) and self.start_s >= 0):
            raise ValueError(f"{self.label}: start_s must be >= 0, got {self.start_s!r}")

    def generate(self, n, rate, rng, inputs=None):
        t = np.maximum(_time(n, rate) - self.start_s, 0.0)
        return self.slope_per_h * t / 3600.0 + self.warmup_amplitude * -np.expm1(
            -t / self.warmup_tau_s
        )

    def params(self, rate, units, out):
        return {
            "slope_per_h": self.slope_per_h,
            "warmup_amplitude": self.warmup_amplitude,
            "warmup_tau_s": self.warmup_tau_s,
            "start_s": self.start_s,
            "formula": "slope_per_h*t/3600 + warmup_amplitude*(1 - exp(-t/warmup_tau_s)), "
            "t = max(time - start_s, 0) in s",
            "units": {"slope_per_h": f"{units}/h", "warmup_amplitude": units,
                      "warmup_tau_s": "s", "start_s": "s"},
        }


@dataclass(frozen=True)
class Knocks(Source):
    """Knocks: ``count`` bursts of ``knock_s`` seconds each, at times drawn over the record.

    Each burst is a decaying oscillation (``amplitude`` at its start, ``freq_hz``, falling
    to 1 % by its end): what a bench bumped or a door slammed leaves on a static record.
    The times are drawn uniformly (the source's own stream), a knock's length apart at
    least.
    """

    count: int
    amplitude: float
    knock_s: float = 0.05
    freq_hz: float = 20.0
    kind: ClassVar[str] = "knocks"

    def __post_init__(self):
        if not (isinstance(self.count, (int, np.integer)) and self.count >= 1):
            raise ValueError(f"{self.label}: count must be a positive integer, got {self.count!r}")
        if not (math.isfinite(self.knock_s) and self.knock_s > 0):
            raise ValueError(f"{self.label}: knock_s must be > 0, got {self.knock_s!r}")

    def starts(self, n: int, rate: float, rng: np.random.Generator) -> np.ndarray:
        """The first sample of each knock, sorted."""
        width = max(1, round(self.knock_s * rate))
        slots = (n - width) // (2 * width)  # a knock's length of quiet after each
        if slots < self.count:
            raise ValueError(f"{self.label}: {self.count} knocks of {self.knock_s:g} s do not "
                             f"fit in {n / rate:g} s")
        return np.sort(rng.choice(slots, self.count, replace=False)) * 2 * width

    def generate(self, n, rate, rng, inputs=None):
        width = max(1, round(self.knock_s * rate))
        t = np.arange(width) / rate
        burst = self.amplitude * np.exp(np.log(0.01) * t / self.knock_s) * np.cos(
            2 * np.pi * self.freq_hz * t)
        out = np.zeros(n)
        for start in self.starts(n, rate, rng):
            out[start : start + width] += burst
        return out

    def params(self, rate, units, out):
        width = max(1, round(self.knock_s * rate))
        hit = np.flatnonzero(np.abs(out) > 0)
        first = hit[np.r_[True, np.diff(hit) > width]] if len(hit) else hit
        return {
            "count": self.count, "amplitude": self.amplitude, "knock_s": self.knock_s,
            "freq_hz": self.freq_hz, "times_s": [float(i / rate) for i in first],
            "formula": "amplitude*exp(ln(0.01)*t/knock_s)*cos(2 pi freq_hz t) for t in "
            "[0, knock_s) after each time",
            "units": {"amplitude": units, "knock_s": "s", "freq_hz": "Hz", "times_s": "s"},
        }


@dataclass(frozen=True)
class Quantizer:
    """Output quantization to multiples of ``lsb`` (round to nearest).

    Applied to the sum of all components of the channel; for a signal spread
    over many LSB the error is uniform with variance ``lsb^2/12``.
    """

    lsb: float
    kind: ClassVar[str] = "quantization"

    def __post_init__(self):
        if not self.lsb > 0:
            raise ValueError("lsb must be > 0")

    def apply(self, x: np.ndarray) -> np.ndarray:
        """Round ``x`` to the nearest multiple of ``lsb``."""
        return self.lsb * np.round(x / self.lsb)

    def params(self, units: str) -> dict[str, Any]:
        """Parameters for the truth."""
        return {
            "lsb": self.lsb,
            "error_variance": self.lsb**2 / 12.0,
            "units": {"lsb": units, "error_variance": f"({units})^2"},
        }
