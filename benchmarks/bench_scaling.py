"""FOS fit time and peak memory against the record length N and the number of candidates C.

Every point is measured in a fresh Python process (this script, run with
``--child``), so that its peak resident set size, ``getrusage(RUSAGE_SELF)
.ru_maxrss``, belongs to that point alone.  A point's process builds the
signals, then times ``FOSModel(..., stop="max_terms", max_terms=k).fit``
(candidate generation, correlation tables, search, coefficients) twice: the
first fit (cold) and the best of the two.  The points are run round-robin for
``--rounds`` rounds (these machines are noisy); a point's time is its best
over the rounds, its peak RSS the largest.  The process also reports its RSS
just before the fit (imports and data, read from ``/proc/self/statm``) and, in
the first round, the peak of the Python-heap allocations of one more fit
(tracemalloc, which sees numpy's arrays).

The signal is an AR(4) process with a small product of lags 1 and 3 added
(so that the search meets a true cross-product), driven by the exogenous
channels, when there are any, through their lag 1 + i; the exogenous channels
are AR(1) processes.  Which terms are selected matters for the time: a
selected cross-product costs one pass of degree-4 products over the record per
candidate shape, a linear term only table look-ups; each point prints how many
of its k terms are cross-products.

* time against N: L = 20, CP = 2 (230 candidates), 10 terms, N = 1e4 .. 1e6;
* time against C: N = 100,000, 10 terms, CP = 2 and L from 4 to 50, with one or two
  exogenous channels for the largest sets (14 .. 1,952 candidates);
* the largest configuration: N = 1,080,000 (90 minutes at 200 Hz), L = 50, CP = 2
  (1,325 candidates), 30 terms; target under 10 s and under 1 GB peak RSS on 2 cores.
  It is also run once with the other BLAS thread count, for comparison.

The log-log slopes of time against N and against C are printed, and a log-log
figure is written to ``--out``.  ``OPENBLAS_NUM_THREADS`` is set for the
child processes from ``--blas-threads`` (default 1; the comparison run of the
largest configuration uses the machine's CPU count).

Run: ``python benchmarks/bench_scaling.py [--quick] [--rounds R] [--out PATH]``
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from _common import loglog_slope, machine_line

HERE = Path(__file__).resolve().parent
BIG = {"n": 1_080_000, "lag": 50, "exog": {}, "k": 30}
TARGET_S, TARGET_MB = 10.0, 1000.0


def make_signals(n: int, exog: dict[str, int], seed: int = 0):
    """AR(4) output with a lag-1 x lag-3 product, driven by AR(1) exogenous channels."""
    from scipy.signal import lfilter

    rng = np.random.default_rng(seed)
    burn = 2000
    drive = rng.standard_normal(n + burn)
    channels = {}
    for i, name in enumerate(sorted(exog)):
        x = lfilter([1.0], [1.0, -0.9], rng.standard_normal(n + burn))
        channels[name] = x[burn:]
        drive[2 + i :] += 0.3 * x[: -(2 + i)]  # y depends on x[n-1-i]
    y = lfilter([1.0], [1.0, -1.1, 0.15, 0.1, -0.05], drive)
    y[3:] += 0.05 * y[2:-1] * y[:-3]
    return y[burn:], channels


def _current_rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def child(point: dict) -> None:
    """Measure one point in this (fresh) process; print one JSON line."""
    from fosmodel import FOSModel

    y, exog = make_signals(point["n"], point["exog"])
    model = FOSModel(max_lag=point["lag"], degree=2, exog_lags=point["exog"] or None,
                     stop="max_terms", max_terms=point["k"], max_candidates=10**6)
    rss_before = _current_rss_mb()
    times = []
    for _ in range(point["inner"]):
        t0 = time.perf_counter()
        model.fit(y, exog or None)
        times.append(time.perf_counter() - t0)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB on Linux
    heap = None
    if point["trace"]:
        import tracemalloc

        tracemalloc.start()
        model.fit(y, exog or None)
        heap = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
    print(json.dumps({
        "first": times[0], "best": min(times), "rss_before_mb": rss_before, "peak_mb": peak,
        "heap_mb": heap, "cands": model.n_candidates_ - 1, "terms": model.terms_,
        "cross": sum("*" in t or "^" in t for t in model.terms_),
    }))


def run_point(point: dict, threads: str, inner: int, trace: bool) -> dict:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": threads}
    spec = json.dumps({**point, "inner": inner, "trace": trace})
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child", spec],
                         env=env, capture_output=True, text=True, check=False, cwd=HERE.parent)
    if out.returncode != 0:
        raise RuntimeError(f"point {point} failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(points: dict[str, dict], rounds: int, threads: str, inner: int,
            once: dict[str, str] | None = None) -> dict[str, dict]:
    """Run every point ``rounds`` times round-robin; keep the best time and the largest RSS.

    ``once`` maps point names to a BLAS thread count: those run only in the
    first round, one fit, with that thread count.
    """
    once = once or {}
    results: dict[str, dict] = {}
    for r in range(rounds):
        for name, point in points.items():
            if name in once and r > 0:
                continue
            res = run_point(point, once.get(name, threads), 1 if name in once else inner,
                            trace=r == 0 and name not in once)
            prev = results.get(name)
            if prev is None:
                results[name] = res
                continue
            prev["best"] = min(prev["best"], res["best"])
            prev["first"] = min(prev["first"], res["first"])
            prev["peak_mb"] = max(prev["peak_mb"], res["peak_mb"])
            prev["rss_before_mb"] = max(prev["rss_before_mb"], res["rss_before_mb"])
    return results


def describe(point: dict) -> str:
    exog = ",".join(f"{k}:{v}" for k, v in point["exog"].items()) or "-"
    return f"{point['n']:>9,} {point['lag']:>3} {exog:<11} {point['k']:>3}"


def print_table(title: str, names: list[str], points: dict, res: dict) -> None:
    print(title)
    header = (f"{'N':>9} {'L':>3} {'exog':<11} {'k':>3} {'cands':>5} {'cross':>5} "
              f"{'first s':>8} {'best s':>8} {'RSS before MB':>13} {'peak RSS MB':>11} "
              f"{'heap peak MB':>12}")
    print(header)
    print("-" * len(header))
    for name in names:
        r = res[name]
        heap = "-" if r["heap_mb"] is None else f"{r['heap_mb']:.1f}"
        print(f"{describe(points[name])} {r['cands']:>5} {r['cross']:>5} {r['first']:>8.3f} "
              f"{r['best']:>8.3f} {r['rss_before_mb']:>13.0f} {r['peak_mb']:>11.0f} {heap:>12}")


def plot(out: Path, n_pts, c_pts, res, big) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    for col, (names, key, label) in enumerate(
            ((n_pts, "n", "record length N (samples)"), (c_pts, "cands", "candidates C"))):
        names = sorted(names, key=lambda n: res[n][key])
        xs = [res[n][key] for n in names]
        t = [res[n]["best"] for n in names]
        slope = loglog_slope(xs, t)
        ax = axes[0, col]
        ax.loglog(xs, t, "o-", label=f"FOSModel.fit (slope {slope:.2f})")
        ax.set_xlabel(label)
        ax.set_ylabel("fit time (s, best)")
        ax.grid(True, which="both", alpha=0.3)
        ax = axes[1, col]
        ax.loglog(xs, [res[n]["peak_mb"] for n in names], "o-", label="peak RSS")
        ax.loglog(xs, [res[n]["peak_mb"] - res[n]["rss_before_mb"] for n in names], "s--",
                  label="peak RSS - RSS before the fit")
        ax.set_xlabel(label)
        ax.set_ylabel("MB")
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].set_title("L = 20, CP = 2 (230 candidates), 10 terms")
    axes[0, 1].set_title(f"N = {res[c_pts[0]]['n']:,}, CP = 2, 10 terms")
    if big is not None:
        axes[0, 0].loglog([big["n"]], [big["best"]], "r*", ms=12,
                          label=f"L = 50, {big['cands']} cands, 30 terms")
        axes[0, 0].axhline(TARGET_S, color="r", ls=":", label="target 10 s")
        axes[1, 0].loglog([big["n"]], [big["peak_mb"]], "r*", ms=12, label="L = 50, 30 terms")
        axes[1, 0].axhline(TARGET_MB, color="r", ls=":", label="target 1 GB")
    for ax in axes.flat:
        ax.legend(fontsize=8)
        ax.xaxis.set_minor_formatter(NullFormatter())
    fig.suptitle("FOS fit time and memory (log-log)")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke check: small N and C, one round, no largest configuration")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--blas-threads", default="1",
                        help="OPENBLAS_NUM_THREADS for the measured processes (default 1)")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "scaling.png")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(json.loads(args.child))
        return

    rounds = 1 if args.quick else args.rounds
    n_values = (10_000, 30_000, 100_000) if args.quick else (
        10_000, 30_000, 100_000, 300_000, 1_000_000)
    n_fixed = 30_000 if args.quick else 100_000
    c_specs = ((4, {}), (10, {}), (20, {})) if args.quick else (
        (4, {}), (6, {}), (10, {}), (20, {}), (30, {}), (10, {"x1": 10, "x2": 10}),
        (30, {"x1": 15}), (50, {}), (40, {"x1": 20}))  # in order of the candidate count
    points: dict[str, dict] = {}  # by content: a point in both sweeps is measured once

    def add(point: dict) -> str:
        name = json.dumps(point, sort_keys=True)
        points[name] = point
        return name

    n_pts = [add({"n": n, "lag": 20, "exog": {}, "k": 10}) for n in n_values]
    c_pts = [add({"n": n_fixed, "lag": lag, "exog": exog, "k": 10}) for lag, exog in c_specs]
    other = str(os.cpu_count() or 2) if args.blas_threads == "1" else "1"
    once = {}
    if not args.quick:
        points["big"] = BIG
        points["big_other"] = BIG
        once = {"big_other": other}

    print(machine_line())
    print(f"measured processes: OPENBLAS_NUM_THREADS={args.blas_threads}; each point in a fresh "
          f"process, 2 fits per process, best over {rounds} round(s) run round-robin\n")
    t0 = time.perf_counter()
    res = measure(points, rounds, args.blas_threads, 2, once)
    for name, point in points.items():
        res[name]["n"] = point["n"]

    print_table("Time against N (L = 20, CP = 2, 10 terms)", n_pts, points, res)
    slope_n = loglog_slope([res[n]["n"] for n in n_pts], [res[n]["best"] for n in n_pts])
    line = f"log-log slope of time against N: {slope_n:.2f}"
    if len(n_pts) > 3:
        top = n_pts[-3:]
        slope_top = loglog_slope([res[n]["n"] for n in top], [res[n]["best"] for n in top])
        line += (f" over all points, {slope_top:.2f} over the largest three (fixed costs weigh "
                 "on the small N)")
    print(line + "\n")
    print_table(f"Time against C (N = {n_fixed:,}, CP = 2, 10 terms)", c_pts, points, res)
    slope_c = loglog_slope([res[n]["cands"] for n in c_pts], [res[n]["best"] for n in c_pts])
    print(f"log-log slope of time against C: {slope_c:.2f}\n")

    big = res.get("big")
    if big is None:
        print("largest configuration (N = 1,080,000, L = 50, CP = 2, 30 terms): skipped in --quick")
    else:
        print_table("Largest configuration", ["big", "big_other"], points, res)
        ok_t, ok_m = big["best"] < TARGET_S, big["peak_mb"] < TARGET_MB
        print(f"N = 1,080,000, L = 50, CP = 2, {big['cands']} candidates, 30 terms "
              f"({big['cross']} cross-products), OPENBLAS_NUM_THREADS={args.blas_threads}: "
              f"fit {big['best']:.2f} s (first fit {big['first']:.2f} s) against the target "
              f"< 10 s: {'met' if ok_t else 'NOT met'}; peak RSS {big['peak_mb']:.0f} MB "
              f"against the target < 1 GB: {'met' if ok_m else 'NOT met'} "
              f"(RSS before the fit {big['rss_before_mb']:.0f} MB)")
        bo = res["big_other"]
        print(f"the same with OPENBLAS_NUM_THREADS={other} (one fit): {bo['first']:.2f} s, "
              f"peak RSS {bo['peak_mb']:.0f} MB; ratio to {args.blas_threads} thread(s): "
              f"{bo['first'] / big['first']:.2f} (first fits)")
        terms_same = bo["terms"] == big["terms"]
        print(f"selected terms identical with both thread counts: {'yes' if terms_same else 'no'}")
    plot(args.out, n_pts, c_pts, res, big)
    print(f"\nfigure: {args.out}; total wall time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
