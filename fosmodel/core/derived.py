"""Columns derived from time and the record's channels, rebuilt from their names.

The residual loop adds user columns to a model (sinusoids, a trend, a step, the
forms of a driver).  Their names say how to compute them, so a saved model can
be applied to a record again (``fosmodel predict``) without the arrays:

=========================  ===========================================================
name                       value at sample ``n`` (``t = n / rate`` from the record's start)
=========================  ===========================================================
``cos@<f>Hz``              ``cos(2 pi f t)``
``sin@<f>Hz``              ``sin(2 pi f t)``
``t@s``                    ``t``
``exp(-t/<tau>s)``         ``exp(-t / tau)``
``step@<t0>s``             1 from ``t0`` on, 0 before
``sq(<ch>)``               ``(x - mu_x)^2``, ``mu_x`` the channel's training mean
``<ch>_fast<T>s``          ``x[n]`` minus its local level over ``T`` s (the exponentially
                           weighted mean of ``x[n-1], x[n-2], ...``, :mod:`fosmodel.core.levels`,
                           started at the mean of the channel's first ``T`` s): the channel's
                           fast part, an input channel with lags of its own
``lowpass(<ch>,<T>s)``     the channel through a first-order lag of time constant ``T``:
                           ``s[n] = s[n-1] + (x[n] - s[n-1]) / (T rate)``, ``s[0] = x[0]``
                           (a sensor that follows its driver late, as a die follows the air)
``rate(<ch>,<T>s)``        the rate of change of ``lowpass(<ch>,<T>s)`` per second,
                           ``(s[n] - s[n-1]) rate`` (0 at ``n = 0``): a smoothed derivative
``pow(<x>,<p>,<c>)``       ``(x - c)^p`` of ``x`` a channel or a ``lowpass(...)`` of one
``u__<spelled>``           the channel a spelled-out token names, as it is: an input channel
                           whose header is not an identifier (``Accel X (g)``)
=========================  ===========================================================

``<ch>`` is a channel *token* (:func:`channel_token`): the column's own name when it
is an identifier (``temp_c``), else an identifier spelling it out (``Accel X (g)``
becomes ``u__Accel_20_X_20__28_g_29_``), so that any header survives in a term's
name, where spaces, ``*``, ``^`` and brackets have a meaning of their own.

Time functions restart at the first sample of the record they are computed
for: a trend or a step fitted on one recording is a statement about time since
*its* start.  :func:`derive` takes ``start``, the index of the first sample it computes
in that record, so that a later stretch of it (the second half a filter runs on) gets
the time of the fitting record: ``t = (start + n) / rate``.  The columns that read a
channel start their memory (a lag's, a local level's) at the first sample they are
given.  :func:`describe` gives a column's definition and unit in words.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import NamedTuple

import numpy as np
from scipy.signal import lfilter

from .exceptions import InputError
from .levels import level_series

_NUMBER = r"([0-9][0-9.]*(?:e[+-]?[0-9]+)?)"
_SIGNED = r"(-?[0-9][0-9.]*(?:e[+-]?[0-9]+)?)"
_TOKEN = r"([A-Za-z_][A-Za-z0-9_]*)"
_PATTERNS = {
    "cos": re.compile(rf"^cos@{_NUMBER}Hz$"),
    "sin": re.compile(rf"^sin@{_NUMBER}Hz$"),
    "time": re.compile(r"^t@s$"),
    "exp": re.compile(rf"^exp\(-t/{_NUMBER}s\)$"),
    "step": re.compile(rf"^step@{_NUMBER}s$"),
    "square": re.compile(rf"^sq\({_TOKEN}\)$"),
    "fast": re.compile(rf"^{_TOKEN}_fast([0-9]+)s$"),
    "lowpass": re.compile(rf"^lowpass\({_TOKEN},{_NUMBER}s\)$"),
    "rate": re.compile(rf"^rate\({_TOKEN},{_NUMBER}s\)$"),
    "power": re.compile(rf"^pow\((.+),([0-9]+),{_SIGNED}\)$"),
    # last: a spelled-out token is the channel itself, so that a header that is not an
    # identifier can be an input channel with lags (``ch[n-k]`` needs an identifier)
    "channel": re.compile(r"^(u__[A-Za-z0-9_]*)$"),
}
#: Kinds whose first argument is a channel token.
_READS = ("square", "fast", "lowpass", "rate")
_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
#: The start of a token that spells out a name which is not a plain identifier.
_SPELLED = "u__"


def channel_token(name: str) -> str:
    """Return an identifier that names the channel ``name`` in derived names and terms.

    An identifier without ``__`` is its own token; any other name (spaces, brackets,
    parentheses, a leading digit, a double underscore) is spelled out after ``u__``: letters
    and digits as they are, every other character as ``_<hex code>_``.

    Examples
    --------
    >>> channel_token("temp_c"), channel_token("Accel X (g)")
    ('temp_c', 'u__Accel_20_X_20__28_g_29_')
    """
    if _IDENTIFIER.match(name) and "__" not in name:
        return name
    return _SPELLED + "".join(c if c.isascii() and c.isalnum() else f"_{ord(c):x}_"
                              for c in name)


def token_channel(token: str) -> str:
    """Return the channel name a :func:`channel_token` stands for.

    Raises
    ------
    InputError
        A spelled-out token that does not decode.
    """
    if not token.startswith(_SPELLED):
        return token
    out, body, i = [], token[len(_SPELLED):], 0
    while i < len(body):
        if body[i] != "_":
            out.append(body[i])
            i += 1
            continue
        end = body.find("_", i + 1)
        try:
            out.append(chr(int(body[i + 1 : end], 16)))
        except ValueError:
            raise InputError(f"{token!r} is not a channel token (a bad escape at {i})") from None
        i = end + 1
    return "".join(out)


def parse(name: str) -> tuple[str, ...] | None:
    """Return ``(kind, arguments...)`` of a derived name as written, or None.

    Examples
    --------
    >>> parse("lowpass(temp_c,600s)"), parse("pow(temp_c,2,25)")
    (('lowpass', 'temp_c', '600'), ('power', 'temp_c', '2', '25'))
    """
    for kind, pattern in _PATTERNS.items():
        m = pattern.match(name)
        if m:
            return (kind, *m.groups())
    return None


def _power_base(text: str) -> tuple[str, str] | None:
    """``("channel", token)`` or ``("lowpass", name)``: what a power's base reads, or None."""
    if _IDENTIFIER.match(text):
        return "channel", text
    found = parse(text)
    return ("lowpass", text) if found and found[0] == "lowpass" else None


