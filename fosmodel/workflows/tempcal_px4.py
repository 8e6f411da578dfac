"""PX4's thermal calibration procedure, step by step as its own script takes them.

``Tools/process_sensor_caldata.py`` fits, from one ULog of a cold-soaked board warming up
at rest, a cubic in temperature to every gyro and accelerometer axis:

1. ``TMIN`` and ``TMAX`` are the lowest and highest temperature of the log, ``TREF`` their
   mean (the middle of the range), and the fit's variable is ``T - TREF``;
2. each axis is median filtered over 31 samples (``scipy.signal.medfilt``, which pads the
   ends with zeros);
3. an accelerometer axis loses its median (gravity and the offset at rest), a gyro nothing;
4. the points are averaged in 2,000 equal bins of temperature (``resampleWithDeltaX``:
   the mean temperature and the mean value of each bin that holds a point);
5. ``numpy.polyfit`` of degree 3 through the bins' means gives ``X3, X2, X1, X0``.

The firmware then subtracts ``X0 + X1 d + X2 d^2 + X3 d^3``, ``d`` the temperature clipped to
``[TMIN, TMAX]`` less ``TREF`` (:func:`calc_thermal_offsets_3D`).  Several sessions are taken
as the script takes its one log: steps 2 and 3 per session (each log on its own), and one fit
through the bins of every session's points (:func:`px4_fit`).

References
----------
PX4-Autopilot, ``Tools/process_sensor_caldata.py``: ``resampleWithDeltaX``, ``median_filter``
and the ``sensor_gyro``/``sensor_accel`` fits.
PX4-Autopilot, ``src/modules/temperature_compensation/TemperatureCompensation.cpp``:
``TemperatureCompensation::calc_thermal_offsets_3D``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import medfilt

#: The script's median filter (samples), temperature bins and polynomial degree.
MEDIAN_SAMPLES, BINS, DEGREE = 31, 2000, 3


@dataclass(frozen=True)
class Px4Fit:
    """PX4's cubic of one axis: ``X0..X3`` about ``tref``, valid over ``[tmin, tmax]``."""

    coefficients: tuple[float, ...]
    tref: float
    tmin: float
    tmax: float

    def offset(self, temperature: ArrayLike) -> np.ndarray:
        """Return the offset the firmware subtracts at ``temperature`` (clipped to the range)."""
        d = np.clip(np.asarray(temperature, dtype=float), self.tmin, self.tmax) - self.tref
        return np.polynomial.polynomial.polyval(d, self.coefficients)


def resample_with_delta_x(x: ArrayLike, y: ArrayLike, bins: int = BINS
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Return the mean ``x`` and ``y`` of each non-empty bin of ``bins`` equal bins of ``x``.

    As the script's ``resampleWithDeltaX``: bin ``int((x - min) / width)``, the maximum in
    the last bin.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    low, high = float(x.min()), float(x.max())
    width = (high - low) / bins
    index = np.full(len(x), bins - 1)
    inside = x < high
    index[inside] = ((x[inside] - low) / width).astype(int) if width > 0 else 0
    count = np.bincount(index, minlength=bins)
    full = count > 0
    return ((np.bincount(index, x, bins)[full] / count[full]),
            (np.bincount(index, y, bins)[full] / count[full]))


def px4_fit(temperatures: Sequence[ArrayLike], values: Sequence[ArrayLike],
            accel: bool) -> Px4Fit:
    """Fit one axis as PX4's script does, over one or several sessions (module docstring).

    Parameters
    ----------
    temperatures, values : sequences of array_like
        Each session's temperature (degC) and the axis's readings, sample for sample.
    accel : bool
        An accelerometer axis: each session's median is taken off first.
    """
    temps = [np.asarray(t, dtype=float) for t in temperatures]
    all_t = np.concatenate(temps)
    tmin, tmax = float(all_t.min()), float(all_t.max())
    tref = 0.5 * (tmin + tmax)
    filtered = []
    for v in values:
        v = medfilt(np.asarray(v, dtype=float), MEDIAN_SAMPLES)
        filtered.append(v - np.median(v) if accel else v)
    x, y = resample_with_delta_x(all_t - tref, np.concatenate(filtered))
    coefficients = np.polyfit(x, y, DEGREE)[::-1]
    return Px4Fit(tuple(float(c) for c in coefficients), tref, tmin, tmax)
