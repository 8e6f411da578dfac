"""Command line: ``fosmodel fit | predict | study | close-loop | allan | synth | demo``.

Exit codes: 0 success, 2 bad input or usage (one-line message on stderr),
1 internal error (with a hint to report it; ``--verbose`` shows the traceback).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import logging
import math
import re
import sys
import traceback
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple, NoReturn

import numpy as np
import pandas as pd

from ._version import __version__
from .core.candidates import count_candidates
from .core.exceptions import InputError
from .core.fos import STOP_RULES
from .core.levels import levels_for
from .io.loader import OUTLIER_K, OUTLIER_MODES, Record, load_record, parse_scales
from .io.output import atomic_write, refuse_overwrite, report_directory, write_text
from .models.model import FOSModel

if TYPE_CHECKING:
    from .study.harness import StudyPlan, StudyResult

log = logging.getLogger("fosmodel")


def _exog_arg(text: str) -> tuple[str, int]:
    name, sep, lag = text.partition(":")
    if not sep or not name or not lag.isdigit():
        raise argparse.ArgumentTypeError(f"expected NAME:K (e.g. temp:5), got {text!r}")
    return name, int(lag)


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def _levels_arg(text: str) -> list[float] | str:
    """``auto`` or comma-separated positive time constants in seconds."""
    if text == "auto":
        return text
    try:
        values = [float(part) for part in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(np.isfinite(v) and v > 0 for v in values):
        raise argparse.ArgumentTypeError(f"expected 'auto' or time constants in seconds like "
                                         f"5,20, got {text!r}")
    return values


def _int_list(text: str) -> list[int]:
    """``1-10`` or ``1,2,5`` or ``1-3,8`` -> a list of integers."""
    out = []
    for part in text.split(","):
        lo, sep, hi = part.strip().partition("-")
        try:
            out.extend(range(int(lo), int(hi) + 1) if sep else [int(lo)])
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected integers like 1-10 or 1,2,5, got {text!r}"
                                             ) from None
    return out


def _name_list(text: str) -> list[str]:
    return [p.strip() for p in text.split(",") if p.strip()]


def _split_arg(text: str) -> tuple[float, float]:
    try:
        train, evaluate = (float(p) for p in text.split(","))
    except ValueError:
        train = evaluate = math.nan
    if not (math.isfinite(train) and math.isfinite(evaluate)):
        raise argparse.ArgumentTypeError(f"expected TRAIN_S,EVALUATE_S, two finite seconds (e.g. "
                                         f"180,180), got {text!r}")
    return train, evaluate


def _out_path(path: str) -> Path:
    out = Path(path)
    if not out.parent.is_dir():
        raise InputError(f"cannot write {out}: directory {out.parent} does not exist")
    if out.is_dir():
        raise InputError(f"cannot write {out}: it is a directory")
    return out


def _out_dir(path: str) -> Path:
    """The output directory of a report: created on success, so it must not be a file."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise InputError(f"cannot write a report into {out}: it is a file, not a directory")
    return out


def _load(args: argparse.Namespace, path: str | None = None,
          columns: list[str] | None = None) -> Record:
    """The record of ``path`` (default ``args.file``) with the loader options.

    Only ``columns`` (default: all) are read and checked.  Its notes go to
    stderr, after the file's name when ``path`` is given.
    """
    rec = load_record(path or args.file, columns=columns, rate=args.rate,
                      scale=parse_scales(args.scale or []), uniform=args.uniform,
                      outliers=args.outliers, gaps=args.gaps)
    for note in rec.notes:
        print(f"fosmodel: note: {path + ': ' if path else ''}{note}", file=sys.stderr)
    return rec


def _add_loader_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--rate", type=_positive_float,
                        help="sample rate in Hz (if no time column)")
    parser.add_argument("--scale", action="append", metavar="NAME=FACTOR",
                        help="multiply column NAME by FACTOR, e.g. gx=1/131 for raw counts "
                             "(repeatable)")
    parser.add_argument("--uniform", action="store_true",
                        help="take the samples as uniformly spaced at the time column's "
                             "effective rate (a host's bursty receive time)")
    parser.add_argument("--outliers", choices=OUTLIER_MODES, default="keep",
                        help=f"outliers (|x - median| > {OUTLIER_K:g} x 1.4826 MAD): keep (report, "
                             "default), clip or drop")
    gaps = parser.add_mutually_exclusive_group()
    gaps.add_argument("--fill", dest="gaps", action="store_const", const="fill",
                      help="fill gaps of the time column by linear interpolation")
    gaps.add_argument("--segments", dest="gaps", action="store_const", const="segments",
                      help="keep gaps and use the contiguous segments (fit and predict)")
    parser.set_defaults(gaps="refuse")


