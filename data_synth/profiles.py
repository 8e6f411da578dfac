"""Deterministic profiles for auxiliary columns: temperature, true rate.

A profile is a source without randomness; it is usually placed on its own
column (``channel="temp_c"``) and profiles on one column add up, e.g. a warm-up
plus a room cycle.  Temperature-driven effects then read that column.

* :class:`WarmUp` -- exponential warm-up of the sensor after power-on;
* :class:`StepProfile` -- held levels with a first-order lag: thermal-chamber
  steps from -30 to +60 C (El-Diasty et al. 2007) or rate-table steps (Park 2004, Fig. 4.7);
* :class:`RoomCycle` -- slow periodic room temperature cycle;
* :class:`Sweep` -- slow piecewise-linear sweeps with flat stretches (a day-long
  session warming from 5 C, held, cooled...).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy.signal import lfilter

from data_synth.base import Source, as_float_tuple

#: Thermal-chamber set points of El-Diasty et al. (2007): -30 to +60 C every 10 C.
CHAMBER_LEVELS_C: tuple[float, ...] = tuple(float(t) for t in range(-30, 61, 10))


@dataclass(frozen=True)
class WarmUp(Source):
    """``start_c + rise_c * (1 - exp(-t/tau_s))``: self-heating after power-on."""

    start_c: float
    rise_c: float
    tau_s: float
    kind: ClassVar[str] = "warm_up"

    def __post_init__(self):
        if self.tau_s <= 0:
            raise ValueError(f"{self.label}: tau_s must be > 0")

    def generate(self, n, rate, rng, inputs=None):
        return self.start_c + self.rise_c * -np.expm1(-np.arange(n) / rate / self.tau_s)

    def params(self, rate, units, out):
        return {
            "start": self.start_c,
            "rise": self.rise_c,
            "tau_s": self.tau_s,
            "formula": "start + rise*(1 - exp(-t/tau_s))",
            "units": {"start": units, "rise": units, "tau_s": "s"},
        }


@dataclass(frozen=True)
class StepProfile(Source):
    """Held levels followed through a first-order lag.

    Level ``levels[i]`` is commanded from ``i*dwell_s`` to ``(i+1)*dwell_s``
    (the last one holds to the end); the output follows it as
    ``x[n] = phi x[n-1] + (1 - phi) c[n]`` with ``phi = exp(-1/(rate*lag_s))``
    (no lag for ``lag_s = 0``), starting settled at ``levels[0]``.

    Parameters
    ----------
    levels : sequence of float
        Set points in the column unit.
    dwell_s : float, optional
        Time per level; default: the record divided equally among the levels.
    lag_s : float
        Time constant of the first-order response (sensor thermal lag).
    """

    levels: tuple[float, ...]
    dwell_s: float | None = None
    lag_s: float = 0.0
    kind: ClassVar[str] = "step_profile"

    def __post_init__(self):
        object.__setattr__(self, "levels", as_float_tuple(self.levels, "levels"))
        if self.lag_s < 0 or (self.dwell_s is not None and self.dwell_s <= 0):
            raise ValueError(f"{self.label}: need lag_s >= 0 and dwell_s > 0")

    def dwell(self, n: int, rate: float) -> float:
        """Dwell time per level in seconds for a record of ``n`` samples."""
        return self.dwell_s if self.dwell_s is not None else n / rate / len(self.levels)

    def generate(self, n, rate, rng, inputs=None):
        index = np.minimum(
            (np.arange(n) / rate / self.dwell(n, rate)).astype(int), len(self.levels) - 1
        )
        command = np.asarray(self.levels)[index]
        if self.lag_s == 0:
            return command
        phi = math.exp(-1.0 / (rate * self.lag_s))
        return lfilter([1.0 - phi], [1.0, -phi], command, zi=[phi * self.levels[0]])[0]

    def params(self, rate, units, out):
        return {
            "levels": list(self.levels),
            "dwell_s": self.dwell(len(out), rate),
            "lag_s": self.lag_s,
            "units": {"levels": units, "dwell_s": "s", "lag_s": "s"},
        }


@dataclass(frozen=True)
class RoomCycle(Source):
    """``mean_c + amplitude_c * sin(2 pi t/period_s + phase_rad)``: a slow room cycle."""

    amplitude_c: float
    period_s: float
    mean_c: float = 0.0
    phase_rad: float = 0.0
    kind: ClassVar[str] = "room_cycle"

    def __post_init__(self):
        if self.period_s <= 0:
            raise ValueError(f"{self.label}: period_s must be > 0")

    def generate(self, n, rate, rng, inputs=None):
        t = np.arange(n) / rate
        return self.mean_c + self.amplitude_c * np.sin(
            2 * math.pi * t / self.period_s + self.phase_rad
        )

    def params(self, rate, units, out):
        return {
            "amplitude": self.amplitude_c,
            "period_s": self.period_s,
            "mean": self.mean_c,
            "phase_rad": self.phase_rad,
            "formula": "mean + amplitude*sin(2*pi*t/period_s + phase_rad)",
            "units": {"amplitude": units, "mean": units, "period_s": "s", "phase_rad": "rad"},
        }


@dataclass(frozen=True)
class Sweep(Source):
    """Piecewise-linear path through the knots ``(times_s[i], levels[i])``.

    Linear between knots, held at the first level before the first knot and at the
    last after the last one; two knots at one level make a flat stretch.

    Parameters
    ----------
    times_s : sequence of float
        Knot times in seconds, strictly increasing.
    levels : sequence of float
        The column's value at each knot.
    """

    times_s: tuple[float, ...]
    levels: tuple[float, ...]
    kind: ClassVar[str] = "sweep"

    def __post_init__(self):
        object.__setattr__(self, "times_s", as_float_tuple(self.times_s, "times_s"))
        object.__setattr__(self, "levels", as_float_tuple(self.levels, "levels"))
        if len(self.times_s) != len(self.levels) or np.any(np.diff(self.times_s) <= 0):
            raise ValueError(f"{self.label}: need strictly increasing times_s, one level each")

    def generate(self, n, rate, rng, inputs=None):
        return np.interp(np.arange(n) / rate, self.times_s, self.levels)

    def params(self, rate, units, out):
        return {
            "knots": [{"time_s": t, "level": v} for t, v in zip(self.times_s, self.levels)],
            "formula": "linear between the knots, held before the first and after the last",
            "units": {"time_s": "s", "level": units},
        }
