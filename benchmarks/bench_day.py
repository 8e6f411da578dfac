"""A day of data: a 24 h, 200 Hz, six-axis record through every step.

data_synth's ``static_imu`` scenario (ADIS16405-like white noise, bias
instability and rate random walk on gx..gz in deg/s and ax..az in m/s^2) is
generated for 86,400 s at 200 Hz (17,280,000 samples per axis) and written
as Parquet and as a structured ``.npy`` (``--data DIR`` keeps the files and
reuses them on the next run).  On its ``gx_dps`` axis:

* reading: ``fosmodel.io.loader.load_record`` of each file against the
  underlying reader timed in the same run (``pyarrow.parquet.read_table``,
  alone and with its columns turned into numpy arrays as load_record gives
  them; ``np.load(mmap_mode="r")`` and a copy of every column; ``pandas.read_csv``
  on the record's first hour written as CSV);
* the FOS fit ``FOSModel(max_lag=50, degree=2, max_terms=30, stop="max_terms")``
  against statsmodels' Burg AR(50) on the same samples, and the residual loop
  (``close_loop`` with its defaults, no auxiliary channel), each for N from
  10^4 (the loop from 4 x 10^4, the shortest its default split takes) to the
  day, every point in a fresh process whose peak resident set size (VmHWM,
  reset just before the step) belongs to it alone; the process also reports
  its RSS just before the step (imports and the N samples), so the step's own
  memory is the difference; a fit under 5 s runs twice and its time is the
  best (the first pays the imports and the candidate plan), the loop runs
  once; log-log slopes of time and memory against N (the number of
  cross-products FOS selects is given: each costs a pass over the record);
* the Allan analysis of the whole day (``allan_deviation`` + ``fit_noise``)
  against ``allantools.oadev`` on the same averaging times;
* the model-order study of the whole day (``run_study``: orders 1-10, CP 1-2,
  every method, both protocols, the CLI's default 180 s + 180 s split).

Targets (issue 20): fit < 30 s and < 2 GB peak; Allan < 15 s; study and loop
< 2 min each.  Writes a text table and a log-log figure.

Run: ``python benchmarks/bench_day.py [--quick] [--data DIR] [--out PATH]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _common import loglog_slope, machine_line

HERE = Path(__file__).resolve().parent
RATE = 200.0
DAY_S = 86_400.0
CSV_S = 3_600.0  # the CSV holds the first hour
AXIS = "gx_dps"
SIZES = (10_000, 40_000, 100_000, 1_000_000, 4_000_000, 17_280_000)
LOOP_MIN = 40_000  # the loop's default split needs a 30 s outage and two 30 s bias windows
TARGETS = {"fit": 30.0, "allan": 15.0, "study": 120.0, "loop": 120.0}
TARGET_FIT_MB = 2000.0


def write_day(folder: Path, seconds: float) -> dict[str, Path]:
    """Generate the record (unless the files are there) and write Parquet, .npy and the axis.

    Also its first hour as CSV: a day of CSV text would take 2 GB and minutes to write.
    """
    paths = {"parquet": folder / "day.parquet", "npy": folder / "day.npy",
             "csv": folder / "hour.csv", "axis": folder / f"{AXIS}.npy"}
    if all(p.exists() for p in paths.values()):
        axis = np.load(paths["axis"], mmap_mode="r")
        if len(axis) == round(seconds * RATE):
            return paths
    from data_synth import make_scenario

    t0 = time.perf_counter()
    rec = make_scenario("static_imu", duration=seconds, rate=RATE, seed=0)
    frame = rec.to_frame()
    frame.to_parquet(paths["parquet"], index=False)
    np.save(paths["npy"], frame.to_records(index=False))
    np.save(paths["axis"], rec.columns[AXIS])
    frame.iloc[: round(min(seconds, CSV_S) * RATE)].to_csv(paths["csv"], index=False)
    print(f"generated and wrote {rec.n_samples:,} samples x {len(rec.columns)} axes "
          f"in {time.perf_counter() - t0:.0f} s", flush=True)
    return paths


def _status_mb(field: str) -> float:
    """A memory field of /proc/self/status (VmRSS, VmHWM) in MB."""
    with open("/proc/self/status") as f:
        line = next(line for line in f if line.startswith(field + ":"))
    return int(line.split()[1]) / 1024


def _reset_peak() -> None:
    """Reset VmHWM to the current RSS (Linux 4.0+), so that the peak is the step's alone.

    ``ru_maxrss`` would not do: it survives exec, so a child starts with its parent's peak.
    """
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def _fos(y: np.ndarray) -> object:
    from fosmodel.models.model import FOSModel

    return FOSModel(max_lag=50, degree=2, max_terms=30, stop="max_terms").fit(y)


def _burg(y: np.ndarray) -> object:
    from statsmodels.regression.linear_model import burg

    return burg(y, 50)


def _loop(y: np.ndarray) -> object:
    from fosmodel.loop.closeloop import LoopConfig, close_loop

    return close_loop(y, {}, LoopConfig(rate=RATE, sensor="gyro", units="deg/s"))


def _study(y: np.ndarray) -> object:
    from fosmodel.study.harness import StudyConfig
    from fosmodel.study.runner import run_study

    return run_study(y, StudyConfig(rate=RATE, sensor="gyro", units="deg/s"))


def _allan(y: np.ndarray) -> object:
    from fosmodel.noise.allan import allan_deviation
    from fosmodel.noise.allan_fit import fit_noise

    return fit_noise(allan_deviation(y, RATE, units="deg/s", sensor="gyro"))


def _oadev(y: np.ndarray) -> object:
    import allantools

    from fosmodel.noise.allan import _averaging_factors

    ms = _averaging_factors(len(y), RATE, None, 10)  # allan_deviation's default taus
    return allantools.oadev(y, rate=RATE, data_type="freq", taus=ms / RATE)


STEPS = {"fit": _fos, "burg": _burg, "loop": _loop, "study": _study, "allan": _allan,
         "oadev": _oadev}


def child(step: str, axis: str, n: int) -> None:
    """Run one step on the first ``n`` samples in this fresh process; print one JSON line."""
    import fosmodel.models.model  # noqa: F401  (imports before the RSS reading)

    y = np.array(np.load(axis, mmap_mode="r")[:n])
    before = _status_mb("VmRSS")
    _reset_peak()
    times = []
    runs = 1 if step == "loop" else 2  # a loop's second run would find its levels cached
    while len(times) < runs and sum(times) < 5.0:  # short fits twice: the first plans
        t0 = time.perf_counter()
        result = STEPS[step](y)
        times.append(time.perf_counter() - t0)
    extra = {"terms": list(result.terms_)} if step == "fit" else {}
    print(json.dumps({"step": step, "n": n, "s": min(times), "first_s": times[0],
                      "before_mb": before, "peak_mb": _status_mb("VmHWM"), **extra}))


def run_child(step: str, axis: Path, n: int) -> dict:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "1")}
    out = subprocess.run([sys.executable, __file__, "--child", step, str(axis), str(n)],
                         capture_output=True, text=True, env=env, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def time_reading(paths: dict[str, Path]) -> list[tuple[str, float, str, float]]:
    """Best of three reads of each file by load_record and by its underlying reader.

    Parquet is compared with pyarrow's table alone and with the table turned
    into numpy columns, which is what load_record gives; the CSV with pandas
    as it is and with the option the loader reads with.
    """
    import pandas as pd
    import pyarrow.parquet as pq

    from fosmodel.io.loader import load_record

    def npy_columns() -> list[np.ndarray]:
        table = np.load(paths["npy"], mmap_mode="r")
        return [np.array(table[name]) for name in table.dtype.names]

    def arrow_columns() -> list[np.ndarray]:
        return [c.to_numpy() for c in pq.read_table(paths["parquet"]).columns]

    def csv_columns(**options: object) -> list[np.ndarray]:
        frame = pd.read_csv(paths["csv"], **options)
        return [frame[name].to_numpy(dtype=float) for name in frame.columns]

    readers = [("csv", "pandas.read_csv + to_numpy of each column", csv_columns),
               ("csv", "the same with skipinitialspace=True, as the loader reads (' 1.5, x')",
                lambda: csv_columns(skipinitialspace=True)),
               ("parquet", "pyarrow.parquet.read_table", lambda: pq.read_table(paths["parquet"])),
               ("parquet", "read_table + to_numpy of each column", arrow_columns),
               ("npy", "np.load(mmap_mode='r') + a copy of each column", npy_columns)]
    rows = []
    for kind, label, read in readers:
        ours, base = [], []
        for _ in range(3):  # alternate, so that both see the same page cache
            t0 = time.perf_counter()
            read()
            base.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            load_record(paths[kind])
            ours.append(time.perf_counter() - t0)
        rows.append((kind, min(ours), label, min(base)))
    return rows


def figure(points: list[dict], slopes: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    styles = {"fit": ("C0", "o", "FOS fit (L=50, CP=2, 30 terms)"),
              "burg": ("C2", "s", "statsmodels Burg AR(50)"),
              "loop": ("C3", "^", "residual loop")}
    for step, (color, marker, label) in styles.items():
        mine = [p for p in points if p["step"] == step]
        n = [p["n"] for p in mine]
        ax_t.loglog(n, [p["s"] for p in mine], marker=marker, color=color,
                    label=f"{label}, slope {slopes[step, 's']:.2f}")
        if step != "burg":
            ax_m.loglog(n, [p["peak_mb"] - p["before_mb"] for p in mine], marker=marker,
                        color=color,
                        label=f"{label}, slope {slopes[step, 'mb']:.2f}")
    data = np.array(sorted({p["n"] for p in points}))
    ax_m.loglog(data, data * 8 / 2**20, "k--", label="the axis itself (8 bytes a sample)")
    ax_t.set(xlabel="samples N", ylabel="time (s)", title="time against N")
    ax_m.set(xlabel="samples N", ylabel="peak RSS above the data (MB)",
             title="memory of the step against N")
    for ax in (ax_t, ax_m):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.savefig(path, dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="a 2,000 s record and N up to 4 x 10^4 (a smoke test)")
    parser.add_argument("--data", type=Path, help="folder to keep the record in and reuse it")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "day.txt")
    args = parser.parse_args()
    seconds = 2_000.0 if args.quick else DAY_S
    sizes = (10_000, 40_000) if args.quick else SIZES
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.data or Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        paths = write_day(folder, seconds)
        n_day = len(np.load(paths["axis"], mmap_mode="r"))
        reading = time_reading(paths)
        points = [run_child(step, paths["axis"], n) for n in sizes
                  for step in ("fit", "burg", "loop") if step != "loop" or n >= LOOP_MIN]
        whole = {step: run_child(step, paths["axis"], n_day)
                 for step in ("allan", "oadev", "study")}
    lines = report(reading, points, whole, n_day)
    lines.append(f"total wall time {time.perf_counter() - t_start:.0f} s")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure_path = args.out.with_suffix(".png")
    slopes = _slopes(points)
    figure(points, slopes, figure_path)
    lines.append(f"figure: {figure_path.name}")
    text = "\n".join(lines) + "\n"
    args.out.write_text(text)
    print(text, end="")


def _slopes(points: list[dict]) -> dict:
    out = {}
    for step in ("fit", "burg", "loop"):
        mine = [p for p in points if p["step"] == step]
        n = [p["n"] for p in mine]
        if len(n) < 2:
            out[step, "s"] = out[step, "mb"] = float("nan")
            continue
        out[step, "s"] = loglog_slope(n, [p["s"] for p in mine])
        out[step, "mb"] = loglog_slope(n, [max(p["peak_mb"] - p["before_mb"], 1.0)
                                           for p in mine])
    return out


def report(reading: list, points: list[dict], whole: dict, n_day: int) -> list[str]:
    lines = [f"A day of data: data_synth static_imu, {n_day:,} samples per axis at {RATE:g} Hz, "
             f"axis {AXIS}; each step in a fresh process (OPENBLAS_NUM_THREADS="
             f"{os.environ.get('OPENBLAS_NUM_THREADS', '1')})", machine_line(), "",
             "Reading the six-axis record and its time column (best of 3; load_record also "
             "checks every cell, the time base and the outlier rule; the CSV holds the first "
             f"hour, {round(min(n_day / RATE, CSV_S) * RATE):,} rows)",
             f"{'file':8s} {'load_record s':>13s} {'reader s':>9s} {'ratio':>6s}  reader"]
    for kind, ours, label, base in reading:
        lines.append(f"{kind:8s} {ours:13.2f} {base:9.2f} {ours / base:6.2f}  {label}")
    lines += ["", "Time and peak memory against N (fit time: best of 2 fits under 5 s, 'first' "
              "the first's, 'cross' the cross-products among its 30 terms; loop: one run; RSS "
              "before: imports and the samples; step MB = peak - before)",
              f"{'N':>11s} {'FOS s':>7s} {'first':>7s} {'cross':>5s} {'Burg s':>8s} "
              f"{'FOS/Burg':>8s} "
              f"{'FOS step MB':>11s} "
              f"{'FOS peak MB':>11s} {'loop s':>7s} {'loop step MB':>12s} {'loop peak MB':>12s}"]
    by = {(p["step"], p["n"]): p for p in points}
    for n in sorted({p["n"] for p in points}):
        fit, burg, loop = by["fit", n], by["burg", n], by.get(("loop", n))
        cross = sum(("*" in t or "^" in t) for t in fit["terms"])
        lines.append(f"{n:11,d} {fit['s']:7.3f} {fit['first_s']:7.3f} {cross:5d} {burg['s']:8.4f} "
                     f"{fit['s'] / burg['s']:8.2f} "
                     f"{fit['peak_mb'] - fit['before_mb']:11.0f} {fit['peak_mb']:11.0f} " + (
                         f"{loop['s']:7.2f} {loop['peak_mb'] - loop['before_mb']:12.0f} "
                         f"{loop['peak_mb']:12.0f}" if loop else f"{'-':>7s} {'-':>12s} {'-':>12s}"
                     ))
    slopes = _slopes(points)
    lines.append("log-log slopes against N: time FOS {:.2f}, Burg {:.2f}, loop {:.2f}; "
                 "step memory FOS {:.2f}, loop {:.2f}".format(
                     slopes["fit", "s"], slopes["burg", "s"], slopes["loop", "s"],
                     slopes["fit", "mb"], slopes["loop", "mb"]))
    top = by["fit", max(n for _, n in by)]
    lines.append(f"FOS on {top['n']:,} samples: {top['s']:.1f} s (target < {TARGETS['fit']:g} s), "
                 f"peak RSS {top['peak_mb']:.0f} MB (target < {TARGET_FIT_MB:g} MB); "
                 f"terms: {', '.join(top['terms'][:6])}, ...")
    allan, oadev, study = whole["allan"], whole["oadev"], whole["study"]
    loop = by["loop", max(n for _, n in by)]
    lines += ["", f"The whole axis ({n_day:,} samples)",
              f"Allan analysis (allan_deviation + fit_noise) {allan['s']:.1f} s "
              f"(target < {TARGETS['allan']:g} s); allantools.oadev on the same taus "
              f"{oadev['s']:.1f} s; ratio {allan['s'] / oadev['s']:.2f}; "
              f"peak RSS {allan['peak_mb']:.0f} MB",
              f"model-order study (orders 1-10, CP 1-2, all methods, both protocols) "
              f"{study['s']:.1f} s (target < {TARGETS['study']:g} s); "
              f"peak RSS {study['peak_mb']:.0f} MB",
              f"residual loop {loop['s']:.1f} s (target < {TARGETS['loop']:g} s); "
              f"peak RSS {loop['peak_mb']:.0f} MB"]
    return lines


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "--child":
        child(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    else:
        main()
