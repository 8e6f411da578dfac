"""Independent calls run in worker processes (joblib), or here one after the other.

The six-axis workflow runs each axis's study and loop, and writes each axis's reports, this
way; so do the studies over several real records.  (The model-order study's fits go to a
Dask cluster instead, :mod:`fosmodel.study.distributed`, and a fleet's records to Dask or
here, :mod:`fosmodel.workflows.fleet`: a cluster, not one machine's processes.)
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any


def in_workers(calls: Iterable[tuple[Callable[..., Any], tuple]], n_jobs: int,
               ordered: bool = True) -> Iterator[Any]:
    """Yield ``function(*args)`` of every call, ``n_jobs`` at a time in worker processes.

    ``n_jobs`` 1 runs them here, one after the other.  The results come in the calls' order,
    or as they end when not ``ordered`` (a result then says what it is).  Each worker gets
    one BLAS thread (joblib's default for as many processes as cores), and large arrays are
    memory-mapped to the workers, not copied per call.
    """
    if n_jobs == 1:
        yield from (function(*args) for function, args in calls)
        return
    from joblib import Parallel, delayed

    run = Parallel(n_jobs=n_jobs, return_as="generator" if ordered else "generator_unordered")
    yield from run(delayed(function)(*args) for function, args in calls)
