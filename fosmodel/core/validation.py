"""Checks on in-memory signals, with messages that name the signal and the sample."""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Iterable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from .exceptions import InputError


def did_you_mean(name: str, options: Iterable[str]) -> str:
    """``" (did you mean 'x'?)"`` for the closest option, or an empty string.

    An option that is ``name`` with a suffix (``gz_rads`` for ``gz``, ``Accel X (g)`` for
    ``accel x``) comes first; else the closest by :func:`difflib.get_close_matches`.
    """
    options = list(options)
    key = name.strip().lower()
    suffixed = [o for o in options if key and o.lower() != key
                and re.match(re.escape(key) + r"[\s_.\-(\[]", o.lower())]
    if suffixed:
        return f" (did you mean {suffixed[0]!r}?)"
    close = difflib.get_close_matches(name, options, n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def check_fitted(model: object, attribute: str) -> None:
    """Raise :class:`NotFittedError` unless ``model`` has the fitted ``attribute``."""
    if not hasattr(model, attribute):
        from .exceptions import NotFittedError  # here: it imports scikit-learn

        raise NotFittedError(f"this {type(model).__name__} is not fitted yet; call fit() first")


def check_int(value: object, name: str, minimum: int) -> int:
    """``value`` as an int, refusing a bool, a non-integer or one below ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def check_positive(value: object, name: str) -> float:
    """``value`` as a float, refusing a bool, a non-number, NaN, infinity and anything <= 0."""
    if (isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating))
            or not math.isfinite(value) or value <= 0):
        raise InputError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def float_array(values: ArrayLike) -> np.ndarray:
    """Return ``values`` as a float64 ndarray: the very object when it already is one.

    ``np.asarray(x, dtype=float)`` makes a new view of an array whose float64 dtype is an
    equal but distinct object, as every array unpickled in a worker process has; the caches
    keyed by the array (:func:`fosmodel.core.levels.level_series`) would then never hit, and
    a study on a worker took 1.7 times as long as in this process.
    """
    if type(values) is np.ndarray and values.dtype == np.float64:
        return values
    return np.asarray(values, dtype=float)


def as_signal(values: ArrayLike, name: str, last: int | None = None) -> np.ndarray:
    """Return a finite 1-D float64 array from a numpy array, list or pandas Series.

    ``last`` checks only the last ``last`` samples for NaN/inf: those a free
    run reads of a long past.

    Raises
    ------
    InputError
        Not 1-D, not numeric, or holding NaN/inf (the first such sample is named).
    """
    if np.iscomplexobj(values):
        raise InputError(f"{name} is complex; fosmodel models real signals (pass its real part "
                         "or its magnitude if that is what you mean)")
    try:
        arr = float_array(values)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} is not numeric: {exc}") from None
    if arr.ndim != 1:
        raise InputError(f"{name} must be one-dimensional, got shape {arr.shape}")
    skip = 0 if last is None else max(len(arr) - last, 0)
    finite = np.isfinite(arr[skip:])
    if finite.all():
        return arr
    bad = skip + np.flatnonzero(~finite)
    raise InputError(
        f"{name} has {bad.size} non-finite value(s) (NaN or inf), first at sample {bad[0]}"
    )


def as_channels(
    exog: Mapping[str, ArrayLike] | None, needed: Iterable[str], length: int
) -> dict[str, np.ndarray]:
    """Return the channels ``needed`` from a dict or DataFrame, checked like :func:`as_signal`."""
    needed = list(needed)
    if not needed:
        return {}
    if exog is None:
        raise InputError(f"the model needs exogenous channel(s) {', '.join(needed)}; none given")
    available = [str(k) for k in exog.keys()]
    out = {}
    for ch in needed:
        if ch not in exog:
            raise InputError(
                f"exogenous channel {ch!r} not given{did_you_mean(ch, available)}; "
                f"available: {', '.join(available) or 'none'}"
            )
        arr = as_signal(exog[ch], f"channel {ch!r}")
        if len(arr) != length:
            raise InputError(f"channel {ch!r} has {len(arr)} samples, the output has {length}")
        out[ch] = arr
    return out