def _cmd_fit(args: argparse.Namespace) -> int:
    out = _out_path(args.out)
    refuse_overwrite({"--out": out}, {"the record": args.file})
    exog_lags = dict(args.exog or [])
    if args.column in exog_lags:
        raise InputError(f"--exog {args.column}:{exog_lags[args.column]}: the modelled column "
                         "cannot be its own input (its lag 0 is the value predicted; its past "
                         "is in --max-lag)")
    rec = _load(args, columns=[args.column, *exog_lags])
    y = rec.column(args.column)
    levels = args.levels
    if levels == "auto":
        levels = list(levels_for(y, rec.require_rate()))
        print("levels offered (below the Allan floor): "
              + ", ".join(f"{t:g} s" for t in levels))
    model = FOSModel(max_lag=args.max_lag, degree=args.degree, exog_lags=exog_lags,
                     levels=levels, rate=rec.require_rate() if levels else None,
                     max_terms=args.max_terms, stop=args.stop, tol=args.tol,
                     max_candidates=args.max_candidates)
    spec = model._spec()
    print(f"candidates: {count_candidates(spec)} (L={spec.max_lag}, CP={spec.degree}"
          + "".join(f", {k}:0-{v}" for k, v in exog_lags.items()) + ")")
    exog = {name: rec.column(name) for name in exog_lags}
    model.fit(pd.Series(y, name=args.column), exog, segments=rec.segments)
    print(model.summary())
    meta = {"source": rec.source, "column": args.column, "rate_hz": rec.rate,
            "n_samples": rec.n_samples}
    write_text(out, json.dumps(model.to_dict(meta), indent=2) + "\n")
    print(f"model written to {out}")
    return 0


