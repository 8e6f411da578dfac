"""PX4's thermal calibration procedure, step by step as Tools/process_sensor_caldata.py."""

import numpy as np
import pytest
from scipy.signal import medfilt

from fosmodel.workflows.tempcal_px4 import Px4Fit, px4_fit, resample_with_delta_x


def _script_resample(x, y):
    """PX4's resampleWithDeltaX, line for line (the script's loop over the samples)."""
    x_min, x_max, bins = np.amin(x), np.amax(x), 2000
    interval = (x_max - x_min) / bins
    ys, xs, count = np.zeros(bins), np.zeros(bins), np.zeros(bins)
    for i in range(len(x)):
        if x[i] < x_min:
            k = 0
        elif x[i] < x_max:
            k = int((x[i] - x_min) / interval)
        else:
            k = bins - 1
        ys[k] += y[i]
        xs[k] += x[i]
        count[k] += 1
    full = np.where(count != 0)
    return xs[full] / count[full], ys[full] / count[full]


def test_the_bins_are_the_script_s():
    rng = np.random.default_rng(0)
    x = np.round(rng.uniform(-20, 20, 5000), 2)  # quantized: bins shared, some empty
    y = rng.standard_normal(5000)
    for ours, theirs in zip(resample_with_delta_x(x, y), _script_resample(x, y)):
        np.testing.assert_allclose(ours, theirs, rtol=1e-12)


@pytest.mark.parametrize("accel", [False, True])
def test_the_fit_takes_the_script_s_steps(accel):
    rng = np.random.default_rng(1)
    temp = np.linspace(5, 45, 4000) + 0.05 * rng.standard_normal(4000)
    values = 0.01 * (temp - 20) + 2e-4 * (temp - 20) ** 2 + 0.02 * rng.standard_normal(4000)
    fit = px4_fit([temp], [values], accel)
    tref = 0.5 * (temp.min() + temp.max())
    smooth = medfilt(values, 31)
    if accel:
        smooth = smooth - np.median(smooth)
    expected = np.polyfit(*_script_resample(temp - tref, smooth), 3)
    np.testing.assert_allclose(fit.coefficients, expected[::-1], rtol=1e-9, atol=1e-12)
    assert (fit.tmin, fit.tmax, fit.tref) == (temp.min(), temp.max(), tref)


def test_several_sessions_are_filtered_each_and_fitted_together():
    rng = np.random.default_rng(2)
    temps = [np.linspace(0, 30, 3000), np.linspace(10, 40, 2000)]
    values = [0.02 * t + c + 0.01 * rng.standard_normal(len(t)) for t, c in zip(temps, (1, 3))]
    fit = px4_fit(temps, values, accel=True)
    tref = 20.0
    pieces = [medfilt(v, 31) for v in values]
    pieces = [p - np.median(p) for p in pieces]
    expected = np.polyfit(*_script_resample(np.concatenate(temps) - tref,
                                            np.concatenate(pieces)), 3)
    np.testing.assert_allclose(fit.coefficients, expected[::-1], rtol=1e-9, atol=1e-12)


def test_the_offset_is_clipped_to_the_range_as_the_firmware_clips_it():
    fit = Px4Fit((1.0, 0.5, 0.1, 0.01), tref=20.0, tmin=10.0, tmax=40.0)
    d = np.array([-10.0, 5.0, 20.0])  # 0 C (clipped to 10), 25 C, 60 C (clipped to 40)
    expected = 1 + 0.5 * d + 0.1 * d**2 + 0.01 * d**3
    np.testing.assert_allclose(fit.offset([0.0, 25.0, 60.0]), expected)
