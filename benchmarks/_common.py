"""Helpers shared by the benchmark scripts: the machine line and interleaved best-of timing.

Not a benchmark itself.  The scripts import it as ``_common`` (``python
benchmarks/<script>.py`` puts ``benchmarks/`` on the path).
"""

from __future__ import annotations

import math
import os
import platform
import time
from collections.abc import Callable, Mapping

import numpy as np


def blas_info() -> str:
    """The BLAS numpy uses and its thread count, from threadpoolctl (when installed)."""
    try:
        from threadpoolctl import threadpool_info
    except ImportError:  # pragma: no cover - threadpoolctl comes with scikit-learn
        return "BLAS unknown (threadpoolctl missing)"
    pools = [p for p in threadpool_info() if p.get("user_api") == "blas"]
    if not pools:
        return "BLAS unknown"
    return "; ".join(
        f"{p.get('internal_api')} {p.get('version')} {os.path.basename(p.get('filepath', ''))} "
        f"({p.get('architecture')}, {p.get('num_threads')} threads)" for p in pools)


def limit_blas(threads: int | None):
    """Limit numpy's BLAS to ``threads`` threads (None: leave it); keep the result referenced."""
    if threads is None:
        return None
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=threads, user_api="blas")


def settle_allocator() -> None:
    """Put glibc's allocator where a long-lived process's settles, before any timing.

    glibc serves a large array by ``mmap`` (fresh pages, a page fault per 4 kB on first
    touch) until a freed mapped array raises its threshold.  So a function's time depended
    on which ran before it: statsmodels' ``burg(y, 10)`` took 1 ms or 2 ms on 36,000
    samples (0 or 460 page faults a call) and 25 ms or 100 ms on 360,000 (0 or 28,000),
    according to the preceding fit.  One freed 30 MiB array (under glibc's 32 MiB cap on
    the threshold) raises it for the process: every timed function then allocates
    without faults, as in a study that has run a while.  Elsewhere it does no harm.
    """
    block = np.ones(30 * 2**17)  # 30 MiB, touched, then freed
    del block


def machine_line() -> str:
    """One line naming the machine, the software and the BLAS threads, for every report."""
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "unset")  # the BLAS entry shows any limit
    return (f"machine: {platform.platform()}, {os.cpu_count()} CPUs, load average {load}; "
            f"Python {platform.python_version()}, numpy {np.__version__}; {blas_info()}; "
            f"OPENBLAS_NUM_THREADS={threads}")


def interleaved_times(
    fns: Mapping[str, Callable[[], object]], repeats: int,
    few: Mapping[str, int] | None = None, loop_s: float = 0.02, cpu: bool = False,
) -> dict[str, list[float]]:
    """Time per call of each function in every round, timed round-robin to share the noise.

    As ``timeit`` does, each round runs a function in a loop of consecutive
    calls lasting at least ``loop_s`` seconds (one call for slow functions)
    and takes the loop's mean.  Timing single calls of a fast function right
    after a slow one would charge it the caches and page faults the slow one
    left behind.  ``few`` caps the rounds of slow functions: ``{"frols": 3}``
    times it only in the first 3 rounds.  With ``cpu``, each list is followed
    in the result by the CPU time of this thread per call in the same loops,
    under the function's name with `` cpu`` appended: on a machine shared with
    other work, the time the thread waited for a core is in the wall time only.
    """
    few = few or {}
    number = {name: _calls_per_loop(fn, loop_s) for name, fn in fns.items()}
    times: dict[str, list[float]] = {name: [] for name in fns}
    times.update({f"{name} cpu": [] for name in fns} if cpu else {})
    for round_ in range(repeats):
        for name, fn in fns.items():
            if round_ >= few.get(name, repeats):
                continue
            t0, c0 = time.perf_counter(), time.thread_time()
            for _ in range(number[name]):
                fn()
            times[name].append((time.perf_counter() - t0) / number[name])
            if cpu:
                times[f"{name} cpu"].append((time.thread_time() - c0) / number[name])
    return times


def interleaved_best(
    fns: Mapping[str, Callable[[], object]], repeats: int,
    few: Mapping[str, int] | None = None, loop_s: float = 0.02,
) -> dict[str, float]:
    """Best time per call of each function over :func:`interleaved_times`' rounds."""
    return {k: min(v) for k, v in interleaved_times(fns, repeats, few, loop_s).items()}


def interleaved_median(
    fns: Mapping[str, Callable[[], object]], repeats: int,
    few: Mapping[str, int] | None = None, loop_s: float = 0.02, cpu: bool = False,
) -> dict[str, float]:
    """Median time per call of each function over :func:`interleaved_times`' rounds.

    With ``cpu``, also the median CPU time of each (``name + " cpu"``).
    """
    return {k: float(np.median(v))
            for k, v in interleaved_times(fns, repeats, few, loop_s, cpu).items()}


def _calls_per_loop(fn: Callable[[], object], loop_s: float) -> int:
    """Calls that make a loop last at least ``loop_s`` seconds, from one timed call."""
    t0 = time.perf_counter()
    fn()
    return max(1, math.ceil(loop_s / max(time.perf_counter() - t0, 1e-9)))


def loglog_slope(x, y) -> float:
    """Least-squares slope of log(y) against log(x)."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])
