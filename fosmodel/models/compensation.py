"""A model's *compensation*: a known part of the output, a weighted sum of derived columns.

A sensor's bias that follows a driver (a temperature, its lag, its square) is a
deterministic function of what is measured in use.  A model may carry it as a
compensation ``c[n] = sum_j w_j col_j[n]`` with fixed weights: its dynamics (lags,
local levels, other terms) are those of ``y - c``, and every prediction and free run
adds ``c`` back.  So a local level of such a model follows what the driver does not
explain, and holds still in an outage while the driver's part moves on as measured.
The columns are named by how to rebuild them (:mod:`fosmodel.core.derived`), so a
saved model applies to a new record of the same channels.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, TypeAlias

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from ..core.derived import channels_read, derive, is_derived
from ..core.exceptions import InputError

Exog: TypeAlias = Mapping[str, ArrayLike] | pd.DataFrame


def check_compensation(weights: Mapping[str, float] | None) -> dict[str, float]:
    """Return the compensation as a plain dict of finite weights by derived column name.

    Raises
    ------
    InputError
        Not a mapping, a name fosmodel cannot rebuild, or a weight that is not finite.
    """
    if weights is None:
        return {}
    if not isinstance(weights, Mapping):
        raise InputError(f"compensation must map derived column names to weights, got "
                         f"{type(weights).__name__}")
    out = {}
    for name, w in weights.items():
        if not isinstance(name, str) or not is_derived(name):
            raise InputError(f"compensation column {name!r} is not one fosmodel can rebuild "
                             "(see fosmodel.core.derived)")
        if isinstance(w, bool) or not isinstance(w, (int, float, np.integer, np.floating)) \
                or not math.isfinite(w):
            raise InputError(f"compensation weight of {name!r} must be a finite number, "
                             f"got {w!r}")
        out[name] = float(w)
    return out


def compensation_channels(weights: Mapping[str, float]) -> list[str]:
    """Return the record channels the compensation's columns read."""
    return channels_read(weights)


def compensation_series(weights: Mapping[str, float], exog: Exog | None, n: int,
                        rate: float | None) -> np.ndarray:
    """``sum_j w_j col_j`` over ``n`` samples; each column given in ``exog`` or rebuilt.

    A column given by its name is taken as it is (a record-long array spares its rebuild);
    else it is rebuilt from the channels it reads, which must be in ``exog``.

    Raises
    ------
    InputError
        A column neither given nor rebuildable (no rate, or a channel missing), or a given
        column of another length.
    """
    total = np.zeros(n)
    given: dict[str, Any] = {str(k): exog[k] for k in exog.keys()} if exog is not None else {}
    for name, w in weights.items():
        if name in given:
            values = np.asarray(given[name], dtype=np.float64)
            if values.shape != (n,):
                raise InputError(f"compensation column {name!r} has {values.size} samples, "
                                 f"the output has {n}")
        else:
            if rate is None:
                raise InputError(f"the compensation column {name!r} can be rebuilt only with "
                                 "the model's sample rate (rate=...)")
            read = {ch: given[ch] for ch in channels_read([name]) if ch in given}
            values = derive(name, n, rate, read, {})
        total += w * values
    return total
