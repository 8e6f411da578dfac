"""Independent calls run in worker processes (joblib), or here one after the other.

The six-axis workflow runs each axis's study and loop, and writes each axis's reports, this
way; so do the studies over several real records.  (The model-order study's fits go to a
Dask cluster instead, :mod:`fosmodel.study.distributed`, and a fleet's records to Dask or
here, :mod:`fosmodel.workflows.fleet`: a cluster, not one machine's processes.)
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TypeVar

Result = TypeVar("Result")


def in_workers(calls: Iterable[tuple[Callable[..., Any], tuple]], n_jobs: int,
               ordered: bool = True) -> Iterator[Any]:
    """Yield ``function(*args)`` of every call, ``n_jobs`` at a time in worker processes.

    ``n_jobs`` 1 runs them here, one after the other.  The results come in the calls' order,
    or as they end when not ``ordered`` (a result then says what it is).  Each worker gets
    one BLAS thread (joblib's default for as many processes as cores), and large arrays are
    memory-mapped to the workers, not copied per call.  A call runs in the caller's current
    directory, as it would here, so that relative paths name the same files.
    """
    if n_jobs == 1:
        yield from (function(*args) for function, args in calls)
        return
    from joblib import Parallel, delayed

    here = os.getcwd()
    run = Parallel(n_jobs=n_jobs, return_as="generator" if ordered else "generator_unordered")
    yield from run(delayed(_in_kept_worker)(function, args, here) for function, args in calls)


def _in_kept_worker(function: Callable[..., Result], args: tuple, cwd: str) -> Result:
    """Call ``function(*args)`` in ``cwd``, in a worker that loky will not retire for its memory.

    The workers outlive a call (loky reuses them), so a worker started before the caller
    changed directory would read and write relative paths elsewhere: it moves to the caller's.

    loky measures a worker's memory after its first call and retires the worker once it
    holds 300 MB more; a worker whose first call was small and whose next one imports the
    models and draws figures is retired so, and a worker retired while calls wait can leave
    the caller waiting for ever (the executor loses the call).  What a worker holds here is
    the libraries it imported, not a leak: the check is switched off in the worker, which
    then only collects garbage between calls.
    """
    from joblib.externals.loky import process_executor

    process_executor._USE_PSUTIL = False
    os.chdir(cwd)
    return function(*args)
