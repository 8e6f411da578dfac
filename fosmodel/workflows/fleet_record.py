"""A record of a fleet: the task that runs the chosen steps on it and publishes its folder.

:func:`run_record` reads one record, runs the chosen steps of the six-axis workflow on its axes
(as :func:`fosmodel.workflows.imu.run_imu` runs them with one job), and publishes its folder of
the store (:mod:`fosmodel.workflows.fleet`) in one rename, with the completion marker inside:
the record's rows of the summary, the marker (:func:`fingerprint`: the file and the settings;
each step's time; the static stretch kept and the columns skipped) and, if asked, its reports.
The record is checked first (:func:`fosmodel.noise.checks.check_record`): one that moves is
refused, or with ``static_only`` cut to its longest static stretch.  BLAS is limited to one
thread in the task, so that it gives the same bits in this process and on any worker.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from ..filter.joint_noise import joint_noise
from ..io.content import settle
from ..io.formats import SUFFIXES
from ..io.loader import load_record
from ..io.output import report_directory
from ..io.record import Record
from ..io.split import SplitSpec
from ..loop.closeloop import LoopResult, close_loop
from ..noise.axes import Axis, UnitsSpec
from ..noise.checks import check_record, unused_columns
from ..noise.imu_noise import ImuNoise, imu_noise
from ..study.harness import StudyResult
from ..study.runner import run_study
from .imu import (
    STEPS,
    TEMPERATURE,
    AxisResult,
    ImuConfig,
    ImuResult,
    loop_row,
    record_axes,
    study_row,
)

_T = TypeVar("_T")

#: The completion marker of a record's folder in the store.
MARKER = "done.json"


@dataclass(frozen=True)
class FleetConfig:
    """What every record of a fleet goes through, and how it is read.

    Parameters
    ----------
    imu : ImuConfig
        The steps' settings (its ``n_jobs`` is not used: the records are the tasks).
    steps : tuple of str
        Among ``"allan"``, ``"study"``, ``"loop"``; all three by default.
    split, loop_split : SplitSpec, optional
        The study's and the loop's segments, resolved against each record (default: those
        of ``imu``).
    columns : tuple of str, optional
        The axes, ``COL`` or ``COL:SENSOR:UNITS`` (default: every column whose name or file
        tells a gyro or an accelerometer).
    units : UnitsSpec, optional
        Units of every column or per column.
    temperature : str, optional
        A column the loop may use (default: one named temperature, temp or temp_c, if any).
    load : mapping
        Keyword options of :func:`fosmodel.io.loader.load_record` (rate, gaps, topic...).
    reports : bool
        Also write each record's reports (tables and figures) into its folder.
    static_only : bool
        Analyse the longest static stretch of a record that moves, instead of refusing it
        (:func:`fosmodel.noise.checks.check_record`).
    """

    imu: ImuConfig = field(default_factory=lambda: ImuConfig(n_jobs=1))
    steps: tuple[str, ...] = STEPS
    split: SplitSpec | None = None
    loop_split: SplitSpec | None = None
    columns: tuple[str, ...] | None = None
    units: UnitsSpec | None = None
    temperature: str | None = None
    load: Mapping[str, Any] = field(default_factory=dict)
    reports: bool = False
    static_only: bool = False


def record_name(path: str | os.PathLike[str]) -> str:
    """Return a record's name in the store: its file name without the format's suffixes.

    Those are its format's and its compression's (:data:`fosmodel.io.formats.SUFFIXES`).
    """
    name = Path(path).name
    while Path(name).suffix.lower() in SUFFIXES and Path(name).stem:
        name = Path(name).stem
    return name


def fingerprint(path: str | os.PathLike[str], config: FleetConfig) -> str:
    """Say what a record's results depend on: its file (path, size, time) and the config."""
    stat = Path(path).stat()
    settings = replace(config, imu=replace(config.imu, n_jobs=1))  # jobs change no result
    return json.dumps({"file": str(Path(path).resolve()), "size": stat.st_size,
                       "mtime_ns": stat.st_mtime_ns, "config": repr(settings)})


def run_record(path: str | os.PathLike[str], store: str | os.PathLike[str],
               config: FleetConfig) -> float:
    """Run the chosen steps on one record and publish its folder in ``store`` (the task).

    Returns
    -------
    float
        The task's time (s), also in the record's marker.
    """
    start = time.perf_counter()
    name = record_name(path)
    folder = Path(store) / name
    with threadpool_limits(limits=1, user_api="blas"):  # the same bits in any process
        rec = load_record(Path(path), **config.load, hold=True)  # every column: its temperature
        axes, aux = record_axes(rec, config.columns, config.units, config.temperature)
        held = [c for c in rec.held if c == config.temperature  # a driver, though held
                or (config.temperature is None and TEMPERATURE.match(c))]
        rec = settle(rec, [*(a.column for a in axes), *aux, *held])  # the others noted, left out
        rec, stretch = check_record(rec, axes, config.static_only)
        aux = {name: rec.column(name) for name in aux}  # the static stretch's, if one was kept
        skipped = unused_columns(rec.names, [*(a.column for a in axes), *aux],
                                 named=config.columns is not None)
        outcome = _steps(rec, axes, aux, config)
        rows = _rows(name, outcome)
        if folder.exists():  # another file's or configuration's results
            shutil.rmtree(folder)
        with report_directory(folder) as tmp:
            rows.to_csv(tmp / "rows.csv", index=False)
            if config.reports:
                _reports(outcome, tmp / "report", name)
            seconds = {**outcome.seconds, "total": time.perf_counter() - start}
            marker = {"record": name, "fingerprint": fingerprint(path, config),
                      "n_samples": rec.n_samples, "rate_hz": rec.require_rate(),
                      "axes": [a.column for a in axes], "steps": list(config.steps),
                      "static_stretch": stretch,
                      "skipped": [f"{column}: {why}" for column, why in skipped],
                      "seconds": seconds}
            (tmp / MARKER).write_text(json.dumps(marker, indent=1) + "\n")
    return seconds["total"]


