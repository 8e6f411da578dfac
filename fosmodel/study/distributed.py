"""Model-order studies on a Dask cluster (dask.distributed).

A study is a set of independent fits (:func:`fosmodel.study.harness.plan_study`).
Here the fits of several studies go to a cluster as one set of tasks, so that
every worker stays busy: each study's plan (its record, split and denoised
signals) is scattered to every worker once, and each task fits and scores one
configuration on it with :func:`fosmodel.study.harness.run_task`.

One BLAS thread per fit: ``run_task`` limits BLAS to one thread itself
(threadpoolctl), in this process and on any worker, so that a fit gives the
same bits everywhere; the workers of :func:`local_client` also run one task at
a time and start with ``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` and
``MKL_NUM_THREADS`` set to 1 (:data:`WORKER_ENV`).  The workers of an existing
scheduler need fosmodel (the same version) installed.
"""

from __future__ import annotations

import contextlib
import logging
import sys
from collections.abc import Iterator, Sequence

from tqdm import tqdm

try:
    import dask
    from distributed import Client, LocalCluster, as_completed
except ImportError as exc:  # an optional extra: say how to get it
    raise ImportError("running fits on Dask needs the 'distributed' extra: pip install "
                      "'fosmodel[distributed]'") from exc

from ..core.exceptions import InputError
from .harness import FitScore, StudyPlan, run_task

#: Environment of the worker processes of :func:`local_client`, set before they start.
#: Dask's default also sets ``MALLOC_TRIM_THRESHOLD_``, which turns off glibc's
#: adaptive mmap threshold: every temporary array of a long record is then mapped
#: afresh and page-faulted, and the fits ran 2-4 times slower.  It is left unset.
WORKER_ENV = {"OMP_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1, "MKL_NUM_THREADS": 1,
              "MALLOC_TRIM_THRESHOLD_": None}


def connect_scheduler(address: str, timeout: float = 10.0) -> Client:
    """Connect a client to the Dask scheduler at ``address`` (e.g. ``tcp://10.0.0.5:8786``).

    Raises
    ------
    InputError
        If no scheduler answers at ``address`` within ``timeout`` seconds.
    """
    try:
        return Client(address, timeout=f"{timeout}s")
    except Exception as exc:  # refused, timed out, malformed address, not a scheduler
        raise InputError(f"cannot connect to the Dask scheduler at {address}: "
                         f"{type(exc).__name__}: {exc}") from None


@contextlib.contextmanager
def local_client(n_workers: int) -> Iterator[Client]:
    """Start a local cluster of ``n_workers`` single-threaded processes; yield its client.

    The cluster is closed on exit.
    """
    if n_workers < 1:
        raise InputError(f"the number of workers must be at least 1, got {n_workers}")
    with _quiet(), dask.config.set({"distributed.nanny.pre-spawn-environ": WORKER_ENV}), \
            LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                         dashboard_address=None, silence_logs=logging.ERROR,
                         scheduler_kwargs={"dashboard_address": ":0"}) as cluster, \
            Client(cluster) as client:
        yield client


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """Keep the scheduler's and nannies' start and stop messages (INFO) off stderr."""
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def run_tasks(
    plans: Sequence[StudyPlan], client: Client, *, progress: bool = False
) -> list[list[FitScore]]:
    """Run every task of every plan on ``client``'s cluster, submitted together.

    Parameters
    ----------
    plans : sequence of StudyPlan
    client : distributed.Client
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    list of list of FitScore
        Per plan, the scores of its tasks in order.
    """
    # hash=False: a plan equal to one scattered before (whose data may be on its way
    # out) gets a key of its own
    shared = client.scatter(list(plans), broadcast=True, hash=False)
    pairs = [(future, task) for future, plan in zip(shared, plans) for task in plan.tasks]
    futures = client.map(run_task, [f for f, _ in pairs], [t for _, t in pairs], pure=False)
    with tqdm(total=len(futures), disable=not progress, file=sys.stderr, desc="study",
              unit="fit") as bar:
        for _ in as_completed(futures):
            bar.update()
    scores = iter(client.gather(futures))
    return [[next(scores) for _ in plan.tasks] for plan in plans]
