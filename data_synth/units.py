"""Unit conversions between datasheet noise coefficients and per-sample values.

Every stochastic source works with a *density*: the one-sided noise level of
the white process behind it, in ``[channel unit]/sqrt(Hz)`` (the same number
as ``[channel unit]*sqrt(s)``).  A datasheet gives it as

* angle random walk (ARW) of a gyro in deg/sqrt(h) or deg/sqrt(s),
* velocity random walk (VRW) of an accelerometer in m/s/sqrt(h),
* rate random walk (RRW) in deg/sqrt(s^3) = (deg/s)/sqrt(s).

The conversions are exact:

* ``sqrt(h) = 60 sqrt(s)``, so an ARW of ``N`` deg/sqrt(h) is ``N/60``
  (deg/s)/sqrt(Hz), or ``N/60*3600 = 60 N`` (deg/h)/sqrt(Hz);
* a white density ``d`` sampled at ``rate`` Hz has the per-sample standard
  deviation ``d*sqrt(rate)`` (Koldbæk and Totu 2011, eq. 4.10: ``sigma = N/sqrt(Ts)``);
* a random walk of density ``K`` has per-sample increments of standard
  deviation ``K/sqrt(rate)``.

The Allan deviations these levels produce (IEEE Std 952 conventions) are given
by :func:`adev_white`, :func:`adev_random_walk` and :func:`adev_flicker_floor`.
"""

from __future__ import annotations

import math

import numpy as np

#: Standard gravity in m/s^2.
STANDARD_GRAVITY = 9.80665

#: Angular-rate units a gyro channel may use, with their size in deg/s.
RATE_UNITS: dict[str, float] = {"deg/s": 1.0, "deg/h": 1.0 / 3600.0}

#: Specific-force unit of accelerometer channels.
ACCEL_UNIT = "m/s^2"

#: Seconds in a sqrt(hour)**2, i.e. sqrt(h) = SQRT_HOUR_S sqrt(s).
SQRT_HOUR_S = 60.0


def rate_factor(units: str) -> float:
    """Number of ``units`` in one deg/s (1 for deg/s, 3600 for deg/h).

    Raises
    ------
    ValueError
        If ``units`` is not an angular-rate unit of :data:`RATE_UNITS`.
    """
    if units not in RATE_UNITS:
        raise ValueError(f"not an angular-rate unit: {units!r} (use one of {sorted(RATE_UNITS)})")
    return 1.0 / RATE_UNITS[units]


def arw_to_density(arw: float, units: str = "deg/s", *, per: str = "sqrt(h)") -> float:
    """White rate-noise density of a gyro from its angle random walk.

    Parameters
    ----------
    arw : float
        Angle random walk in deg/sqrt(h) (``per="sqrt(h)"``, datasheets, seed
        001 Table 1) or deg/sqrt(s) (``per="sqrt(s)"``, Koldbæk and Totu 2011, Table 5.1).
    units : {"deg/s", "deg/h"}
        Unit of the gyro channel.
    per : {"sqrt(h)", "sqrt(s)"}
        Time unit under the square root of ``arw``.

    Returns
    -------
    float
        Density in ``units``/sqrt(Hz): ``arw/60`` deg/s/sqrt(Hz) for an ARW in
        deg/sqrt(h), times 3600 for deg/h.
    """
    deg_per_sqrt_s = _per_sqrt_s(arw, per)
    return deg_per_sqrt_s * rate_factor(units)


def density_to_arw(density: float, units: str = "deg/s") -> float:
    """Angle random walk in deg/sqrt(h) of a white density in ``units``/sqrt(Hz)."""
    return density / rate_factor(units) * SQRT_HOUR_S


def vrw_to_density(vrw: float) -> float:
    """White specific-force density (m/s^2)/sqrt(Hz) from a VRW in m/s/sqrt(h).

    ``1 m/s/sqrt(h) = 1/60 m/s/sqrt(s) = 1/60 (m/s^2)/sqrt(Hz)``.
    """
    return vrw / SQRT_HOUR_S


def density_to_vrw(density: float) -> float:
    """Velocity random walk in m/s/sqrt(h) of a density in (m/s^2)/sqrt(Hz)."""
    return density * SQRT_HOUR_S


def rrw_to_density(rrw: float, units: str = "deg/s", *, per: str = "sqrt(s^3)") -> float:
    """Random-walk density of a gyro bias from its rate random walk.

    Parameters
    ----------
    rrw : float
        Rate random walk in deg/sqrt(s^3) (``per="sqrt(s^3)"``, Koldbæk and Totu (2011)) or in
        deg/h/sqrt(h) (``per="h/sqrt(h)"``).
    units : {"deg/s", "deg/h"}
        Unit of the gyro channel.

    Returns
    -------
    float
        Density ``K`` in ``units``/sqrt(s): the bias increment over one sample
        has the standard deviation ``K/sqrt(rate)``.
    """
    if per == "sqrt(s^3)":
        deg_s_per_sqrt_s = rrw
    elif per == "h/sqrt(h)":
        deg_s_per_sqrt_s = rrw / 3600.0 / SQRT_HOUR_S
    else:
        raise ValueError(f"per must be 'sqrt(s^3)' or 'h/sqrt(h)', not {per!r}")
    return deg_s_per_sqrt_s * rate_factor(units)


def white_sigma(density: float, rate: float) -> float:
    """Per-sample standard deviation ``density*sqrt(rate)`` of white noise."""
    return density * math.sqrt(rate)


def random_walk_step(density: float, rate: float) -> float:
    """Per-sample increment standard deviation ``density/sqrt(rate)`` of a random walk."""
    return density / math.sqrt(rate)


def mg_to_mps2(value_mg: float) -> float:
    """Convert milli-g to m/s^2 with standard gravity."""
    return value_mg * 1e-3 * STANDARD_GRAVITY


def adev_white(density: float, tau: np.ndarray | float) -> np.ndarray | float:
    """Allan deviation ``N/sqrt(tau)`` of white rate noise of density ``N``."""
    return density / np.sqrt(tau)


def adev_random_walk(density: float, tau: np.ndarray | float) -> np.ndarray | float:
    """Allan deviation ``K*sqrt(tau/3)`` of a rate random walk of density ``K``."""
    return density * np.sqrt(np.asarray(tau) / 3.0)


def adev_flicker_floor(bias_instability: float) -> float:
    """Flat Allan deviation ``sqrt(2 ln 2/pi) B ~ 0.664 B`` of flicker noise ``B``."""
    return math.sqrt(2.0 * math.log(2.0) / math.pi) * bias_instability


def _per_sqrt_s(value: float, per: str) -> float:
    if per == "sqrt(h)":
        return value / SQRT_HOUR_S
    if per == "sqrt(s)":
        return value
    raise ValueError(f"per must be 'sqrt(h)' or 'sqrt(s)', not {per!r}")