def is_derived(name: str) -> bool:
    """Whether a column name says how to compute the column."""
    found = parse(name)
    return found is not None and (found[0] != "power" or _power_base(found[1]) is not None)


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
    return f"sq({channel_token(channel)})"


def fast_name(channel: str, tau_s: float) -> str:
    """``ay_g_fast20s``: the channel minus its local level over ``tau_s`` (whole seconds)."""
    return f"{channel_token(channel)}_fast{round(tau_s)}s"


def lowpass_name(channel: str, tau_s: float) -> str:
    """``lowpass(temp_c,600s)``: ``channel`` through a first-order lag of ``tau_s`` seconds."""
    return f"lowpass({channel_token(channel)},{tau_s:.6g}s)"


def rate_name(channel: str, tau_s: float) -> str:
    """``rate(temp_c,60s)``: the rate of change per second of ``lowpass(channel, tau_s)``."""
    return f"rate({channel_token(channel)},{tau_s:.6g}s)"


def power_name(channel: str, power: int, centre: float, tau_s: float | None = None) -> str:
    """``pow(temp_c,2,25)``: ``(x - centre)^power`` of the channel, or of its lag over ``tau_s``."""
    base = channel_token(channel) if tau_s is None else lowpass_name(channel, tau_s)
    return f"pow({base},{int(power)},{centre:.8g})"


