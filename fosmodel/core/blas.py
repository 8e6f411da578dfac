"""One BLAS thread for the searches' products.

The correlation tables and the search work by many short, memory-bound dot
products and small matrix products.  OpenBLAS splits each over its threads,
which costs far more than it gains at these sizes (a dot product of 36,000
values took 12 us on one thread and 184 us on two on a busy 2-core machine),
so the fits run with BLAS limited to one thread and restore the caller's
setting after.  The limit is process-wide while it holds.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache

from threadpoolctl import ThreadpoolController


@lru_cache(maxsize=1)
def _controller() -> ThreadpoolController:
    return ThreadpoolController()  # inspects the loaded libraries once: a few ms


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Limit BLAS to one thread inside the ``with`` block (a few microseconds).

    Only the libraries not already at one thread are touched, so nested
    blocks cost two reads of the thread count.
    """
    blas = [lib for lib in _controller().lib_controllers if lib.user_api == "blas"]
    changed = [(lib, n) for lib in blas if (n := lib.num_threads) != 1]
    for lib, _ in changed:
        lib.set_num_threads(1)
    try:
        yield
    finally:
        for lib, n in changed:
            lib.set_num_threads(n)