def _read_model(path: str) -> FOSModel:
    """The model saved in ``path``, checked down to its numbers and the column it names."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(f"cannot read model {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a model file (not UTF-8 text)") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not a model file (invalid JSON at line {exc.lineno})") from None
    except (ValueError, RecursionError) as exc:  # a number of 4300+ digits, nesting too deep
        raise InputError(f"{path}: not a model file ({exc})") from None
    try:
        model = FOSModel.from_dict(data)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    except (AttributeError, TypeError, ValueError, OverflowError) as exc:  # e.g. terms of numbers
        raise InputError(f"{path}: corrupted model file: {type(exc).__name__}: {exc}") from None
    _check_model(model, path)
    return model


def _check_model(model: FOSModel, path: str) -> None:
    """Refuse a model whose weights are not finite or whose source column is not a name."""
    numbers = [*model.coef_, model.intercept_, *model.offsets_.values()]
    if not np.isfinite(numbers).all():
        raise InputError(f"{path}: corrupted model file: a weight or offset is not a finite "
                         "number")
    column = model.meta_.get("column")
    if column is not None and not isinstance(column, str):
        raise InputError(f"{path}: corrupted model file: meta.column {column!r} is not a column "
                         "name")


def _cmd_predict(args: argparse.Namespace) -> int:
    out = _out_path(args.out)
    refuse_overwrite({"--out": out}, {"the record": args.file, "the model": args.model})
    model = _read_model(args.model)
    column = args.column or model.meta_.get("column")
    if not column:
        raise InputError("the model does not say which column it models; pass --column")
    inputs = model.input_columns()
    rec = _load(args, columns=[column, *inputs])
    y = rec.column(column)
    channels = {name: rec.column(name) for name in inputs}
    pred = model.predict(y, channels, segments=rec.segments)
    resid = (y - pred)[~np.isnan(pred)]  # NaN over the lag window of each segment
    if not resid.size:
        pieces = f" in {len(rec.segments)} segments" if rec.segments else ""
        raise InputError(f"{rec.source}: record too short: {rec.n_samples} samples{pieces}, but "
                         f"the model's lag window needs {model.lag_window_} before the first "
                         "prediction")
    frame = pd.DataFrame({column: y, "prediction": pred, "residual": y - pred})
    if rec.time is not None:
        frame.insert(0, "time", rec.time)
    with atomic_write(out) as fh:
        frame.to_csv(fh, index=False, float_format="%.10g")
    mse = float(np.mean(resid**2))
    print(f"one-step prediction of {column!r} on {rec.source}: {resid.size} samples, MSE {mse:.6g}")
    print(f"predictions written to {out}")
    return 0


class _SensorRecord(NamedTuple):
    """One column of one file in a study, with its plan and the name of its report."""

    file: str
    column: str
    name: str
    plan: StudyPlan


_COMPRESSED = (".gz", ".bz2", ".xz")


def _report_name(path: str, column: str) -> str:
    """``imu1_gx`` for column gx of ``imu1.csv(.gz)``: the subdirectory of its report."""
    p = Path(path)
    stem = Path(p.stem).stem if p.suffix in _COMPRESSED else p.stem
    return re.sub(r"[^\w.-]+", "_", f"{stem}_{column}")


def _check_report_names(files: list[str], columns: list[str]) -> None:
    """Refuse, before any work, two records whose reports would share a directory."""
    if not columns:
        raise InputError("no column given; pass --columns COL[,COL...]")
    seen: dict[str, tuple[str, str]] = {}
    for path in files:
        for column in columns:
            name = _report_name(path, column)
            if name in seen:
                raise InputError(f"{seen[name][0]} column {seen[name][1]!r} and {path} column "
                                 f"{column!r} would both be reported in {name}/; give each "
                                 "file a distinct name")
            seen[name] = (path, column)


def _study_records(args: argparse.Namespace, path: str) -> list[_SensorRecord]:
    """The records of the file ``path``, one per column, each checked and planned."""
    from .study.harness import StudyConfig, plan_study

    rec = _load(args, path, columns=args.columns)
    rec.require_contiguous("the model-order study")
    protocols = ["paper", "fair"] if args.protocol == "both" else [args.protocol]
    config = StudyConfig(
        rate=rec.require_rate(), sensor=args.sensor, units=args.units, orders=args.orders,
        degrees=args.degrees, methods=args.methods, protocols=protocols, train_s=args.split[0],
        evaluate_s=args.split[1], horizon_s=args.horizon, n_starts=args.starts,
        paper_denoise=args.denoise, fos_stop=args.stop, levels=not args.no_levels,
    )
    records = []
    for column in args.columns:
        y = rec.column(column)
        try:
            plan = plan_study(y, config)
        except InputError as exc:
            raise InputError(f"{path}, column {column!r}: {exc}") from None
        records.append(_SensorRecord(path, column, _report_name(path, column), plan))
    return records


def _check_dask(args: argparse.Namespace) -> None:
    """Refuse ``--scheduler``/``--workers`` before any work when the extra is missing."""
    if args.scheduler or args.workers:
        try:
            importlib.import_module(".study.distributed", __package__)
        except ImportError as exc:
            flag = "--scheduler" if args.scheduler else "--workers"
            raise InputError(f"{flag}: {exc}") from None


def _dask_client(args: argparse.Namespace) -> contextlib.AbstractContextManager:
    """The Dask client of ``--scheduler`` or ``--workers``; none (this process) without them."""
    if args.scheduler:
        from .study.distributed import connect

        return connect(args.scheduler, args.connect_timeout)
    if args.workers:
        from .study.distributed import local_client

        return local_client(args.workers)
    return contextlib.nullcontext()


def _cmd_study(args: argparse.Namespace) -> int:
    from .study.runner import run_studies

    _check_dask(args)
    json_path = _out_path(args.json) if args.json else None
    out = _out_dir(args.out)
    refuse_overwrite({"--json": json_path}, {f"the record {i + 1}": f
                                             for i, f in enumerate(args.files)})
    _check_report_names(args.files, args.columns)
    records = [record for path in args.files for record in _study_records(args, path)]
    with _dask_client(args) as client:
        results = run_studies([r.plan for r in records], client=client,
                              progress=sys.stderr.isatty())
    _write_study_reports(records, results, out, args.title, args.files)
    _print_studies(records, results)
    if json_path:
        write_text(json_path, json.dumps(_studies_json(records, results), indent=1) + "\n")
    fits = sum(len(result.rows) for result in results)
    count = "" if len(records) == 1 else f"{len(records)} records, "
    print(f"study of {count}{fits} fits written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else ""))
    return 0


def _title(record: _SensorRecord, title: str | None, single: bool) -> str:
    """``--title`` for a lone record; before the record's own title when there are several."""
    own = f"{record.column} of {Path(record.file).name}"
    if single:
        return title or own
    return f"{title}: {own}" if title else own


