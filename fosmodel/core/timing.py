"""Where a fit's time goes: named parts that the kernels report into, when asked.

The correlation providers mark their parts (the plan, the first pass, each Gram column,
the pair and tile products inside them) with :func:`part`.  Outside a
:func:`timed_parts` block a mark is one context-variable read and a shared no-op
context manager (a fraction of a microsecond, a few hundred times per fit), so the
kernels keep their marks in every fit.  Inside one, each part's wall time is summed
under its name, nested parts under ``"outer: inner"``, and :func:`count` sums the
quantities the kernels report (such as multiply-adds).  Benchmarks read the parts
from it instead of patching the kernels.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext
from contextvars import ContextVar
from dataclasses import dataclass, field

_NOTHING = nullcontext()


@dataclass
class PartTimes:
    """Seconds per named part, and counts per name, summed over every time it ran.

    Attributes
    ----------
    seconds : dict of str to float
        Wall time of each part; a part run inside another is named ``"outer: inner"``
        (and its time is also in the outer part's).
    counts : dict of str to int
        Quantities reported with :func:`count`, under the enclosing part's name and
        theirs, as nested parts are.
    """

    seconds: dict[str, float] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    _open: list[str] = field(default_factory=list, repr=False)

    def _name(self, name: str) -> str:
        return ": ".join([*self._open[-1:], name])

    @contextmanager
    def _part(self, name: str) -> Iterator[None]:
        key = self._name(name)
        self._open.append(key)
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[key] = self.seconds.get(key, 0.0) + time.perf_counter() - t0
            self._open.pop()

    def _count(self, name: str, n: int) -> None:
        key = self._name(name)
        self.counts[key] = self.counts.get(key, 0) + n


_CURRENT: ContextVar[PartTimes | None] = ContextVar("fosmodel_part_times", default=None)


@contextmanager
def timed_parts() -> Iterator[PartTimes]:
    """Time the parts the kernels mark while the ``with`` block runs.

    Yields
    ------
    PartTimes
        Filled as the parts run; blocks may nest (the inner one collects alone).

    Examples
    --------
    >>> import numpy as np
    >>> from fosmodel import FOSModel
    >>> from fosmodel.core import timed_parts
    >>> y = np.random.default_rng(0).standard_normal(500)
    >>> with timed_parts() as parts:
    ...     _ = FOSModel(max_lag=3, degree=2).fit(y)
    >>> "first pass" in parts.seconds
    True
    """
    times = PartTimes()
    token = _CURRENT.set(times)
    try:
        yield times
    finally:
        _CURRENT.reset(token)


def part(name: str) -> AbstractContextManager[None]:
    """Sum the ``with`` block's wall time under ``name`` when parts are timed, else nothing."""
    times = _CURRENT.get()
    return _NOTHING if times is None else times._part(name)


def count(name: str, n: int) -> None:
    """Add ``n`` to the count ``name`` when parts are timed (``n`` should be cheap to form)."""
    times = _CURRENT.get()
    if times is not None:
        times._count(name, n)
