"""The six-axis workflow: every axis of an IMU record through each analysis, one report.

Every axis goes through the Allan analysis, the model-order study and the residual loop.

The Allan analysis fits all axes at once (:func:`fosmodel.noise.imu_noise.imu_noise`);
the study (:func:`fosmodel.study.runner.run_study`) and the loop
(:func:`fosmodel.loop.closeloop.close_loop`) of each axis are independent tasks, run
``n_jobs`` at a time in worker processes (joblib), each reported as it ends.  The loop
of an axis reads the record's other columns by their role (:mod:`fosmodel.loop.roles`):
the other axes of the same kind are its companions (never inputs, their correlation
with the residual is cross-axis noise), the accelerometers drive a gyro and the
temperature drives every axis.  The results are the same whatever ``n_jobs``: every step is
deterministic.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from ..core.exceptions import InputError
from ..core.parallel import in_workers
from ..core.validation import check_int, check_positive
from ..filter.allan_statespace import allan_state_space, assemble_axes, initial_covariance
from ..filter.joint_noise import JointNoise, joint_noise
from ..filter.statespace import StateSpace
from ..io.record import Record
from ..io.split import SplitSpec
from ..loop.closeloop import LoopConfig, LoopResult, close_loop, loop_split
from ..noise.axes import Axis, UnitsSpec, infer_axis, resolve_axes
from ..noise.imu_noise import ImuNoise, imu_noise
from ..noise.metrics import is_sensor_units
from ..study.harness import METHODS, StudyConfig, StudyResult, study_split
from ..study.runner import run_study

Progress = Callable[[str], None]
#: Names a temperature column goes by (a ROS bag's or a ULog's reader names it temperature).
TEMPERATURE = re.compile(r"^(die_?)?temp(erature)?(_?(c|degc|deg_c))?$", re.IGNORECASE)
STEPS = ("allan", "study", "loop")


@dataclass(frozen=True)
class ImuConfig:
    """What the six-axis workflow runs on each axis.

    Parameters
    ----------
    orders, degrees, methods, protocols
        The model-order study's grid (:class:`fosmodel.study.harness.StudyConfig`); the
        fair protocol only by default (every method on the same raw data).
    train_s, evaluate_s : float
        The study's fitting and selection segments (s); the rest is predicted.
    horizon_s, n_starts : float, int
        Outage metrics of the study (the loop judges and reports at its own horizons,
        :data:`fosmodel.loop.config.HORIZONS_S`).
    loop_split : tuple of float, optional
        Fractions of the record the loop fits on and evaluates on (default: the study's
        segments, so that both steps score on one prediction segment; :meth:`for_record`
        resolves them against a record).
    loop_max_lag : int
        L of the loop's starting model.
    min_tau : float, optional
        Shortest averaging time of the Allan fits (default: found per axis).
    inflate : float
        Factor on every exported noise value, for a moving platform
        (:mod:`fosmodel.noise.exports`; 1: the static record's values).
    n_jobs : int
        Study and loop tasks run at once (1: in this process).
    """

    orders: Sequence[int] = tuple(range(1, 11))
    degrees: Sequence[int] = (1, 2)
    methods: Sequence[str] = METHODS
    protocols: Sequence[str] = ("fair",)
    train_s: float = 180.0
    evaluate_s: float = 180.0
    horizon_s: float = 30.0
    n_starts: int = 20
    loop_split: tuple[float, float] | None = None
    loop_max_lag: int = 10
    min_tau: float | None = None
    inflate: float = 1.0
    n_jobs: int = 2

    def __post_init__(self) -> None:
        """Check every option, before any record is read.

        The study's grid, segments and outage metrics as :class:`StudyConfig` checks them
        (with the sensor and rate of any record); the loop's split and lag, the Allan fits'
        shortest tau and the number of jobs here.

        Raises
        ------
        InputError
            An option out of range; an integer option given as a float (``3.0``) or a bool.
        """
        StudyConfig(rate=1.0, sensor="gyro", units="rad/s", orders=self.orders,
                    degrees=self.degrees, methods=self.methods, protocols=self.protocols,
                    train_s=self.train_s, evaluate_s=self.evaluate_s, horizon_s=self.horizon_s,
                    n_starts=self.n_starts)
        if self.loop_split is not None:  # whether it leaves some to predict: check()
            split = tuple(self.loop_split) if isinstance(self.loop_split, Sequence) else ()
            if len(split) != 2:
                raise InputError("loop_split must be the two fractions of the record the loop "
                                 f"fits on and evaluates on, got {self.loop_split!r}")
            for fraction in split:
                check_positive(fraction, "each loop_split fraction")
        check_int(self.loop_max_lag, "loop_max_lag", 1)
        if self.min_tau is not None:
            check_positive(self.min_tau, "min_tau")
        check_int(self.n_jobs, "n_jobs", 1)

    def study_config(self, rate: float, axis: Axis) -> StudyConfig:
        """Configure the study of one axis."""
        return StudyConfig(rate=rate, sensor=axis.sensor, units=axis.units, orders=self.orders,
                           degrees=self.degrees, methods=self.methods, protocols=self.protocols,
                           train_s=self.train_s, evaluate_s=self.evaluate_s,
                           horizon_s=self.horizon_s, n_starts=self.n_starts)

    def on_record(self, n: int, rate: float, split: SplitSpec | None = None,
                  loop_split: SplitSpec | None = None) -> ImuConfig:
        """Return this configuration with splits given in seconds or percent resolved on a record.

        ``split`` sets the study's segments for a record of ``n`` samples at ``rate`` Hz
        (None: keep ``train_s`` and ``evaluate_s``), and the loop's too unless ``loop_split``
        gives its own (:data:`fosmodel.io.split.PROPORTIONAL`, the residual loop's default, is
        in proportion to the record).

        Raises
        ------
        InputError
            A split in percent that leaves nothing to predict.
        """
        config = self
        if split is not None:
            train_s, evaluate_s = split.seconds(n, rate)
            config = replace(config, train_s=train_s, evaluate_s=evaluate_s)
        if loop_split is not None:
            config = replace(config, loop_split=loop_split.fractions(n, rate))
        return config

    def for_record(self, n: int, rate: float) -> ImuConfig:
        """Return this configuration with the loop's split resolved for ``n`` samples at ``rate``.

        Without a ``loop_split`` of its own the loop takes the study's segments: ``train_s``
        and ``evaluate_s`` as fractions of the record (the same sample bounds).
        """
        if self.loop_split is not None:
            return self
        return replace(self, loop_split=(self.train_s * rate / n, self.evaluate_s * rate / n))

    def check(self, n: int, rate: float, axes: Sequence[Axis], steps: Sequence[str] = STEPS,
              at: Callable[[int], ImuConfig] | None = None) -> None:
        """Refuse, before any work, a record the steps cannot split or units they cannot take.

        ``n`` is the record's length in samples; ``steps`` are those that will run.  A record
        too short for the study or the loop is refused in one message that gives the least
        length each step needs with these settings, and why.  ``at(m)`` is the configuration
        for a record of ``m`` samples (default: this one), for splits given in percent of
        the record or in seconds before they are resolved.

        Raises
        ------
        InputError
            A record too short for the steps' splits, or a setting the configurations refuse.
        """
        if not axes:
            return
        at = at or (lambda m: self)
        axis = axes[0]  # every axis is split alike

        def study(m: int) -> None:
            study_split(m, at(m).study_config(rate, axis))

        def loop(m: int) -> None:
            config = at(m)
            if config.loop_split is None and config.train_s + config.evaluate_s >= m / rate:
                raise InputError("on the study's segments, which the record does not hold")
            loop_split(m, config.for_record(m, rate).loop_config(rate, axis))

        short = {}
        for step, check in (("study", study), ("loop", loop)):
            if step in steps:
                try:
                    check(n)
                except InputError as error:
                    short[step] = (_least_length(check, n), str(error))
        if short:
            raise InputError(_too_short(n, rate, short))
        resolved = at(n).for_record(n, rate)
        for axis in axes[1:]:  # their sensors and units
            if "study" in steps:
                resolved.study_config(rate, axis)
            if "loop" in steps:
                resolved.loop_config(rate, axis, axes)

    def loop_config(self, rate: float, axis: Axis, axes: Sequence[Axis] = ()) -> LoopConfig:
        """Configure the residual loop of one axis (of a configuration :meth:`for_record`).

        The other ``axes`` of its kind are its companions.

        Raises
        ------
        ValueError
            The loop's split is not resolved yet.
        """
        if self.loop_split is None:
            raise ValueError("the loop's split follows the study's: resolve it against the "
                             "record with for_record(n, rate)")
        return LoopConfig(rate=rate, sensor=axis.sensor, units=axis.units,
                          max_lag=self.loop_max_lag, train=self.loop_split[0],
                          evaluate=self.loop_split[1],
                          companions=tuple(a.column for a in axes if a.sensor == axis.sensor
                                           and a.column != axis.column))


def _least_length(check: Callable[[int], object], n: int) -> int | None:
    """Return the fewest samples above ``n`` that ``check`` takes, or None if no length does.

    ``check(m)`` raises InputError for a record of ``m`` samples too short; a longer record
    passes whenever a shorter one does.
    """
    def fits(m: int) -> bool:
        try:
            check(m)
        except InputError:
            return False
        return True

    low, high = n, max(2 * n, 2)
    while not fits(high):
        if high > 2**40:  # some segment is too short whatever the record's length
            return None
        low, high = high, 2 * high
    while high - low > 1:  # low fails, high fits
        mid = (low + high) // 2
        low, high = (low, mid) if fits(mid) else (mid, high)
    return high


def _too_short(n: int, rate: float, short: Mapping[str, tuple[int | None, str]]) -> str:
    """Say in one message how long a record the settings need, each step's need and why."""
    least = [m for m, _ in short.values()]
    needs = "; ".join(
        f"the {step} " + ("cannot run with these settings, whatever the record's length"
                          if m is None else f"needs {m / rate:.6g} s")
        + f" ({_RECORD.sub('', why)})" for step, (m, why) in short.items())
    head = (f"the record has {n} samples ({n / rate:.6g} s at {rate:g} Hz), too short for "
            "these settings")
    if None in least:  # a segment too short for its windows: a longer record cannot help
        return (f"{head}: {needs}; change train_s= and evaluate_s= (the loop's: loop_split=) "
                "or horizon_s=")
    head += f", which need at least {max(m for m in least if m) / rate:.6g} s"
    return (f"{head}: {needs}; shorten train_s= and evaluate_s= (the loop's: loop_split=) or "
            "horizon_s=, or give a longer record")


#: The record's length at the head of a step's own message (the message above says it once).
_RECORD = re.compile(r"^the record has \d+ samples \([^)]*\); |^the record \([^)]*\) is too "
                     r"short for ")


@dataclass
class AxisResult:
    """One axis through every step, with each step's run time (s)."""

    axis: Axis
    study: StudyResult
    loop: LoopResult
    seconds: dict[str, float] = field(default_factory=dict)


@dataclass
class ImuResult:
    """The workflow's results: the noise of every axis, and each axis's study and loop."""

    source: str
    rate: float
    n_samples: int
    config: ImuConfig
    noise: ImuNoise
    axes: list[AxisResult]
    aux: list[str]
    allan_seconds: float
    joint: JointNoise | None = None

    def study_table(self) -> pd.DataFrame:
        """Tabulate per axis the best FOS and the best baseline of the study.

        Both are chosen on the evaluation segment; their errors are on the prediction segment.
        """
        return pd.DataFrame([study_row(a.axis, a.study) for a in self.axes])

    def loop_table(self) -> pd.DataFrame:
        """Tabulate per axis the effects the loop kept and the errors before and after them.

        The errors are on the prediction segment.
        """
        return pd.DataFrame([loop_row(a.axis, a.loop) for a in self.axes])

    def timing_table(self) -> pd.DataFrame:
        """Run time of each step per axis (s); the Allan fits ran on all axes at once."""
        return pd.DataFrame([{"axis": a.axis.column, **{f"{k} (s)": round(v, 2) for k, v in
                                                        a.seconds.items()}} for a in self.axes])

    def filter_model(self) -> StateSpace:
        """Return the axes' Allan error models as one block-diagonal shaping filter.

        Each axis has white noise, a Gauss-Markov and a random-walk bias, at the record's rate
        (:func:`fosmodel.filter.allan_statespace.assemble_axes`).
        """
        return assemble_axes({a.axis.column: allan_state_space(a.fit) for a in self.noise.axes})

    def filter_dict(self) -> dict[str, Any]:
        """:meth:`filter_model` with its initial covariance, as JSON-ready lists."""
        model = self.filter_model()
        return {"source": self.source, "rate_hz": self.rate,
                "axes": [a.axis.column for a in self.noise.axes],
                "units": {a.axis.column: a.axis.units for a in self.noise.axes},
                **model.to_dict(), "P0": initial_covariance(model, self.n_samples).tolist()}

    def to_dict(self) -> dict[str, Any]:
        """Every table of the report as records, and the noise parameters."""
        return {"source": self.source, "rate_hz": self.rate, "n_samples": self.n_samples,
                "aux": self.aux, "noise": self.noise.to_dict(self.config.inflate),
                "study": _records(self.study_table()), "loop": _records(self.loop_table()),
                "loops": {a.axis.column: a.loop.to_json_dict() for a in self.axes}}


def record_axes(
    rec: Record, columns: Sequence[str] | None = None, units: UnitsSpec | None = None,
    temperature: str | None = None,
) -> tuple[list[Axis], dict[str, np.ndarray]]:
    """Return a record's axes and the auxiliary channel (a temperature) its loops may use.

    Parameters
    ----------
    rec : Record
    columns : sequence of str, optional
        The axes, each ``COLUMN`` or ``COLUMN:SENSOR:UNITS`` (default: every column whose
        name or file tells a gyro or an accelerometer, or whose units ``units`` gives).
    units : UnitsSpec, optional
        Units given for every column or per column.
    temperature : str, optional
        The temperature column (default: a column named like ``temperature``, ``temp``,
        ``temp_c``, if any).

    Raises
    ------
    InputError
        No column tells a gyro or an accelerometer and none is named, or an axis whose sensor
        or units cannot be told (:func:`fosmodel.noise.axes.resolve_axes`).
    """
    temperature = temperature or next((c for c in rec.names if TEMPERATURE.match(c)), None)
    specs = list(columns or [c for c in rec.names if c != temperature and (
        infer_axis(c)[0] or is_sensor_units(rec.units.get(c, ""))
        or (units and c in units.columns))])
    if not specs:
        raise InputError(f"{rec.source}: no column tells a gyro or an accelerometer by its name "
                         f"(columns: {', '.join(rec.names)}); name the axes and give their units")
    axes = resolve_axes(specs, given=units, declared=rec.units)
    return axes, ({temperature: rec.column(temperature)} if temperature else {})


def run_imu(
    columns: Mapping[str, np.ndarray], axes: Sequence[Axis], rate: float, source: str = "",
    *, aux: Mapping[str, np.ndarray] | None = None, config: ImuConfig | None = None,
    progress: Progress | None = None,
) -> ImuResult:
    """Run the Allan analysis, the model-order study and the residual loop on every axis.

    Parameters
    ----------
    columns : mapping of str to ndarray
        The rate signals by column name (each axis's ``column`` in it), of equal length.
    axes : sequence of Axis
        The columns with their sensors and units (:func:`fosmodel.noise.axes.resolve_axes`).
    rate : float
        Sample rate in Hz.
    source : str
        Where the record came from.
    aux : mapping of str to ndarray, optional
        Further channels (a temperature) the loop may use besides the other axes.
    config : ImuConfig, optional
    progress : callable, optional
        Called with one line as each step of each axis ends.

    Returns
    -------
    ImuResult

    Raises
    ------
    InputError
        No axis, an axis missing from ``columns``, columns of unequal length, or a record
        too short for the study's or the loop's split (before any work).
    """
    say = progress or (lambda line: None)
    _check(columns, axes, aux or {})
    n = len(columns[axes[0].column])
    config = config or ImuConfig()
    config.check(n, rate, axes)
    config = config.for_record(n, rate)
    start = time.perf_counter()
    noise = imu_noise(columns, axes, rate, source, min_tau=config.min_tau)
    joint = joint_noise(columns, noise) if len(axes) > 1 else None
    allan_s = time.perf_counter() - start
    say(f"allan: {len(axes)} axes in {allan_s:.1f} s")
    channels = {**{a.column: columns[a.column] for a in axes}, **(aux or {})}
    done: dict[tuple[str, str], tuple[Any, float]] = {}
    for (column, step), outcome, seconds in _run_tasks(channels, axes, rate, config):
        done[column, step] = outcome, seconds
        say(f"{step}: {column} in {seconds:.1f} s ({_brief(step, outcome)}); "
            f"{len(done)}/{2 * len(axes)} tasks done")
    results = [AxisResult(a, done[a.column, "study"][0], done[a.column, "loop"][0],
                          {"study": done[a.column, "study"][1],
                           "loop": done[a.column, "loop"][1]}) for a in axes]
    return ImuResult(source, float(rate), n, config, noise, results, sorted(aux or {}), allan_s,
                     joint)


def _check(columns: Mapping[str, np.ndarray], axes: Sequence[Axis],
           aux: Mapping[str, np.ndarray]) -> None:
    if not axes:
        raise InputError("no axis to analyse")
    missing = [a.column for a in axes if a.column not in columns]
    if missing:
        raise InputError(f"no column {', '.join(map(repr, missing))} among the signals given")
    lengths = {name: len(x) for name, x in
               [*((a.column, columns[a.column]) for a in axes), *aux.items()]}
    if len(set(lengths.values())) > 1:
        raise InputError("the columns differ in length: "
                         + ", ".join(f"{k} {v}" for k, v in lengths.items()))


def _task(step: str, column: str, channels: Mapping[str, np.ndarray], axis: Axis,
          axes: Sequence[Axis], rate: float,
          config: ImuConfig) -> tuple[tuple[str, str], Any, float]:
    """One step of one axis (a worker process runs it); returns its key, result and time."""
    start = time.perf_counter()
    y = channels[column]
    if step == "study":
        outcome: Any = run_study(y, config.study_config(rate, axis))
    else:
        others = {k: v for k, v in channels.items() if k != column}
        outcome = close_loop(y, others, config.loop_config(rate, axis, axes))
    return (column, step), outcome, time.perf_counter() - start


def _run_tasks(channels: Mapping[str, np.ndarray], axes: Sequence[Axis], rate: float,
               config: ImuConfig) -> Iterator[tuple[tuple[str, str], Any, float]]:
    """Run the study and the loop of every axis, longest first; yield them as they end."""
    tasks = [(_task, (step, a.column, channels, a, axes, rate, config))
             for step in ("loop", "study") for a in axes]
    yield from in_workers(tasks, config.n_jobs, ordered=False)


def _brief(step: str, outcome: StudyResult | LoopResult) -> str:
    if isinstance(outcome, StudyResult):
        return f"{len(outcome.rows)} fits"
    kept = [s.effect.describe() for s in outcome.steps]
    return f"{len(kept)} effect(s) kept"


def _best(rows: pd.DataFrame, fos: bool) -> tuple[pd.Series | None, str]:
    """Return the stable row with the lowest evaluation MSE among FOS's forms or the baselines'.

    An unstable model (its free runs diverge, their errors NaN) is never the best, however low
    its one-step error.  With no row, ``(None, "not studied")`` (``methods`` without FOS, or
    FOS alone); with no stable one, ``(None, "none stable")``.
    """
    is_fos = rows["method"].str.startswith("fos")
    pick = rows[is_fos if fos else ~is_fos]
    if pick.empty:
        return None, "not studied"
    if "stable" in pick:
        pick = pick[pick["stable"].astype(bool)]
    if pick.empty:
        return None, "none stable"
    row = pick.loc[pick["evaluate_mse"].idxmin()]
    return row, f"{row['label']} L={row['order']}"


def study_row(axis: Axis, study: StudyResult) -> dict[str, Any]:
    """Tabulate the best FOS and the best baseline of an axis's study (a row of the tables).

    A side the study did not run (FOS alone, or baselines alone) is ``not studied``, its
    errors and the ratio NaN: the columns are the same whatever the methods.
    """
    rows = study.rows[study.rows["protocol"] == "fair"] if "fair" in \
        study.config.protocols else study.rows
    (fos, fos_name), (base, base_name) = _best(rows, True), _best(rows, False)
    outage, bias = study_columns(study.config.horizon_s)
    return {"axis": axis.column, "units": axis.units,
            "FOS": fos_name,
            f"FOS {outage}": _value(fos, "outage_position_error_m"),
            f"FOS {bias}": _value(fos, "bias_rms_30s"),
            "best baseline": base_name,
            f"baseline {outage}": _value(base, "outage_position_error_m"),
            f"baseline {bias}": _value(base, "bias_rms_30s"),
            "FOS / baseline (outage)": _value(fos, "outage_position_error_m")
            / _value(base, "outage_position_error_m")}


def study_columns(horizon_s: float) -> tuple[str, str]:
    """Return the names of the outage error and bias columns of :func:`study_row`.

    They end each table's FOS and baseline heads; the outage horizon is the study's.
    """
    return f"outage error (m, {horizon_s:g} s)", "one-step bias RMS 30 s"


def _value(row: pd.Series | None, key: str) -> float:
    return np.nan if row is None else float(row[key])


def loop_row(axis: Axis, loop: LoopResult) -> dict[str, Any]:
    """Tabulate the effects an axis's loop kept and its errors before and after them.

    The errors at 30 s outages, and its largest cross-axis correlation.
    """
    before, after = loop.before, loop.after
    strongest = max(loop.cross_axis, key=lambda c: abs(c["rho"]), default=None)
    return {"axis": axis.column, "units": axis.units,
            "effects kept": len(loop.steps),
            "kept": "; ".join(s.effect.describe() for s in loop.steps) or "none",
            # NaN where the prediction segment holds too few 30 s windows to report them
            "30 s outage error before (m)": _number(before["outage_position_error_m"].get("30")),
            "30 s outage error after (m)": _number(after["outage_position_error_m"].get("30")),
            "30 s free-run bias RMS before": _number(before["bias_rms"].get("30")),
            "30 s free-run bias RMS after": _number(after["bias_rms"].get("30")),
            "cross-axis noise (largest)": "none" if strongest is None else
            f"{strongest['channel']} {strongest['rho']:+.3f}",
            "still firing": ", ".join(loop.unexplained) or "none",
            "worse on prediction": "; ".join(loop.worse()) or "none"}


def _number(value: float | None) -> float:
    return float("nan") if value is None else float(value)


def _records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    return [{k: (v.item() if hasattr(v, "item") else v) for k, v in row.items()}
            for row in frame.to_dict(orient="records")]
