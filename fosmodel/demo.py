"""``fosmodel demo``: the main job, on embedded data, with no network and no arguments.

1. Tamazin et al.'s (2013) model-order study on two seeded, paper-like one-hour 200 Hz
   records (accelerometer-Y in m/s^2, gyro-Y in deg/h, from :mod:`data_synth`):
   orders 1-10, FOS at CP 1 and 2, Yule-Walker, covariance, Burg and
   Gauss-Markov, under the paper protocol (baselines on wavelet-denoised data)
   and the fair one (everything raw); the two comparison tables are printed in
   the layout of the paper's Tables 1 and 2.
2. The same study on the real MPU-6050 record bundled with the package (one
   gyroscope and one accelerometer axis), and the residual loop on each of its
   six axes, the other five offered as explanatory channels.

Every table, figure and report is written under the output directory.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pandas as pd

from .io.output import report_directory
from .io.samples import load_mpu6050_static
from .loop.closeloop import LoopConfig, close_loop
from .loop.loop_report import write_loop_report
from .study.harness import StudyConfig, StudyResult
from .study.report import paper_table, table_orders, write_study
from .study.runner import run_study

__all__ = ["run_demo"]

SEED = 2013
RECORDS: dict[str, tuple[int, str, dict[str, Any], str, str]] = {
    # table number, scenario, its overrides (make_scenario's keywords), sensor, units
    "accelerometer": (1, "paper_accel_y", {}, "accel", "m/s^2"),
    "gyroscope": (2, "paper_gyro_y", {"units": "deg/h"}, "gyro", "deg/h"),
}
MPU_AXES = {"ax": ("accel", "g"), "ay": ("accel", "g"), "az": ("accel", "g"),
            "gx": ("gyro", "deg/s"), "gy": ("gyro", "deg/s"), "gz": ("gyro", "deg/s")}
MPU_STUDY = ("gx", "ay")


def _print_table(title: str, result: StudyResult) -> None:
    print(f"\n{title}, orders {' and '.join(map(str, table_orders(result)))}")
    print(paper_table(result).to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    for note in result.warnings:
        print(f"warning: {note}")


def run_paper_records(out_dir: Path) -> dict[str, StudyResult]:
    """Part 1: the model-order study on the two paper-like synthetic records."""
    from data_synth import make_scenario

    results = {}
    for name, (number, scenario, overrides, sensor, units) in RECORDS.items():
        rec = make_scenario(scenario, seed=SEED, **overrides)
        config = StudyConfig(rate=rec.rate, sensor=sensor, units=units)
        print(f"\n{name}: {scenario} (seed {SEED}), {rec.n_samples} samples at {rec.rate:g} Hz, "
              f"{config.units}; {len(config.configurations())} configurations x "
              f"{len(config.protocols)} protocols", flush=True)
        result = run_study(rec.columns[rec.target], config, progress=sys.stderr.isatty())
        title = f"{name} ({scenario}, seed {SEED})"
        write_study(result, out_dir / name, title)
        _print_table(f"Table {number}: {title}", result)
        results[name] = result
    return results


def run_bundled_record(out_dir: Path) -> pd.DataFrame:
    """Part 2: the study and the residual loop on the bundled MPU-6050 record."""
    rec = load_mpu6050_static()
    print(f"\nMPU-6050 record bundled with fosmodel (MIT licence): {rec.n_samples} samples at "
          f"{rec.rate:g} Hz, {', '.join(rec.names)}", flush=True)
    base = out_dir / "mpu6050"
    for column in MPU_STUDY:
        sensor, units = MPU_AXES[column]
        result = run_study(rec.column(column), StudyConfig(rate=rec.require_rate(),
                                                           sensor=sensor, units=units))
        title = f"MPU-6050 {column} ({units})"
        write_study(result, base / f"study_{column}", title)
        _print_table(title, result)
    rows = []
    for axis, (sensor, units) in MPU_AXES.items():
        others = {c: rec.column(c) for c in rec.names if c != axis}
        loop = close_loop(rec.column(axis), others,
                          LoopConfig(rate=rec.require_rate(), sensor=sensor, units=units))
        write_loop_report(loop, base / f"loop_{axis}", f"MPU-6050 {axis} ({units})")
        rows.append({"axis": axis, "units": units,
                     "effects kept": "; ".join(s.effect.describe() for s in loop.steps) or "none",
                     "still firing": ", ".join(loop.unexplained) or "none",
                     "one-step MSE before": loop.before.mse,
                     "one-step MSE after": loop.after.mse,
                     "30 s outage position error before (m)":
                         loop.before.outage_position_error_m.get(30),
                     "30 s outage position error after (m)":
                         loop.after.outage_position_error_m.get(30)})
    table = pd.DataFrame(rows)
    print("\nResidual loop on each axis of the MPU-6050 record (prediction segment):")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    return table


def run_demo(out_dir: Path) -> dict[str, StudyResult]:
    """Run both parts and say where everything went.

    Everything is written beside ``out_dir`` and moved onto it at the end
    (:func:`fosmodel.io.output.report_directory`): an interrupted demo leaves
    ``out_dir`` as it was.
    """
    with report_directory(out_dir) as staging:
        results = run_paper_records(staging)
        run_bundled_record(staging)
    print(f"\noutputs written to {out_dir.resolve()}/ (report.md, tables and figures per record)")
    return results
