"""Run model-order studies: every fit of their plans, in this process or on a Dask cluster.

:func:`run_study` runs one record's study, :func:`run_studies` several at once
(their fits together, so a cluster's workers stay busy).  The plans and the
fits themselves are the harness's (:func:`fosmodel.study.harness.plan_study`,
:func:`fosmodel.study.harness.run_task`); the cluster's side is
:mod:`fosmodel.study.distributed`, imported only when a client is given (Dask is an
optional extra).
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from numpy.typing import ArrayLike
from tqdm import tqdm

from .harness import FitScore, StudyConfig, StudyPlan, StudyResult, assemble, plan_study, run_task

if TYPE_CHECKING:  # only for the annotations: Dask is an optional extra
    from distributed import Client


def run_studies(
    plans: Sequence[StudyPlan], *, client: Client | None = None, progress: bool = False
) -> list[StudyResult]:
    """Run every task of several studies, here one by one or all at once on a Dask cluster.

    Parameters
    ----------
    plans : sequence of StudyPlan
    client : distributed.Client, optional
        Send the tasks to its cluster (see :mod:`fosmodel.study.distributed`); by
        default they run in this process, in order.
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    list of StudyResult
        One per plan; equal whichever way the tasks ran, ``runtime_s`` aside.
    """
    if client is None:
        scores = _run_here(plans, progress)
    else:
        from .distributed import run_tasks

        scores = run_tasks(plans, client, progress=progress)
    return [assemble(plan, plan_scores) for plan, plan_scores in zip(plans, scores)]


def _run_here(plans: Sequence[StudyPlan], progress: bool) -> list[list[FitScore]]:
    bar = tqdm(total=sum(len(plan.tasks) for plan in plans), disable=not progress,
               file=sys.stderr, desc="study", unit="fit")
    scores: list[list[FitScore]] = []
    with bar:
        for plan in plans:
            scores.append([])
            for task in plan.tasks:
                scores[-1].append(run_task(plan, task))
                bar.update()
    return scores


def run_study(
    y: ArrayLike, config: StudyConfig, *, progress: bool = False, client: Client | None = None
) -> StudyResult:
    """Fit, select and score every configuration of ``config`` on the record ``y``.

    Parameters
    ----------
    y : array-like
        The sensor record (the error signal of a static test), in ``config.units``.
    config : StudyConfig
    progress : bool
        Show a progress bar on stderr.
    client : distributed.Client, optional
        Run the fits on its Dask cluster instead of in this process.

    Returns
    -------
    StudyResult
    """
    return run_studies([plan_study(y, config)], client=client, progress=progress)[0]


def dask_client(scheduler: str | None = None, workers: int | None = None,
                timeout: float = 10.0) -> contextlib.AbstractContextManager:
    """Return a context giving the Dask client for :func:`run_studies`.

    The client is of the scheduler at the address ``scheduler``, or of a local cluster of
    ``workers`` single-threaded processes; None (run in this process) with neither.

    Raises
    ------
    ImportError
        Dask is not installed (the message names the extra to install).
    """
    if scheduler:
        from .distributed import connect_scheduler

        return connect_scheduler(scheduler, timeout)
    if workers:
        from .distributed import local_client

        return local_client(workers)
    return contextlib.nullcontext()