def channels_read(names: Iterable[str]) -> list[str]:
    """Return the record channels that derived columns among ``names`` read."""
    out = []
    for name in names:
        found = parse(name)
        if found is None:
            continue
        if found[0] == "power":
            base = _power_base(found[1])
            found = None if base is None else (parse(base[1]) if base[0] == "lowpass"
                                               else ("channel", base[1]))
        if found and (found[0] in _READS or found[0] == "channel"):
            channel = token_channel(found[1])
            if channel not in out:
                out.append(channel)
    return out


def first_order_lag(x: np.ndarray, tau_s: float, rate: float) -> np.ndarray:
    """``s[n] = s[n-1] + a (x[n] - s[n-1])``, ``a = 1 / (tau_s rate)``, from ``s[0] = x[0]``.

    Raises
    ------
    InputError
        A time constant shorter than one sample.
    """
    x = np.asarray(x, dtype=float)
    a = 1.0 / (tau_s * rate)
    if not 0 < a <= 1:
        raise InputError(f"a first-order lag of {tau_s:g} s is shorter than one sample at "
                         f"{rate:g} Hz")
    if not len(x):
        return x.copy()
    return lfilter([a], [1.0, a - 1.0], x, zi=[(1.0 - a) * x[0]])[0]


def derive(name: str, n: int, rate: float, channels: Mapping[str, np.ndarray],
           offsets: Mapping[str, float], start: int = 0) -> np.ndarray:
    """Compute the column ``name`` over ``n`` samples at ``rate`` Hz.

    Parameters
    ----------
    name : str
        A derived column's name (the module's table).
    n : int
        Samples to compute.
    rate : float
        Sample rate in Hz.
    channels : mapping of str to ndarray
        The record's channels by their names (for the columns that read one), from the first
        sample computed on.
    offsets : mapping of str to float
        Training means of the channels (for ``sq(<channel>)``).
    start : int
        Index of the first sample computed in the record whose first sample is time zero:
        the functions of time are those of ``t = (start + k) / rate``.  Columns that read a
        channel do not depend on it.

    Returns
    -------
    ndarray of shape (n,)

    Raises
    ------
    InputError
        Not a derived name, or a column that reads a channel not given (or, for a square,
        without its mean).
    """
    found = parse(name)
    if found is None or not is_derived(name):
        raise InputError(f"column {name!r} is not one fosmodel can derive; pass its values")
    kind = found[0]
    if kind == "power":
        base, p, centre = found[1], int(found[2]), float(found[3])
        kind_of_base, text = _power_base(base) or ("", "")
        x = (_channel(name, text, n, channels) if kind_of_base == "channel"
             else derive(text, n, rate, channels, offsets, start))
        return (x - centre) ** p
    if kind == "channel":
        return _channel(name, found[1], n, channels)
    if kind == "square":
        channel = token_channel(found[1])
        # the mean by the channel's name, or by its token (a fitted model's offsets name its
        # input channels as its terms do)
        mean = offsets.get(channel, offsets.get(found[1]))
        if channel not in channels or mean is None:
            raise InputError(f"column {name!r} needs the channel {channel!r} and its training "
                             "mean")
        return (_channel(name, found[1], n, channels) - mean) ** 2
    if kind in _READS:
        x = _channel(name, found[1], n, channels)
        if kind == "fast":
            return x - _level_from_mean(x, float(found[2]), rate)
        lagged = first_order_lag(x, float(found[2]), rate)
        if kind == "lowpass":
            return lagged
        return np.r_[0.0, np.diff(lagged) * rate] if n else lagged
    if start < 0:
        raise InputError(f"start must be a sample index (0 or more), got {start}")
    t = (start + np.arange(n)) / rate
    arg = float(found[1]) if len(found) > 1 else 0.0
    if kind == "cos":
        return np.cos(2 * np.pi * arg * t)
    if kind == "sin":
        return np.sin(2 * np.pi * arg * t)
    if kind == "time":
        return t
    if kind == "exp":
        return np.exp(-t / arg)
    return (t >= arg).astype(float)


