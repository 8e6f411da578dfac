"""Time a 40-fit model-order study in this process and on 1- and 2-worker Dask clusters.

Run: ``python benchmarks/bench_distributed.py [--duration 10800] [--repeat 1]``.

The study is FOS (CP 1 and 2), Yule-Walker, covariance and Burg at orders 1-8
under the fair protocol (40 fits) on the paper-like accelerometer record of
``data_synth`` (seed 2013, 200 Hz, 3 h by default: each fit and its scoring
take about 0.1-1 s).  The same plan runs in this process (one fit after the
other, no scheduler) and on local clusters of 1 and 2 single-threaded worker
processes.  Every fit uses one BLAS thread.  Cluster start-up and a warm-up
study on a short record (first imports, first calls) are outside the clock;
scattering the record is inside.
Repeats are interleaved and the best time of each is kept.  The script prints
the machine, its load and how many cores two busy processes get (before and
after), and for each run the CPU time of the processes that fit (this one, or
the workers): on a shared machine the ratios depend on what it really gives.
It checks that the three ways give the same rows (runtime aside).
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import platform
import time
from multiprocessing.queues import Queue
from multiprocessing.synchronize import Barrier

import dask
import numpy as np

from data_synth import make_scenario
from fosmodel.study import StudyConfig, StudyPlan, local_client, plan_study, run_studies


def make_plan(duration: float) -> StudyPlan:
    """The 40-fit study on ``duration`` seconds of the paper-like accelerometer record."""
    rec = make_scenario("paper_accel_y", seed=2013, duration=duration)
    config = StudyConfig(rate=rec.rate, sensor="accel", units="m/s^2", orders=range(1, 9),
                         degrees=(1, 2), methods=("fos", "yw", "cov", "burg"),
                         protocols=("fair",), train_s=1800.0, evaluate_s=600.0,
                         levels=False)  # each method about the level too would make 152 fits
    plan = plan_study(rec.columns[rec.target], config)
    assert len(plan.tasks) == 40, len(plan.tasks)
    return plan


def cpu_seconds(client: object) -> float:
    """CPU time used so far by the processes that fit: this one, or the workers."""
    if client is None:
        return time.process_time()
    return sum(client.run(time.process_time).values())


def timed(plan: StudyPlan, client: object) -> tuple[float, float, object]:
    """Wall time of the study (scatter included on a cluster), CPU time of the fits, rows."""
    cpu, start = cpu_seconds(client), time.perf_counter()
    result = run_studies([plan], client=client)[0]
    wall = time.perf_counter() - start
    return wall, cpu_seconds(client) - cpu, result.rows.drop(columns="runtime_s")


def _burn(barrier: Barrier, results: Queue, n: int) -> None:
    """Once both processes are up, run a pure-Python loop of ``n`` steps; put (CPU s, wall s)."""
    barrier.wait()
    start, cpu, total = time.perf_counter(), time.process_time(), 0
    for i in range(n):
        total += i * i
    results.put((time.process_time() - cpu, time.perf_counter() - start))


def cores_available(n: int = 10_000_000) -> float:
    """The cores two busy processes get now: 2 on an idle 2-core machine, less if shared.

    Both start their loops together, after a barrier: with a pool, the first worker up could
    take both loops while the other was still importing, and a quiet machine read 1.0.
    """
    spawn = multiprocessing.get_context("spawn")
    barrier, results = spawn.Barrier(2), spawn.Queue()
    workers = [spawn.Process(target=_burn, args=(barrier, results, n)) for _ in range(2)]
    for worker in workers:
        worker.start()
    measured = [results.get() for _ in workers]
    for worker in workers:
        worker.join()
    return sum(cpu for cpu, _ in measured) / max(wall for _, wall in measured)


def machine() -> str:
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    return (f"{platform.platform()}, {platform.machine()}, {os.cpu_count()} CPUs, Python "
            f"{platform.python_version()}, numpy {np.__version__}, dask {dask.__version__}; "
            f"load average {load}; two busy processes get {cores_available():.2f} cores")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=10800.0, help="record seconds")
    parser.add_argument("--repeat", type=int, default=1, help="interleaved repeats")
    args = parser.parse_args()
    print(f"machine: {machine()}")
    plan = make_plan(args.duration)
    n = len(plan.signals[None][1])
    print(f"study: {len(plan.tasks)} fits (FOS CP 1-2, Yule-Walker, covariance, Burg; orders "
          f"1-8; fair protocol) on {n:,} samples ({n / plan.config.rate:g} s at "
          f"{plan.config.rate:g} Hz)", flush=True)
    warm_up = make_plan(2500.0)  # the shortest record the split takes
    with local_client(1) as one, local_client(2) as two:
        ways = {"in-process": None, "1-worker cluster": one, "2-worker cluster": two}
        for client in ways.values():
            run_studies([warm_up], client=client)  # first imports, first calls
        best = dict.fromkeys(ways, float("inf"))
        rows = {}
        for _ in range(args.repeat):
            for name, client in ways.items():
                seconds, cpu, rows[name] = timed(plan, client)
                best[name] = min(best[name], seconds)
                print(f"  {name:17s} {seconds:7.2f} s wall, {cpu:6.2f} s CPU: "
                      f"{cpu / seconds:.2f} cores busy", flush=True)
    same = all(rows[name].equals(rows["in-process"]) for name in ways)
    here, w1, w2 = best["in-process"], best["1-worker cluster"], best["2-worker cluster"]
    print(f"best of {args.repeat}: in-process {here:.2f} s, 1 worker {w1:.2f} s, "
          f"2 workers {w2:.2f} s")
    print(f"1 worker / 2 workers = {w1 / w2:.2f} (target >= 1.5); 1 worker / in-process = "
          f"{w1 / here:.2f}; in-process / 2 workers = {here / w2:.2f}")
    print(f"same rows (runtime aside) all three ways: {'yes' if same else 'NO'}")
    print(f"machine after: {machine()}")


if __name__ == "__main__":
    main()
