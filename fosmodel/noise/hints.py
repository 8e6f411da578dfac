"""Hints on a record whose numbers look wrong for what it claims to be, one line each.

Two simple, physical rules, each on a gyro's or an accelerometer's own samples:

- **Units** (:func:`units_hint`): a gyro in deg/s whose angle random walk, read off the Allan
  deviation at :data:`HINT_TAU` (1 s) as ``sigma(tau) * sqrt(tau)``, is below
  :data:`MIN_DEG_ARW` (0.05 deg/sqrt(h), a tactical-grade gyro's; the low-cost MEMS gyros
  fosmodel models read 0.1-10), while the same values in rad/s (57.3 times more) would read
  a MEMS gyro's, from :data:`MIN_DEG_ARW` to :data:`MAX_DEG_ARW` (20 deg/sqrt(h)), is told
  that its values look like rad/s.  At
  1 s a sensor's own low-pass filter has no part in it, and a bias instability only raises it
  (never a false hint).
- **Decimation** (:func:`decimation_hint`): a record under :data:`LOW_RATE_HZ` (10 Hz) with a
  gyro whose first differences have the lag-1 autocorrelation of white noise's (-1/2, within
  :data:`WHITE_TOLERANCE`) and whose angle random walk is over :data:`LARGE_DEG_ARW`
  (4 deg/sqrt(h): the MEMS gyros of the real records read 0.5-2.6) looks subsampled without
  averaging.  Point subsampling leaves the samples uncorrelated and aliases the noise of the
  sensor's whole band into the white noise read at the low rate (1 - 10 Hz over 100 Hz of
  band: 3-5 times the true ARW); averaging keeps the true ARW, but whitens the samples too, so
  whiteness alone tells nothing.  The hint asks to average (or low-pass) before decimating.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from .axes import Axis
from .metrics import to_si_scale

#: The averaging time (s) at which the white noise of the units rule is read.
HINT_TAU = 1.0
#: An angle random walk (deg/sqrt(h)) below which a gyro in deg/s is better than tactical grade,
#: and one above which no MEMS gyro reads.
MIN_DEG_ARW = 0.05
MAX_DEG_ARW = 20.0
#: Fewest averaging blocks for the units rule, fewest samples for the decimation rule.
MIN_BLOCKS = 20
MIN_SAMPLES = 200
#: Under this rate (Hz) an uncorrelated gyro with an angle random walk over
#: :data:`LARGE_DEG_ARW` (deg/sqrt(h)) looks decimated without averaging.
LOW_RATE_HZ = 10.0
LARGE_DEG_ARW = 4.0
#: How near -1/2 the differences' lag-1 autocorrelation is to count as white noise's.
WHITE_TOLERANCE = 0.05


def record_hints(columns: Mapping[str, np.ndarray], axes: Sequence[Axis],
                 rate: float) -> list[str]:
    """Return the hints on a record's axes, one line each: units, then decimation."""
    hints = [h for a in axes if (h := units_hint(columns[a.column], a, rate))]
    decimated = decimation_hint(columns, axes, rate)
    return [*hints, *([decimated] if decimated else [])]


def _arw_deg(x: np.ndarray, units: str, rate: float) -> float | None:
    """Return a gyro's angle random walk in deg/sqrt(h): its Allan deviation at ``HINT_TAU``."""
    m = max(1, round(HINT_TAU * rate))
    blocks = len(x) // m
    if blocks < MIN_BLOCKS:
        return None
    means = np.asarray(x[: blocks * m], dtype=float).reshape(blocks, m).mean(axis=1)
    adev = math.sqrt(float(np.mean(np.diff(means) ** 2)) / 2.0)
    tau = m / rate
    return adev * math.sqrt(tau) * to_si_scale("gyro", units) * 180.0 / math.pi * 60.0


def units_hint(x: np.ndarray, axis: Axis, rate: float) -> str | None:
    """Return a hint that a gyro's values in deg/s look like rad/s, or None.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> rads = rng.normal(0, 1e-3, 60_000)  # 1e-3 rad/s at 100 Hz: 0.34 deg/sqrt(h)
    >>> units_hint(rads, Axis("gx", "gyro", "deg/s", "given"), 100.0)[:46]
    'gx: values look like rad/s, not deg/s: its ARW'
    >>> units_hint(rads * 57.3, Axis("gx", "gyro", "deg/s", "given"), 100.0) is None
    True
    """
    if axis.sensor != "gyro" or axis.units != "deg/s":
        return None
    arw = _arw_deg(x, axis.units, rate)
    if arw is None or not MIN_DEG_ARW <= arw * 180 / math.pi <= MAX_DEG_ARW or arw >= MIN_DEG_ARW:
        return None
    return (f"{axis.column}: values look like rad/s, not deg/s: its ARW {arw:.2g} deg/sqrt(h) "
            f"would be better than a tactical-grade gyro's, {arw * 180 / math.pi:.2g} in rad/s "
            f"a MEMS gyro's; if so, give its units as {axis.column}=rad/s")


def decimation_hint(columns: Mapping[str, np.ndarray], axes: Sequence[Axis],
                    rate: float) -> str | None:
    """Return a hint that a low-rate record was subsampled without averaging, or None.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> fast = rng.normal(0, 0.3, 400_000)  # deg/s at 100 Hz: 1.8 deg/sqrt(h)
    >>> gx = Axis("gx", "gyro", "deg/s", "given")
    >>> decimation_hint({"gx": fast[::25]}, [gx], 4.0)[:38]  # 9 deg/sqrt(h)
    'at 4 Hz the samples are uncorrelated a'
    >>> decimation_hint({"gx": fast.reshape(-1, 25).mean(axis=1)}, [gx], 4.0) is None
    True
    """
    if rate >= LOW_RATE_HZ:
        return None
    found = []
    for a in axes:
        x = np.asarray(columns[a.column], dtype=float)
        if a.sensor != "gyro" or len(x) < MIN_SAMPLES:
            continue
        d = np.diff(x) - np.mean(np.diff(x))
        power = float(d @ d)
        arw = _arw_deg(x, a.units, rate)
        if power == 0 or arw is None or arw <= LARGE_DEG_ARW:
            continue
        lag1 = float(d[1:] @ d[:-1]) / power
        if abs(lag1 + 0.5) <= WHITE_TOLERANCE:
            found.append(f"{a.column} {lag1:.2f}, ARW {arw:.2g} deg/sqrt(h)")
    if not found:
        return None
    return (f"at {rate:.3g} Hz the samples are uncorrelated and their white noise large "
            f"({'; '.join(found)}; white noise's lag-1 autocorrelation of the differences is "
            f"-0.50): if the record was decimated from a faster sensor without averaging, its "
            f"white noise is aliased; average (or low-pass) before decimating")
