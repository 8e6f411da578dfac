"""Local-level candidates: the exponentially weighted mean of the output's own past.

A MEMS bias wanders (bias instability, rate random walk).  A stationary model
centred on its training mean reverts to that mean in every outage, and a
deterministic function of time fitted on one stretch runs on into the next.
The *local level* follows the wander instead::

    level@<tau>s[n] = (1 - a) level[n-1] + a y[n-1],    a = 1 / (tau * rate),

a causal filter of the past of ``y`` (never of ``y[n]`` itself), started as
if ``y`` had stayed at ``y[0]`` before the record (``level[0] = level[1] =
y[0]``).  In a free run it is fed the model's own predictions, never the true
signal.  For a random-walk bias in white noise this is the optimal predictor
(the local-level model, whose steady-state Kalman filter is exactly this
exponential smoother; Harvey 1989, sec. 2.3), so a fitted weight on it also
exports as one extra state of a shaping filter.

A level is a *factor* ``("level@20s", 0)`` of a candidate term, named
``level@20s``; it is computed from the centred output, like the lagged outputs.

References
----------
A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman
Filter*, Cambridge University Press, 1989.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import numpy as np
from scipy.signal import lfilter

from .exceptions import InputError
from .validation import float_array

PREFIX = "level@"
_NAME_RE = re.compile(r"^level@(?P<tau>[0-9][0-9.]*(?:e[+-]?[0-9]+)?)s$")


def level_name(tau_s: float) -> str:
    """``level@20s``: the channel name of the level with time constant ``tau_s`` seconds."""
    return f"{PREFIX}{float(tau_s):.4g}s"


def level_tau(name: str) -> float | None:
    """Return the time constant in seconds of a level name, or None if ``name`` is not one."""
    m = _NAME_RE.match(name)
    return float(m.group("tau")) if m else None


def checked_level_tau(name: str) -> float:
    """Return the time constant in seconds of the level ``name``.

    Raises
    ------
    InputError
        ``name`` is not the name of a level.
    """
    tau = level_tau(name)
    if tau is None:
        raise InputError(f"{name!r} is not the name of a level (level@<seconds>s)")
    return tau


def is_level(channel: str) -> bool:
    """Whether ``channel`` names a local level of the output."""
    return channel.startswith(PREFIX)


def check_level_rate(taus: Sequence[float], rate: float | None) -> float | None:
    """Return the sample rate levels with time constants ``taus`` (seconds) are computed at.

    Raises
    ------
    InputError
        Levels without a finite positive rate, or a level shorter than one sample.
    """
    if not taus:
        return None if rate is None else float(rate)
    if isinstance(rate, bool) or not isinstance(rate, (int, float, np.integer, np.floating)) \
            or not math.isfinite(rate) or rate <= 0:
        raise InputError(f"level candidates need the sample rate in Hz (rate=...), got {rate!r}")
    short = [t for t in taus if t * rate < 1.0]
    if short:
        raise InputError(f"{level_name(short[0])} is shorter than one sample at {rate:g} Hz")
    return float(rate)


def level_gain(tau_s: float, rate: float) -> float:
    """Return ``a = 1 / (tau * rate)``, the weight of the newest sample."""
    return 1.0 / (tau_s * rate)


def level_series(y: np.ndarray, tau_s: float, rate: float) -> np.ndarray:
    """``level[n]`` for ``n = 0 .. N-1`` (each from ``y[0] .. y[n-1]``), started at ``y[0]``.

    The few most recent series are kept (read-only; at most :data:`_KEEP` of them
    and :data:`_KEEP_SAMPLES` samples in all), keyed by the array, its length,
    two sums of its values, ``tau_s`` and ``rate``: a study predicts and
    free-runs the same record with many models, and the recursion over millions
    of samples costs more than the sums that recognise it.
    """
    y = float_array(y)
    key = (id(y), len(y), float(y.sum()), float(y[::97].sum()), float(tau_s), float(rate))
    for i, (k, ref, series) in enumerate(_RECENT):
        if k == key and ref is y:
            _RECENT.insert(0, _RECENT.pop(i))
            return series
    series = smooth(y, level_gain(tau_s, rate))
    series.flags.writeable = False
    _RECENT.insert(0, (key, y, series))
    held = np.cumsum([len(kept) for _, _, kept in _RECENT])
    del _RECENT[min(_KEEP, int(np.searchsorted(held, _KEEP_SAMPLES, side="right"))):]
    return series


_KEEP = 8
#: 1 GiB of series (and the records they hold alive): four levels of a day at 200 Hz, which a
#: study's FOS model with levels reads in every prediction and free run of that day.
_KEEP_SAMPLES = 2**27
_RECENT: list[tuple[tuple, np.ndarray, np.ndarray]] = []


def level_after(y: np.ndarray, tau_s: float, rate: float) -> float:
    """Return the level at sample ``N``, just after ``y`` ends: what a free run starts from."""
    return smooth_after(y, level_gain(tau_s, rate))


def smooth(y: np.ndarray, gain: float) -> np.ndarray:
    """``s[0] = y[0]``, ``s[n] = (1 - gain) s[n-1] + gain y[n-1]``, for ``n < N``."""
    y = np.asarray(y, dtype=float)
    out = np.empty(len(y))
    if len(y):
        out[0] = y[0]
    if len(y) > 1:  # out[k+1] = (1 - gain) out[k] + gain y[k], from out[0] = y[0]
        out[1:] = lfilter([gain], [1.0, gain - 1.0], y[:-1], zi=[(1.0 - gain) * y[0]])[0]
    return out


def smooth_after(y: np.ndarray, gain: float) -> float:
    """Return the next value of :func:`smooth` after the last sample of ``y``."""
    y = np.asarray(y, dtype=float)
    if len(y) == 0:
        raise InputError("a level needs at least one past sample")
    return float((1.0 - gain) * smooth(y, gain)[-1] + gain * y[-1])


def check_level_series(values: np.ndarray, y: np.ndarray, tau_s: float, rate: float,
                       name: str) -> np.ndarray:
    """Return ``values`` as a float array if it is ``level_series(y, tau_s, rate)``.

    It is checked at its start and at 16 points (to rounding): a cheap guard against the
    series of another record or time constant.

    Raises
    ------
    InputError
        Another length, or a value off the recursion.
    """
    values = np.asarray(values, dtype=float)
    if values.shape != y.shape:
        raise InputError(f"{name} has {values.size} samples, the output has {y.size}")
    a = level_gain(tau_s, rate)
    k = np.unique(np.linspace(0, len(y) - 2, 16).astype(int)) if len(y) > 1 else np.zeros(0, int)
    expected = np.r_[y[:1], (1.0 - a) * values[k] + a * y[k]]
    got = np.r_[values[:1], values[k + 1]]
    scale = 1e-9 * (np.abs(np.r_[expected, got]).max(initial=0.0) + 1e-300)
    if not np.all(np.abs(got - expected) <= scale):
        raise InputError(f"{name} given with the record is not the level of this output "
                         f"(time constant {tau_s:g} s at {rate:g} Hz)")
    return values


def level_grid(n_samples: int, rate: float, tau_floor_s: float | None = None,
               count: int = 4) -> tuple[float, ...]:
    """Time constants to offer as level candidates, chosen from the record.

    For a rate random walk in white noise (Allan deviation ``N/sqrt(tau)`` and
    ``K sqrt(tau/3)``) the optimal smoother's time constant is ``N/K``, i.e.
    ``tau_min / sqrt(3)`` with ``tau_min`` where the Allan deviation has its
    floor; bias instability (flicker) wants a shorter one.  The grid spans
    ``tau_min / 30 .. tau_min / sqrt(3)`` geometrically (``count`` values),
    kept between 10 samples and a twentieth of the record.  Without a floor
    (``tau_floor_s`` None: the deviation falls all the way) it spans up to a
    twentieth of the record.

    Returns
    -------
    tuple of float
        Increasing time constants in seconds, rounded as their names show them.
    """
    longest = n_samples / rate / 20.0
    shortest = 10.0 / rate
    if longest <= shortest:
        return ()
    top = longest if tau_floor_s is None else min(longest, tau_floor_s / math.sqrt(3.0))
    top = max(top, shortest)
    bottom = max(shortest, top / (30.0 / math.sqrt(3.0)))
    taus = np.geomspace(bottom, top, count) if top > bottom else np.array([top])
    return tuple(dict.fromkeys(checked_level_tau(level_name(t)) for t in taus))


def levels_for(y: np.ndarray, rate: float, count: int = 4) -> tuple[float, ...]:
    """Return :func:`level_grid` for a record.

    The grid takes the record's length and the floor of its overlapping Allan deviation
    (allantools), at the shortest ``tau`` where it stops falling.
    """
    import allantools  # only here: the grid of a record needs it, the levels do not

    n = len(y)
    m = np.unique(np.geomspace(1, max(1, n // 10), 30).astype(int))
    taus, adev = allantools.oadev(np.asarray(y, dtype=float), rate=rate, data_type="freq",
                                  taus=(m + 0.1) / rate)[:2]  # m back, truncated or rounded
    k = int(np.argmin(adev))
    floor = float(taus[k]) if k < len(taus) - 1 else None  # still falling: no floor seen
    return level_grid(n, rate, floor, count)


def with_levels(signals: dict[str, np.ndarray], names: Sequence[str], rate: float,
                output: str) -> dict[str, np.ndarray]:
    """``signals`` plus the level series ``names`` of its ``output`` channel."""
    y = signals[output]
    return {**signals, **{name: level_series(y, checked_level_tau(name), rate)
                          for name in names}}
