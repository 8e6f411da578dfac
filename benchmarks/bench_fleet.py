"""Time a fleet of IMU records in this process and on 1- and 2-worker Dask clusters.

Run: ``python benchmarks/bench_fleet.py [--records 8] [--duration 420] [--repeat 1]``
(``--adis`` runs the six ADIS16405 sessions of ``../shared/data`` instead; ``--steps allan``
a chosen step).

The fleet is ``--records`` six-axis ``data_synth`` sessions (scenario ``static_imu``, seeds 0,
1, ..., 100 Hz, ``--duration`` s each) written as CSV, each through the six-axis workflow of
``fosmodel.workflows.fleet.run_fleet``: the Allan analysis of all axes, and per axis a study
(FOS CP 1-2, Yule-Walker, Burg at orders 1-4, fair protocol) and the residual loop.  A
record is one task.  The same fleet runs in this process (the baseline, one record after the
other) and on local clusters of 1 and 2 single-threaded worker processes, each time into a
fresh store; cluster start-up and a warm-up fleet of one record per worker (first imports,
first calls) are outside the clock.  Repeats are interleaved and the best time of each way
kept.  Each run prints its CPU time (this process's, or the workers') over its wall time: the
cores it really got on a shared machine.  The script checks that the three summaries are
identical, then that a rerun after two records' markers are removed redoes those two only.
It prints each record's task time (the task sizes), and from them the time a fleet of such
tasks (the records measured, and 100 of them) would take on W workers with no overhead
(longest task first onto the least busy worker), beside the measured 1 and 2; and writes a
figure of both.
"""

from __future__ import annotations

import argparse
import heapq
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _common import machine_line
from bench_distributed import cores_available, cpu_seconds

from data_synth import make_scenario, write_record
from fosmodel.io.split import SplitSpec
from fosmodel.study.distributed import local_client
from fosmodel.workflows.fleet import MARKER, FleetConfig, record_name, run_fleet
from fosmodel.workflows.imu import ImuConfig

HERE = Path(__file__).resolve().parent
FLEET = 100  # the fleet of issue 20: 100 sessions of a few minutes
ADIS = HERE.parent.parent / "shared" / "data" / "adis16405"


def make_fleet(folder: Path, records: int, duration: float) -> list[Path]:
    """Write ``records`` six-axis static sessions of ``duration`` s as CSV; return the files."""
    files = []
    for seed in range(records):
        path = folder / f"session{seed:03d}.csv"
        write_record(make_scenario("static_imu", duration=duration, seed=seed), path)
        files.append(path)
    return files


def schedule(tasks: list[float], workers: int) -> float:
    """Time ``tasks`` take on ``workers`` with no overhead, longest first onto the least busy."""
    loads = [0.0] * workers
    for task in sorted(tasks, reverse=True):
        heapq.heapreplace(loads, loads[0] + task)
    return max(loads)


def _tiled(sizes: np.ndarray, n: int) -> list[float]:
    """``n`` tasks of the measured sizes, repeated in turn."""
    return list(np.resize(sizes, n))


def timed(files: list[Path], store: Path, config: FleetConfig, client: object
          ) -> tuple[float, float, pd.DataFrame, dict[str, float]]:
    """Wall time of the fleet into a fresh store, CPU time of the processes that ran it."""
    shutil.rmtree(store, ignore_errors=True)
    cpu, start = cpu_seconds(client), time.perf_counter()
    result = run_fleet(files, store, config, client=client)
    wall = time.perf_counter() - start
    return wall, cpu_seconds(client) - cpu, result.table, result.seconds


def check_resume(files: list[Path], store: Path, config: FleetConfig) -> str:
    """Remove two records' markers (an interrupted run) and rerun: only those two run again."""
    for path in files[:2]:
        (store / record_name(path) / MARKER).unlink()
    start = time.perf_counter()
    again = run_fleet(files, store, config)
    seconds = time.perf_counter() - start
    ok = sorted(again.ran) == sorted(record_name(p) for p in files[:2])
    return (f"resume: two markers removed, the rerun ran {len(again.ran)} records "
            f"({', '.join(again.ran)}) and skipped {len(again.skipped)} in {seconds:.2f} s: "
            f"{'as it should' if ok else 'WRONG'}")


