"""What a record's analysed columns hold, checked before any fitting; the others left out.

Every command checks the columns it analyses, and the drivers its model may use, the same
way (:func:`settle`), before it fits anything:

- the loader's refusals it held (``load_record(..., hold=True)``): cells that are no finite
  real numbers, booleans, outliers under ``outliers="refuse"`` (:mod:`fosmodel.io.outliers`);
- their content (:func:`check_content`): only zeros, a constant, values too small to compute
  with (a mean square below float64's smallest normal number: denormal numbers), and integers
  beyond 2^53, which float64 does not hold to the unit (a raw counter's overflowing uint64).

A column that is neither analysed nor a driver (another axis, a flag) does not refuse the
record: one the loader held is named in a note and left out of the record, and so out of
whatever it would have fed (the loop's cross-axis table).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..core.exceptions import InputError
from .record import Record

#: Values at most this large in magnitude have squares below float64's smallest normal number
#: (2.2e-308): their mean square, variance and Allan deviation are zero or denormal.
TINY = 1e-154
#: Integers beyond this (2^53) are not held exactly by float64.
EXACT_INTEGERS = 2.0**53


def check_content(x: np.ndarray, name: str, source: str) -> None:
    """Refuse a column that holds nothing a model or an Allan deviation can use.

    Raises
    ------
    InputError
        Only zeros, a constant, every value within :data:`TINY` of zero, or integers beyond
        :data:`EXACT_INTEGERS` (the message names the column and what it holds).
    """
    if not x.size:
        return
    low, high = float(x.min()), float(x.max())
    scale = max(abs(low), abs(high))
    if scale == 0.0:
        raise InputError(f"{source}: column {name!r} holds only zeros: there is nothing to "
                         "model (a sensor's readings are never exactly zero throughout)")
    if scale >= EXACT_INTEGERS and np.array_equal(x, np.rint(x)):
        i = int(np.argmax(np.abs(x)))
        raise InputError(f"{source}: column {name!r}: integers up to {x[i]:.4g} (row {i + 1}), "
                         "beyond the 2^53 that float64 holds exactly: a raw counter that "
                         "overflowed, or readings of another type; check the column")
    if low == high:
        raise InputError(f"{source}: column {name!r} is constant ({low:g}): there is nothing "
                         "to model")
    if scale <= TINY:
        raise InputError(f"{source}: column {name!r}: its values are at most {scale:.3g} in "
                         f"magnitude, too small to compute with (their squares fall below "
                         f"float64's smallest normal number); check its units or pass "
                         f"scale={{{name!r}: FACTOR}}")


def settle(rec: Record, analysed: Sequence[str], feeds: str = "",
           drivers: Sequence[str] = ()) -> Record:
    """Refuse the record on its analysed columns' content; leave out the others the loader held.

    Parameters
    ----------
    rec : Record
        As loaded, with ``hold=True`` (or not: then only :func:`check_content` applies).
    analysed : sequence of str
        The columns analysed and the drivers the model may use.
    feeds : str, optional
        What a column left out would have fed, for its note (``"the cross-axis table"``).
    drivers : sequence of str, optional
        Those of ``analysed`` that are drivers: a refusal of one says that it gets the
        modelled column's policy.

    Returns
    -------
    Record
        ``rec``, without the columns left out (each named in its notes).

    Raises
    ------
    InputError
        The first analysed column the loader held (its own message), or whose content
        :func:`check_content` refuses.
    """
    for name in analysed:
        if name in rec.held:
            why = (f" ({name!r} is a driver the model may use: the modelled column's policy "
                   "applies to it)" if name in drivers else "")
            raise InputError(rec.held[name] + why)
    for name in analysed:
        if name in rec.data:
            check_content(rec.data[name], name, rec.source)
    for name, why in rec.held.items():
        rec.data.pop(name, None)
        reason = why.removeprefix(f"{rec.source}: ")
        rec.notes.append(f"column {name!r} left out of {feeds or 'the analysis'} (it is not "
                         f"analysed): {reason}")
    rec.held = {}
    if not rec.data:
        raise InputError(f"{rec.source}: no column left to analyse")
    return rec