class Description(NamedTuple):
    """What a derived column holds, in words, and its unit."""

    definition: str
    unit: str
    """``"s"``, ``"1"`` (dimensionless), or built from ``[<channel>]``, the unit of the
    channel read (``"[temp_c]^2"``, ``"[temp_c]/s"``), where it is not given."""


def describe(name: str, units: Mapping[str, str] | None = None) -> Description:
    """Return the definition and the unit of the derived column ``name``.

    Parameters
    ----------
    name : str
        A derived column's name (the module's table).
    units : mapping of str to str, optional
        Units of the channels by their names; a channel not in it is written ``[<name>]``.

    Returns
    -------
    Description

    Raises
    ------
    InputError
        Not a derived name.

    Examples
    --------
    >>> describe("exp(-t/413.66s)").definition
    'exp(-t / 413.66 s), t = (start + n) / rate in s'
    >>> describe("rate(temp_c,60s)", {"temp_c": "degC"}).unit
    'degC/s'
    """
    found = parse(name)
    if found is None or not is_derived(name):
        raise InputError(f"column {name!r} is not one fosmodel can derive")
    kind, args = found[0], found[1:]
    time = "t = (start + n) / rate in s"

    def unit_of(token: str) -> str:
        channel = token_channel(token)
        return (units or {}).get(channel, f"[{channel}]")

    if kind in ("cos", "sin"):
        return Description(f"{kind}(2 pi {args[0]} Hz t), {time}", "1")
    if kind == "time":
        return Description(f"t, {time}", "s")
    if kind == "exp":
        return Description(f"exp(-t / {args[0]} s), {time}", "1")
    if kind == "step":
        return Description(f"1 where t >= {args[0]} s, else 0; {time}", "1")
    if kind == "channel":
        return Description(f"the channel {token_channel(args[0])!r} as measured",
                           unit_of(args[0]))
    if kind == "power":
        base, p, centre = args
        inner = (describe(base, units) if _IDENTIFIER.match(base) is None
                 else Description(f"the channel {token_channel(base)!r}", unit_of(base)))
        return Description(f"({inner.definition} - {centre})^{p}", f"({inner.unit})^{p}")
    channel, unit = token_channel(args[0]), unit_of(args[0])
    if kind == "square":
        return Description(f"(x - mean)^2 of the channel {channel!r}, mean its training mean",
                           f"({unit})^2")
    if kind == "fast":
        return Description(f"the channel {channel!r} minus its local level over {args[1]} s "
                           "(exponentially weighted mean of its earlier samples, started at "
                           f"the mean of its first {args[1]} s)", unit)
    lag = (f"s[n] = s[n-1] + (x[n] - s[n-1]) / ({args[1]} s * rate), s[0] = x[0], x the "
           f"channel {channel!r}")
    if kind == "lowpass":
        return Description(f"first-order lag {lag}", unit)
    return Description(f"(s[n] - s[n-1]) * rate (0 at n = 0), {lag}", f"{unit}/s")


def _level_from_mean(x: np.ndarray, tau_s: float, rate: float) -> np.ndarray:
    """Return the local level of ``x`` over ``tau_s`` started at the mean of its first ``tau_s``.

    Started at ``x[0]``, as the output's level is, the level of a noisy channel would carry
    that one sample's noise for ``tau_s`` seconds: a transient whose mean over a fitting
    segment a model takes for an offset, and carries into every outage after it.
    """
    if not len(x):
        return x.copy()
    start = float(np.mean(x[: max(1, round(tau_s * rate))]))
    return level_series(np.r_[start, x], tau_s, rate)[1:]


def _channel(name: str, token: str, n: int, channels: Mapping[str, np.ndarray]) -> np.ndarray:
    """Return the first ``n`` samples of the channel ``token`` names (``name`` reads it)."""
    channel = token_channel(token)
    if channel not in channels:
        raise InputError(f"column {name!r} needs the channel {channel!r}")
    return np.asarray(channels[channel], dtype=float)[:n]