def figure(tasks: list[float], measured: dict[int, float], here: float, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    from fosmodel.io.figures import tidy

    fig, (left, right) = plt.subplots(1, 2, figsize=(9.5, 3.8), layout="constrained")
    left.hist(tasks, bins=min(20, len(tasks)), color="C0")
    left.set_xlabel("task time: one record through the workflow (s)")
    left.set_ylabel("records")
    left.yaxis.set_major_locator(MaxNLocator(integer=True))
    left.set_title("task sizes", fontsize="medium")
    workers = np.array([1, 2, 4, 8, 16, 32])
    for n, style in sorted({(len(tasks), "o-"), (FLEET, "o--")} if len(tasks) != FLEET
                           else {(FLEET, "o-")}):
        right.loglog(workers, [schedule(_tiled(np.array(tasks), n), w) for w in workers], style,
                     color="0.5", label=f"{n} records of these sizes, no overhead")
    right.loglog(list(measured), list(measured.values()), "s", color="C3", ms=8,
                 label="measured (LocalCluster)")
    right.axhline(here, color="C0", lw=0.8, ls="--", label="in-process")
    right.set_xlabel("workers")
    right.set_ylabel("fleet wall time (s)")
    right.set_title(f"fleet time against workers ({len(tasks)} records measured)",
                    fontsize="medium")
    right.legend(fontsize="small")
    right.grid(True, which="both", alpha=0.3)
    tidy(fig)
    fig.savefig(out, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=8, help="synthetic records")
    parser.add_argument("--duration", type=float, default=420.0, help="seconds per record")
    parser.add_argument("--adis", action="store_true", help="the six ADIS16405 sessions")
    parser.add_argument("--steps", default="allan,study,loop")
    parser.add_argument("--repeat", type=int, default=1, help="interleaved repeats")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "fleet.png")
    args = parser.parse_args()
    print(f"{machine_line()}; two busy processes get {cores_available():.2f} cores", flush=True)
    config = FleetConfig(imu=ImuConfig(orders=range(1, 5), degrees=(1, 2),
                                       methods=("fos", "yw", "burg"), n_starts=10),
                         steps=tuple(args.steps.split(",")), split=SplitSpec.parse("50%,25%"),
                         load={"rate": 100.0} if args.adis else {})  # the sessions' rate
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if args.adis:
            files = sorted(ADIS.glob("imu*.csv.gz"))
            if not files:
                sys.exit(f"no ADIS16405 sessions in {ADIS}")
        else:
            files = make_fleet(folder, args.records, args.duration)
        (folder / "warm").mkdir()
        warm = make_fleet(folder / "warm", 2, 300.0)  # a record per worker: first calls
        print(f"fleet: {len(files)} records ({'ADIS16405' if args.adis else 'data_synth'}), "
              f"steps {args.steps}; a record is one task", flush=True)
        with local_client(1) as one, local_client(2) as two:
            ways = {"in-process": None, "1 worker": one, "2 workers": two}
            for name, client in ways.items():
                run_fleet(warm, folder / f"warm-{name}", config, client=client)
            best = dict.fromkeys(ways, float("inf"))
            tables, tasks = {}, {}
            for _ in range(args.repeat):
                for name, client in ways.items():
                    seconds, cpu, tables[name], task_s = timed(files, folder / name, config,
                                                               client)
                    if name == "in-process" and seconds < best[name]:
                        tasks = task_s  # the task sizes of the best in-process run
                    best[name] = min(best[name], seconds)
                    print(f"  {name:10s} {seconds:7.2f} s wall, {cpu:6.2f} s CPU: "
                          f"{cpu / seconds:.2f} cores busy", flush=True)
        same = all(t.equals(tables["in-process"]) for t in tables.values())
        resume = check_resume(files, folder / "in-process", config)
    sizes = np.array(list(tasks.values()))
    here, w1, w2 = best["in-process"], best["1 worker"], best["2 workers"]
    print(f"task sizes (s, in-process): min {sizes.min():.2f}, median {np.median(sizes):.2f}, "
          f"max {sizes.max():.2f}, total {sizes.sum():.2f}")
    if len(tasks) <= 12:  # each record's, when they fit on a line
        print("  " + ", ".join(f"{k} {v:.2f}" for k, v in tasks.items()))
    print(f"best of {args.repeat}: in-process {here:.2f} s, 1 worker {w1:.2f} s, 2 workers "
          f"{w2:.2f} s")
    print(f"1 worker / 2 workers = {w1 / w2:.2f}; in-process / 2 workers = {here / w2:.2f}; "
          f"1 worker / in-process = {w1 / here:.2f}")
    for n in sorted({len(sizes), FLEET}):
        print(f"from the task sizes, {n} records of them, no overhead (longest first): "
              + ", ".join(f"{w} worker(s) {schedule(_tiled(sizes, n), w):.1f} s"
                          for w in (1, 2, 4, 8, 16, 32)))
    print(f"same summary in-process and on 1 and 2 workers: {'yes' if same else 'NO'}")
    print(resume)
    print(f"after: {machine_line()}; two busy processes get {cores_available():.2f} cores")
    figure(list(sizes), {1: w1, 2: w2}, here, args.out)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