def _write_study_reports(records: list[_SensorRecord], results: list[StudyResult], out: Path,
                         title: str | None, inputs: list[str]) -> None:
    """One record's report in ``out``; several in a directory each and their best rows.

    Everything is written to a directory beside ``out`` first, then moved into
    place, so a failure leaves ``out`` as it was (:func:`report_directory`).
    """
    from .study.report import write_study, write_tables

    single = len(records) == 1
    with report_directory(out, inputs) as tmp:
        for record, result in zip(records, results):
            write_study(result, tmp if single else tmp / record.name,
                        _title(record, title, single))
        if not single:
            write_tables(_combined_best(records, results), tmp, "best")


def _combined_best(records: list[_SensorRecord], results: list[StudyResult]) -> pd.DataFrame:
    """Every record's best rows in one table, led by its report's name, file and column."""
    from .study.report import study_table

    lead = ["Record", "File", "Column"]
    frame = pd.concat([study_table(result, result.best()).assign(
        Record=record.name, File=record.file, Column=record.column)
        for record, result in zip(records, results)], ignore_index=True)
    return frame[lead + [c for c in frame.columns if c not in lead]]


def _print_studies(records: list[_SensorRecord], results: list[StudyResult]) -> None:
    """The comparison table of one record, or the main columns of every record's best rows."""
    from .study.report import paper_table

    single = len(records) == 1
    if single:
        table = paper_table(results[0])
    else:
        table = _combined_best(records, results)
        table = table[[c for c in table.columns if c in ("Record", "Protocol", "Method", "Data",
                                                         "Order L")
                       or c.startswith(("MSE", "Outage position"))]]
    print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    for record, result in zip(records, results):
        for note in result.warnings:
            print(f"fosmodel: warning: {'' if single else record.name + ': '}{note}",
                  file=sys.stderr)


def _studies_json(records: list[_SensorRecord], results: list[StudyResult]) -> dict:
    """One record's study as ``StudyResult.to_json_dict``; several as a list of those."""
    if len(records) == 1:
        return results[0].to_json_dict()
    return {"records": [{"file": record.file, "column": record.column, "report": record.name,
                         **result.to_json_dict()} for record, result in zip(records, results)]}


def _fractions(text: str) -> tuple[float, float]:
    try:
        train, evaluate = (float(p) for p in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected TRAIN,EVALUATE fractions (e.g. 0.5,0.2), "
                                         f"got {text!r}") from None
    return train, evaluate


def _cmd_close_loop(args: argparse.Namespace) -> int:
    from .loop.closeloop import LoopConfig, close_loop
    from .loop.loop_report import effects_table, write_loop_report

    json_path = _out_path(args.json) if args.json else None
    model_path = _out_path(args.model) if args.model else None
    out = _out_dir(args.out)
    refuse_overwrite({"--json": json_path, "--model": model_path}, {"the record": args.file})
    if args.aux is not None and args.column in args.aux:
        raise InputError(f"--aux {args.column}: the modelled column cannot explain its own "
                         "residual (its lag 0 is the value predicted)")
    rec = _load(args, columns=None if args.aux is None else [args.column, *args.aux])
    rec.require_contiguous("the residual loop")
    y = rec.column(args.column)
    aux = args.aux if args.aux is not None else [c for c in rec.names if c != args.column]
    channels = {name: rec.column(name) for name in aux}
    config = LoopConfig(rate=rec.require_rate(), sensor=args.sensor, units=args.units,
                        max_lag=args.max_lag, train=args.split[0], evaluate=args.split[1])
    result = close_loop(y, channels, config,
                        progress=lambda line: print(f"fosmodel: {line}", file=sys.stderr,
                                                    flush=True))
    with report_directory(out, [args.file]) as tmp:
        write_loop_report(result, tmp, args.title or f"{args.column} of {Path(args.file).name}")
    if model_path:
        meta = {"source": rec.source, "column": args.column, "rate_hz": rec.rate,
                "n_samples": rec.n_samples, "fitted_on": "close-loop fitting segment",
                "effects": [step.effect.describe() for step in result.steps]}
        write_text(model_path, json.dumps(result.final_model.model.to_dict(meta), indent=2)
                   + "\n")
    print(effects_table(result).drop(columns=["Evidence"]).to_string(
        index=False, float_format=lambda v: f"{v:.4g}"))
    if result.unexplained:
        print(f"still firing, with no effect that survives: {', '.join(result.unexplained)}")
    if json_path:
        write_text(json_path, json.dumps(result.to_json_dict(), indent=1) + "\n")
    print(f"residual loop report written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else "")
          + (f"; final model written to {model_path}" if model_path else ""))
    return 0