@dataclass
class _Outcome:
    """A record through the chosen steps: the noise of its axes, each axis's study and loop."""

    rec: Record
    axes: list[Axis]
    aux: dict[str, np.ndarray]
    imu: ImuConfig
    noise: ImuNoise | None = None
    study: dict[str, StudyResult] = field(default_factory=dict)
    loop: dict[str, LoopResult] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)  # each step's, over the axes
    axis_seconds: dict[str, dict[str, float]] = field(default_factory=dict)  # by axis, step

    def timed(self, step: str, column: str, work: Callable[[], _T]) -> _T:
        """Run one axis's step, adding its time to the step's and the axis's."""
        clock = time.perf_counter()
        result = work()
        seconds = time.perf_counter() - clock
        self.seconds[step] = self.seconds.get(step, 0.0) + seconds
        self.axis_seconds.setdefault(column, {})[step] = seconds
        return result


def _steps(rec: Record, axes: list[Axis], aux: dict[str, np.ndarray],
           config: FleetConfig) -> _Outcome:
    """Run the chosen steps on every axis, as the six-axis workflow does with one job."""
    rate, n = rec.require_rate(), rec.n_samples
    at = partial(_imu_at, config, rate=rate)
    at(n).check(n, rate, axes, config.steps, at=at)  # one message if the record is too short
    imu = at(n).for_record(n, rate)  # the loop on the study's segments, unless given its own
    columns = {a.column: rec.column(a.column) for a in axes}
    channels = {**columns, **aux}
    out = _Outcome(rec, axes, aux, imu)
    if "allan" in config.steps:
        clock = time.perf_counter()
        out.noise = imu_noise(columns, axes, rate, rec.source, min_tau=imu.min_tau)
        out.seconds["allan"] = time.perf_counter() - clock
    for a in axes if "study" in config.steps else ():
        out.study[a.column] = out.timed("study", a.column, partial(
            run_study, columns[a.column], imu.study_config(rate, a)))
    for a in axes if "loop" in config.steps else ():
        others = {k: v for k, v in channels.items() if k != a.column}
        out.loop[a.column] = out.timed("loop", a.column, partial(
            close_loop, columns[a.column], others, imu.loop_config(rate, a, axes)))
    return out


def _imu_at(config: FleetConfig, n: int, rate: float) -> ImuConfig:
    """Return the steps' settings for a record of ``n`` samples: the splits resolved on it.

    Raises
    ------
    InputError
        A split in percent that leaves nothing to predict.
    """
    return replace(config.imu, n_jobs=1).on_record(n, rate, config.split, config.loop_split)


def _rows(name: str, outcome: _Outcome) -> pd.DataFrame:
    """Tabulate the record's rows of the summary: each axis's noise terms, study, loop."""
    noise = ({r["Column"]: r for r in outcome.noise.table().to_dict(orient="records")}
             if outcome.noise else {})
    rows = []
    for a in outcome.axes:
        row: dict[str, Any] = {"record": name, "axis": a.column, "sensor": a.sensor,
                               "units": a.units}
        if noise:
            row.update({k: noise[a.column][k] for k in ("N fitted", "B fitted", "K fitted")})
        if outcome.study:
            row.update(_without_axis(study_row(a, outcome.study[a.column])))
        if outcome.loop:
            row.update(_without_axis(loop_row(a, outcome.loop[a.column])))
        rows.append(row)
    return pd.DataFrame(rows)


def _without_axis(row: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in row.items() if k not in ("axis", "units")}


def _reports(outcome: _Outcome, out_dir: Path, name: str) -> None:
    """Write the record's reports: the six-axis report with every step, else each step's."""
    from .imu_report import report_parts, write_imu_report  # drawing: only with reports

    out_dir.mkdir()
    rec, axes = outcome.rec, outcome.axes
    if outcome.noise and outcome.study and outcome.loop:
        result = ImuResult(rec.source, rec.require_rate(), rec.n_samples, outcome.imu,
                           outcome.noise, [AxisResult(a, outcome.study[a.column],
                                                      outcome.loop[a.column],
                                                      outcome.axis_seconds[a.column])
                                           for a in axes],
                           sorted(outcome.aux), outcome.seconds["allan"],
                           joint_noise({a.column: rec.column(a.column) for a in axes},
                                       outcome.noise) if len(axes) > 1 else None)
        write_imu_report(result, out_dir, name)
        return
    for write, args in report_parts(out_dir, name, axes, outcome.noise, outcome.study,
                                    outcome.loop, outcome.imu.inflate):
        write(*args)
