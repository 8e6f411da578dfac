"""Columns derived from time and the record's channels, rebuilt from their names.

The residual loop adds user columns to a model (sinusoids, a trend, a step, the
square of a channel).  Their names say how to compute them, so a saved model
can be applied to a record again (``fosmodel predict``) without the arrays:

=====================  ===============================================================
name                   value at sample ``n`` (``t = n / rate`` from the record's start)
=====================  ===============================================================
``cos@<f>Hz``          ``cos(2 pi f t)``
``sin@<f>Hz``          ``sin(2 pi f t)``
``t@s``                ``t``
``exp(-t/<tau>s)``     ``exp(-t / tau)``
``step@<t0>s``         1 from ``t0`` on, 0 before
``sq(<channel>)``      ``(x - mu_x)^2``, ``mu_x`` the channel's training mean
``<channel>_fast<T>s``  ``x[n]`` minus its local level over ``T`` s (the exponentially
                       weighted mean of ``x[n-1], x[n-2], ...``, :mod:`fosmodel.core.levels`):
                       the channel's fast part, an input channel with lags of its own
=====================  ===============================================================

Time functions restart at the first sample of the record they are computed
for: a trend or a step fitted on one recording is a statement about time since
*its* start.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping

import numpy as np

from .exceptions import InputError
from .levels import level_series

_NUMBER = r"([0-9][0-9.]*(?:e[+-]?[0-9]+)?)"
_PATTERNS = {
    "cos": re.compile(rf"^cos@{_NUMBER}Hz$"),
    "sin": re.compile(rf"^sin@{_NUMBER}Hz$"),
    "time": re.compile(r"^t@s$"),
    "exp": re.compile(rf"^exp\(-t/{_NUMBER}s\)$"),
    "step": re.compile(rf"^step@{_NUMBER}s$"),
    "square": re.compile(r"^sq\(([A-Za-z_][A-Za-z0-9_]*)\)$"),
    "fast": re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)_fast([0-9]+)s$"),
}


def _match(name: str) -> tuple[str, ...] | None:
    for kind, pattern in _PATTERNS.items():
        m = pattern.match(name)
        if m:
            return (kind, *m.groups())
    return None


def is_derived(name: str) -> bool:
    """Whether a column name says how to compute the column."""
    return _match(name) is not None


# Frequencies and step times keep 8 significant digits: a line's phase must hold over
# hours (1e-8 relative of 7 Hz is 0.02 rad after 10 h) and a step must land on its sample.


def cosine_name(freq_hz: float) -> str:
    """``cos@7Hz``: the name of the cosine of frequency ``freq_hz`` over the record's time."""
    return f"cos@{freq_hz:.8g}Hz"


def sine_name(freq_hz: float) -> str:
    """``sin@7Hz``: the name of the sine of frequency ``freq_hz`` over the record's time."""
    return f"sin@{freq_hz:.8g}Hz"


TIME_NAME = "t@s"


def exp_name(tau_s: float) -> str:
    """``exp(-t/600s)``: the name of the decay with time constant ``tau_s`` seconds."""
    return f"exp(-t/{tau_s:.6g}s)"


def step_name(time_s: float) -> str:
    """``step@120s``: the name of the unit step at ``time_s`` seconds into the record."""
    return f"step@{time_s:.8g}s"


def square_name(channel: str) -> str:
    """``sq(temp)``: the name of the square of the centred ``channel``."""
    return f"sq({channel})"


def fast_name(channel: str, tau_s: float) -> str:
    """``ay_g_fast20s``: the channel minus its local level over ``tau_s`` (whole seconds)."""
    return f"{channel}_fast{round(tau_s)}s"


def channels_read(names: Iterable[str]) -> list[str]:
    """Return the record channels that derived columns among ``names`` read."""
    out = []
    for name in names:
        found = _match(name)
        if found and found[0] in ("square", "fast") and found[1] not in out:
            out.append(found[1])
    return out


def derive(name: str, n: int, rate: float, channels: Mapping[str, np.ndarray],
           offsets: Mapping[str, float]) -> np.ndarray:
    """Compute the column ``name`` over ``n`` samples at ``rate`` Hz.

    Parameters
    ----------
    channels : mapping of str to ndarray
        The record's channels (for ``sq(<channel>)``).
    offsets : mapping of str to float
        Training means of the channels (for ``sq(<channel>)``).

    Raises
    ------
    InputError
        Not a derived name, or a square of a channel without its values or mean.
    """
    found = _match(name)
    if found is None:
        raise InputError(f"column {name!r} is not one fosmodel can derive; pass its values")
    kind, arg = found[0], (found[1] if len(found) > 1 else "")
    if kind == "fast":
        if arg not in channels:
            raise InputError(f"channel {name!r} needs the channel {arg!r}")
        x = np.asarray(channels[arg], dtype=float)[:n]
        return x - level_series(x, float(found[2]), rate)
    t = np.arange(n) / rate
    if kind == "cos":
        return np.cos(2 * np.pi * float(arg) * t)
    if kind == "sin":
        return np.sin(2 * np.pi * float(arg) * t)
    if kind == "time":
        return t
    if kind == "exp":
        return np.exp(-t / float(arg))
    if kind == "step":
        return (t >= float(arg)).astype(float)
    if arg not in channels or arg not in offsets:
        raise InputError(f"column {name!r} needs the channel {arg!r} and its training mean")
    return (np.asarray(channels[arg], dtype=float)[:n] - offsets[arg]) ** 2