def _cmd_allan(args: argparse.Namespace) -> int:
    if args.columns:
        return _cmd_allan_axes(args)
    if args.gyro_units or args.accel_units:
        raise InputError("--gyro-units and --accel-units go with --columns; give --sensor and "
                         "--units with --column")
    from .noise.allan import allan_deviation, fit_noise, write_allan

    json_path = _out_path(args.json) if args.json else None
    out = _out_dir(args.out)
    refuse_overwrite({"--json": json_path}, {"the record": args.file})
    rec = _load(args, columns=[args.column])
    rec.require_contiguous("the Allan deviation")
    y = rec.column(args.column)
    result = allan_deviation(y, rec.require_rate(), units=args.units, sensor=args.sensor)
    fit = fit_noise(result, min_tau=args.min_tau)
    with report_directory(out, [args.file]) as tmp:
        write_allan(result, fit, tmp, args.title or f"{args.column} of {Path(args.file).name}")
    print(fit.summary())
    misses = fit.misses()
    if misses:
        tau, ratio = misses[0]
        print(f"warning: the IEEE Std 952 fit misses the measured Allan deviation beyond its "
              f"95 % interval at {len(misses)} averaging time(s) (fit/data {ratio:.2f} "
              f"at tau = {tau:.3g} s first); see the figure's lower panel", file=sys.stderr)
    if json_path:
        data = {"source": rec.source, "column": args.column, "allan": result.to_dict(),
                "noise": fit.to_dict()}
        write_text(json_path, json.dumps(data, indent=1) + "\n")
    print(f"Allan variance report written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else ""))
    return 0


def _cmd_allan_axes(args: argparse.Namespace) -> int:
    from .noise.imu_noise import imu_noise, resolve_axes, write_imu_noise

    if args.sensor or args.units:
        raise InputError("--sensor and --units go with --column; with --columns give "
                         "COLUMN:SENSOR:UNITS or --gyro-units/--accel-units")
    json_path = _out_path(args.json) if args.json else None
    out = _out_dir(args.out)
    refuse_overwrite({"--json": json_path}, {"the record": args.file})
    units = {s: u for s, u in (("gyro", args.gyro_units), ("accel", args.accel_units)) if u}
    axes = resolve_axes(args.columns, units)
    rec = _load(args, columns=[a.column for a in axes])
    rec.require_contiguous("the Allan deviation")
    for axis in axes:
        print(f"fosmodel: {axis.describe()}", file=sys.stderr)
    noise = imu_noise({a.column: rec.column(a.column) for a in axes}, axes, rec.require_rate(),
                      rec.source, min_tau=args.min_tau)
    with report_directory(out, [args.file]) as tmp:
        write_imu_noise(noise, tmp, args.title or Path(args.file).name)
    print(noise.summary())
    for a in noise.axes:
        if a.fit.misses():
            print(f"warning: {a.axis.column}: the IEEE Std 952 fit misses the measured Allan "
                  "deviation beyond its 95 % interval; see its figure's lower panel",
                  file=sys.stderr)
    if json_path:
        write_text(json_path, json.dumps(noise.to_dict(), indent=1) + "\n")
    print(f"Allan noise report of {len(axes)} axes written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else ""))
    return 0


def _cmd_synth(args: argparse.Namespace) -> int:
    from data_synth.cli import run

    return run(args)


def _cmd_demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    run_demo(Path(args.out))
    return 0


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors take one line, like every other error."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"fosmodel: error: {message} ({self.prog} --help shows the usage)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="fosmodel",
        description="Fast Orthogonal Search error models for MEMS inertial sensors.",
    )
    parser.add_argument("--version", action="version", version=f"fosmodel {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log details and tracebacks")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    fit = sub.add_parser("fit", help="fit a FOS model to one column of a record")
    fit.add_argument("file", help="CSV, .npy or .parquet record")
    fit.add_argument("--column", required=True, help="column to model")
    _add_loader_options(fit)
    fit.add_argument("--max-lag", type=int, default=10, help="L, output lags 1..L (default 10)")
    fit.add_argument("--degree", type=int, default=1, help="CP, cross-product degree (default 1)")
    fit.add_argument("--exog", type=_exog_arg, action="append", metavar="NAME:K",
                     help="exogenous column NAME with lags 0..K (repeatable)")
    fit.add_argument("--max-terms", type=int, help="most terms besides the constant")
    fit.add_argument("--stop", choices=STOP_RULES, default="korenberg", help="stopping rule")
    fit.add_argument("--tol", type=float, help="fraction for --stop variance / mean_square")
    fit.add_argument("--levels", type=_levels_arg, metavar="auto|T1,T2,...",
                     help="local levels of the output to offer: their time constants in "
                          "seconds, or 'auto' for a grid below the record's Allan floor")
    fit.add_argument("--max-candidates", type=_positive_int, default=100_000,
                     help="refuse a candidate set larger than this (default 100000)")
    fit.add_argument("--out", required=True, help="model file to write (JSON)")
    fit.set_defaults(func=_cmd_fit)

    pred = sub.add_parser("predict", help="one-step-ahead prediction with a saved model")
    pred.add_argument("file", help="CSV, .npy or .parquet record")
    pred.add_argument("--model", required=True, help="model file written by 'fosmodel fit'")
    pred.add_argument("--column", help="column to predict (default: the one the model was fit on)")
    _add_loader_options(pred)
    pred.add_argument("--out", required=True, help="CSV to write")
    pred.set_defaults(func=_cmd_predict)

    study = sub.add_parser("study", help="model-order study: every method, order and degree")
    study.add_argument("files", nargs="+", metavar="FILE",
                       help="CSV, .npy or .parquet records; with several files or columns, "
                            "a report directory per file and column")
    study.add_argument("--columns", "--column", dest="columns", type=_name_list, required=True,
                       metavar="COL[,COL...]", help="columns to model, in every file")
    _add_loader_options(study)
    study.add_argument("--sensor", required=True, choices=("accel", "gyro"))
    study.add_argument("--units", required=True,
                       help="units of the column: m/s^2, g, mg (accel); rad/s, deg/s, deg/h (gyro)")
    study.add_argument("--orders", type=_int_list, default=list(range(1, 11)),
                       help="model orders, e.g. 1-10 (default) or 1,2,5")
    study.add_argument("--degrees", type=_int_list, default=[1, 2],
                       help="FOS cross-product degrees (default 1,2)")
    study.add_argument("--methods", type=_name_list, default=["fos", "yw", "cov", "burg", "gm"],
                       help="comma-separated among fos,yw,cov,burg,gm (default all)")
    study.add_argument("--protocol", choices=("paper", "fair", "both"), default="both")
    study.add_argument("--no-levels", action="store_true",
                       help="leave out the methods about the local level (fair protocol)")
    study.add_argument("--split", type=_split_arg, default=(180.0, 180.0),
                       help="training and evaluation seconds (default 180,180)")
    study.add_argument("--horizon", type=_positive_float, default=30.0,
                       help="outage horizon in seconds (default 30)")
    study.add_argument("--starts", type=int, default=20, help="outage starts (default 20)")
    study.add_argument("--denoise", choices=("wavelet", "kaiser"), default="wavelet",
                       help="denoiser of the baselines under the paper protocol")
    study.add_argument("--stop", choices=STOP_RULES, default="korenberg", help="FOS stopping rule")
    study.add_argument("--title", help="title of the report")
    study.add_argument("--out", required=True, help="output directory (created)")
    study.add_argument("--json", help="also write every row and the best rows as JSON")
    dask = study.add_mutually_exclusive_group()
    dask.add_argument("--scheduler", metavar="ADDRESS",
                      help="run the fits on the Dask cluster of this scheduler "
                           "(e.g. tcp://10.0.0.5:8786)")
    dask.add_argument("--workers", type=_positive_int, metavar="N",
                      help="run the fits on a local Dask cluster of N single-threaded processes")
    study.add_argument("--connect-timeout", type=_positive_float, default=10.0, metavar="S",
                       help="seconds to wait for --scheduler (default 10)")
    study.set_defaults(func=_cmd_study)

    loop = sub.add_parser("close-loop", help="find what the model lacks in its residual, "
                          "add it, report the error before and after")
    loop.add_argument("file", help="CSV, .npy or .parquet record")
    loop.add_argument("--column", required=True, help="column to model")
    _add_loader_options(loop)
    loop.add_argument("--aux", nargs="+", metavar="COL",
                      help="columns that may explain the residual (default: every other column)")
    loop.add_argument("--sensor", choices=("accel", "gyro"), help="for position errors")
    loop.add_argument("--units", help="units of the column (with --sensor)")
    loop.add_argument("--max-lag", type=int, default=10, help="L of the starting model")
    loop.add_argument("--split", type=_fractions, default=(0.5, 0.2),
                      help="fractions for fitting and evaluation (default 0.5,0.2)")
    loop.add_argument("--title", help="title of the report")
    loop.add_argument("--out", required=True, help="output directory (created)")
    loop.add_argument("--json", help="also write the before/after metrics and effects as JSON")
    loop.add_argument("--model", help="also write the final model as JSON (as 'fosmodel fit' "
                                      "does), for 'fosmodel predict' and a filter")
    loop.set_defaults(func=_cmd_close_loop)

    allan = sub.add_parser("allan", help="Allan deviation with confidence intervals and the "
                           "IEEE Std 952 noise coefficients")
    allan.add_argument("file", help="CSV, .npy or .parquet record")
    which = allan.add_mutually_exclusive_group(required=True)
    which.add_argument("--column", help="column to analyse (a rate signal)")
    which.add_argument("--columns", type=_name_list, metavar="COL[:SENSOR:UNITS],...",
                       help="several axes in one run, e.g. gx,gy,gz,ax,ay,az: one table, one "
                            "figure per sensor, Kalibr/MATLAB/JSON exports; the sensor and "
                            "units come from the names (gx_dps, acc_y_mps2) where not given")
    _add_loader_options(allan)
    allan.add_argument("--sensor", choices=("accel", "gyro"),
                       help="sensor of --column, for navigation units")
    allan.add_argument("--units", help="units of --column (with --sensor)")
    allan.add_argument("--gyro-units", metavar="UNITS",
                       help="units of the gyro columns of --columns (rad/s, deg/s, deg/h)")
    allan.add_argument("--accel-units", metavar="UNITS",
                       help="units of the accelerometer columns of --columns (m/s^2, g, mg)")
    allan.add_argument("--min-tau", type=_positive_float,
                       help="shortest averaging time fitted, in s (default: found from the "
                            "curve, leaving out taus bent by the sensor's own filtering)")
    allan.add_argument("--title", help="title of the figure")
    allan.add_argument("--out", required=True, help="output directory (created)")
    allan.add_argument("--json", help="also write the Allan deviation and coefficients as JSON")
    allan.set_defaults(func=_cmd_allan)

    from data_synth.cli import configure_parser

    synth = sub.add_parser("synth", help="write a synthetic record with its ground truth")
    configure_parser(synth).set_defaults(func=_cmd_synth)

    demo = sub.add_parser("demo", help="the main job on embedded synthetic data")
    demo.add_argument("--out", default="fosmodel-out",
                      help="output directory (default ./fosmodel-out)")
    demo.set_defaults(func=_cmd_demo)
    return parser


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """A warning as the command line shows it: one line, like its notes and errors."""
    return f"fosmodel: warning: {' '.join(str(message).split())}\n"


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    shown, warnings.formatwarning = warnings.formatwarning, _one_line_warning
    try:
        return _run(args)
    finally:
        warnings.formatwarning = shown


def _run(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="fosmodel: %(message)s", stream=sys.stderr)
    try:
        return args.func(args)
    except InputError as exc:
        print(f"fosmodel: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fosmodel: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug: say so, briefly, and how to get details
        if args.verbose:
            traceback.print_exc()
        print(f"fosmodel: internal error: {type(exc).__name__}: {' '.join(str(exc).split())} "
              "(this is a bug; please report it with the command you ran; "
              "--verbose shows the traceback)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
