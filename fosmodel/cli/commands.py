"""One short function per command, each over public library functions.

A command checks its outputs before it reads anything (no output may name an input),
reads only the columns it uses, imports only the modules it uses (the models, SciPy and
scikit-learn inside the functions that need them), and writes every file atomically; its
errors are
:class:`~fosmodel.core.exceptions.InputError`, which :func:`fosmodel.cli.main` prints in
one line with exit code 2.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.exceptions import InputError, OptionError
from ..io.loader import Record, load_record, parse_scales
from ..io.output import (
    atomic_write,
    refuse_overwrite,
    report_directory,
    writable_directory,
    writable_file,
    write_text,
)
from ..noise.axes import SENSORS, Axis, column_sensor, resolve_axes
from .flags import with_flags

if TYPE_CHECKING:
    from ..loop.config import LoopConfig
    from ..loop.handoff import Handoff
    from ..loop.outcome import LoopOutcome
    from ..loop.rounds import Progress
    from ..models.model import FOSModel


def _load(args: argparse.Namespace, path: str | None = None,
          columns: list[str] | None = None, notes: bool = True,
          analysed: Sequence[str] | Callable[[Record], Sequence[str]] | None = None,
          feeds: str = "", drivers: Sequence[str] = ()) -> Record:
    """Load the record of ``path`` (default ``args.file``) with the loader options.

    Only ``columns`` (default: all) are read and checked.  Its ``analysed`` columns (the
    modelled ones and the model's drivers; or a function of the record that names them;
    default ``columns``) are refused on their content, the others the loader held left out
    with a note (:func:`fosmodel.io.content.settle`; ``feeds`` says what they would have
    fed).  Its notes go to stderr, after the file's name when ``path`` is given, unless not
    ``notes`` (:func:`_checked` says them after its checks).  With ``--start``/``--stop``
    only that stretch is kept (:meth:`Record.between`), and a note says so.
    """
    from ..io.content import settle

    rec = load_record(path or args.file, columns=columns, rate=args.rate,
                      scale=parse_scales(args.scale or []), uniform=args.uniform,
                      outliers=args.outliers, gaps=args.gaps, topic=args.topic,
                      temperature_topic=args.temperature_topic, hold=True)
    window = (vars(args).get("window_start"), vars(args).get("window_stop"))
    if window != (None, None):  # the stretch asked for, before any analysis; its name says it
        rec = rec.between(*window)
        rec.source += window_label(args)
    analysed = analysed if analysed is not None else columns
    rec = settle(rec, (analysed(rec) if callable(analysed) else analysed
                       if analysed is not None else [*rec.names, *rec.held]), feeds,
                 drivers)
    if notes:
        for note in rec.notes:
            print(f"fosmodel: note: {path + ': ' if path else ''}{with_flags(note)}",
                  file=sys.stderr)
    return rec


def window_label(args: argparse.Namespace) -> str:
    """Say the stretch ``--start``/``--stop`` keep (`` from 60 s to 300 s``), or ``""``."""
    start, stop = vars(args).get("window_start"), vars(args).get("window_stop")
    if start is None and stop is None:
        return ""
    return f" from {start or 0:g} s" + (f" to {stop:g} s" if stop is not None else " to its end")


def _checked(args: argparse.Namespace, rec: Record, axes: list[Axis]) -> Record:
    """Check the record's units and stillness (:func:`~fosmodel.noise.checks.check_record`).

    Return it, or its longest static stretch with ``--static-only``; then say the loader's
    notes (a refused record gets its one line and nothing else), after the stretch kept, and
    the hints on the axes kept (:func:`~fosmodel.noise.hints.record_hints`).
    """
    from ..noise.checks import check_record

    kept, stretch = check_record(rec, axes, args.static_only)
    if stretch:
        print(f"fosmodel: note: {stretch}", file=sys.stderr)
    for note in rec.notes:
        print(f"fosmodel: note: {'(the whole file) ' if stretch else ''}{with_flags(note)}",
              file=sys.stderr)
    if axes:
        from ..noise.hints import record_hints

        columns = {a.column: kept.column(a.column) for a in axes}
        for hint in record_hints(columns, axes, kept.require_rate()):
            print(f"fosmodel: hint: {hint}", file=sys.stderr)
    return kept


def _axes(args: argparse.Namespace, columns: list[str], rec: Record,
          optional: bool = False) -> list[Axis]:
    """Resolve each column's sensor and units (:func:`~fosmodel.noise.axes.resolve_axes`).

    From --units, the file, --sensor, --gyro-units/--accel-units or its name (``gz_dps``,
    ``Accel X (g)``), as every command reads them; none if ``optional`` and none is told.
    """
    per_sensor = {s: units for s in SENSORS if (units := vars(args).get(f"{s}_units"))}
    return resolve_axes(columns, per_sensor, given=args.units, declared=rec.units,
                        sensor=args.sensor, optional=optional)


def fit(args: argparse.Namespace) -> int:
    import pandas as pd

    from ..core.candidates import count_candidates
    from ..core.levels import levels_for
    from ..io.model_file import write_model
    from ..models.model import FOSModel

    out = writable_file(args.out)
    refuse_overwrite({"--out": out}, {f"the record {i + 1}": f for i, f in enumerate(args.files)})
    exog_lags = dict(args.exog or [])
    if args.column in exog_lags:
        raise InputError(f"--exog {args.column}:{exog_lags[args.column]}: the modelled column "
                         "cannot be its own input (its lag 0 is the value predicted; its past "
                         "is in --max-lag)")
    args.file = args.files[0]  # a single record's notes are not prefixed with its name
    recs = [_load(args, path if len(args.files) > 1 else None, columns=[args.column, *exog_lags])
            for path in args.files]
    y = recs[0].column(args.column)
    levels = args.levels
    if levels == "auto":
        levels = list(levels_for(y, recs[0].require_rate()))
        print("levels offered (below the Allan floor): "
              + ", ".join(f"{t:g} s" for t in levels))
    model = FOSModel(max_lag=args.max_lag, degree=args.degree, exog_lags=exog_lags,
                     levels=levels, rate=recs[0].require_rate() if levels else None,
                     max_terms=args.max_terms, stop=args.stop, tol=args.tol,
                     max_candidates=args.max_candidates)
    spec = model.candidate_spec()
    print(f"candidates: {count_candidates(spec)} (L={spec.max_lag}, CP={spec.degree}"
          + "".join(f", {k}:0-{v}" for k, v in exog_lags.items()) + ")")
    meta: dict = {"column": args.column, "rate_hz": recs[0].rate}
    if len(recs) == 1:
        rec = recs[0]
        model.fit(pd.Series(y, name=args.column), {n: rec.column(n) for n in exog_lags},
                  segments=rec.segments)
        meta.update(source=rec.source, n_samples=rec.n_samples)
    else:
        model, constants = _fit_sessions(model, recs, args.column, exog_lags)
        meta.update(_sessions_meta(recs, constants))
    print(model.summary())
    write_model(out, model, meta)
    print(f"model written to {out}")
    return 0


def _fit_sessions(model: FOSModel, recs: list[Record], column: str,
                  inputs: dict[str, int]) -> tuple[FOSModel, list[float]]:
    """Fit ``model`` on several records of one sensor, each contiguous and at the same rate.

    :func:`fosmodel.models.sessions.fit_sessions`.
    """
    from ..models.sessions import fit_sessions

    rates = {rec.require_rate() for rec in recs}
    if len(rates) > 1:
        raise InputError("the sessions' rates differ: " + ", ".join(
            f"{rec.source} {rec.rate:g} Hz" for rec in recs))
    gapped = [rec.source for rec in recs if rec.segments]
    if gapped:
        raise InputError(f"{gapped[0]}: a session must be contiguous; pass --fill to "
                         "interpolate across its gaps")
    return fit_sessions(model, [rec.column(column) for rec in recs],
                        [{n: rec.column(n) for n in inputs} for rec in recs])


def _sessions_meta(recs: list[Record], constants: list[float]) -> dict:
    """Return the meta of a model shared by sessions: each session and its own constant."""
    return {"source": [rec.source for rec in recs],
            "n_samples": [rec.n_samples for rec in recs],
            "sessions": [{"source": rec.source, "constant": c}
                         for rec, c in zip(recs, constants)],
            "constant": "the model's constant is the mean session's; each session's own is its "
                        "constant plus the session's, and a new session's is the model's one-step "
                        "residual over its first minutes with the output held at its mean "
                        "(fosmodel.models.sessions.session_constant)"}


def predict(args: argparse.Namespace) -> int:
    import numpy as np
    import pandas as pd

    from ..io.model_file import read_model

    out = writable_file(args.out)
    refuse_overwrite({"--out": out}, {"the record": args.file, "the model": args.model})
    model = read_model(args.model)
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


def _check_dask(args: argparse.Namespace) -> None:
    """Refuse ``--scheduler``/``--workers`` before any work when the extra is missing."""
    if args.scheduler or args.workers:
        try:
            importlib.import_module("fosmodel.study.distributed")
        except ImportError as exc:
            flag = "--scheduler" if args.scheduler else "--workers"
            raise InputError(f"{flag}: {exc}") from None


def study(args: argparse.Namespace) -> int:
    from ..study.files import (
        check_report_names,
        overview,
        plan_columns,
        studies_json,
        write_reports,
    )
    from ..study.harness import StudyConfig
    from ..study.runner import dask_client, run_studies

    _check_dask(args)
    json_path = writable_file(args.json) if args.json else None
    out = writable_directory(args.out)
    refuse_overwrite({"--json": json_path}, {f"the record {i + 1}": f
                                             for i, f in enumerate(args.files)})
    columns = [spec.partition(":")[0] for spec in args.columns]  # COL or COL:SENSOR:UNITS
    check_report_names(args.files, columns)
    settings = dict(orders=args.orders, degrees=args.degrees, methods=args.methods,
                    protocols=["paper", "fair"] if args.protocol == "both" else [args.protocol],
                    horizon_s=args.horizon, n_starts=args.starts, paper_denoise=args.denoise,
                    fos_stop=args.stop, levels=not args.no_levels)
    studies = []
    for path in args.files:
        rec = _load(args, path, columns=columns)
        axes = _axes(args, args.columns, rec)
        train_s, evaluate_s = args.split.seconds(rec.n_samples, rec.require_rate())
        studies += plan_columns(rec, path, {a.column: StudyConfig(
            rate=rec.require_rate(), sensor=a.sensor, units=a.units, train_s=train_s,
            evaluate_s=evaluate_s, **settings) for a in axes})
    with dask_client(args.scheduler, args.workers, args.connect_timeout) as client:
        results = run_studies([s.plan for s in studies], client=client,
                              progress=sys.stderr.isatty())
    write_reports(studies, results, out, args.title, args.files)
    print(overview(studies, results).to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    for s, result in zip(studies, results):
        for note in result.warnings:
            print(f"fosmodel: warning: {'' if len(studies) == 1 else s.name + ': '}{note}",
                  file=sys.stderr)
    if json_path:
        write_text(json_path, json.dumps(studies_json(studies, results), indent=1) + "\n")
    fits = sum(len(result.rows) for result in results)
    count = "" if len(studies) == 1 else f"{len(studies)} records, "
    print(f"study of {count}{fits} fits written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else ""))
    return 0


#: The command line's flag of each loop option its messages may name.
LOOP_FLAGS = {"horizons_s": "--horizons", "train": "--split", "evaluate": "--split",
              "aux": "--aux", "max_lag": "--max-lag", "units": "--units"}


def close_loop(args: argparse.Namespace) -> int:
    from ..loop.closeloop import LoopConfig
    from ..loop.closeloop import close_loop as run_loop
    from ..loop.handoff import hand_off
    from ..loop.loop_report import CONSOLE_WIDTH, console_summary, write_loop_report
    from ..loop.roles import channel_roles

    json_path = writable_file(args.json) if args.json else None
    model_path = writable_file(args.model) if args.model else None
    out = writable_directory(args.out)
    refuse_overwrite({"--json": json_path, "--model": model_path},
                     {f"the record {i + 1}": f for i, f in enumerate(args.files)})
    several = len(args.files) > 1
    args.file = args.files[0]  # a single record's notes are not prefixed with its name

    drivers: list[str] = []  # of the record being loaded

    def analysed(r: Record) -> list[str]:
        """Name the modelled column, the drivers of its slow forms and the inputs asked for.

        A column of no numbers (booleans, text) is no driver, and an inertial axis (a
        companion; a gyro's accelerometers, offered in their fast part only) is not
        analysed: a refusal of one becomes a note, and it is left out.
        """
        # a column held for a bad cell (an empty one, a word) may still be a driver; one
        # that holds no numbers at all (booleans, text) is none
        held = [n for n, why in r.held.items() if f"column {n!r} holds " not in why]
        names = [n for n in [*r.names, *held] if n != args.column]
        try:
            axis = _axes(args, [args.column], r, optional=True)
            sensor = axis[0].sensor if axis else column_sensor(args.column, r.units)
            roles = channel_roles(names, sensor, aux=args.aux or (), sensors={
                c: s for c in names if (s := column_sensor(c, r.units))})
        except (InputError, OptionError):  # said by the checks below
            return [args.column]
        drivers[:] = [*roles.slow, *roles.opted_in]
        return [args.column, *drivers]

    recs = [_load(args, path if several else None, analysed=analysed,
                  feeds="the loop's cross-axis table and fast inputs",
                  drivers=drivers) for path in args.files]
    rec = recs[0]
    axis = _axes(args, [args.column], rec, optional=True)
    channels = [{name: r.column(name) for name in r.names if name != args.column}
                for r in recs]
    sensor = axis[0].sensor if axis else column_sensor(args.column, rec.units)
    if args.column in (args.aux or ()):
        raise InputError(f"--aux {args.column}: the modelled column cannot explain its own "
                         "residual")
    train, evaluate = args.split.fractions(min(r.n_samples for r in recs), rec.require_rate())
    try:
        roles = channel_roles(channels[0], sensor, aux=args.aux or (), sensors={
            c: s for c in channels[0] if (s := column_sensor(c, rec.units))})
        config = LoopConfig(rate=rec.require_rate(), sensor=axis[0].sensor if axis else None,
                            units=axis[0].units if axis else None, max_lag=args.max_lag,
                            train=train, evaluate=evaluate, horizons_s=args.horizons,
                            companions=roles.companions, aux=roles.opted_in)
    except OptionError as exc:
        raise InputError(exc.with_flag(LOOP_FLAGS)) from None
    say = lambda line: print(  # noqa: E731
        textwrap.fill(f"fosmodel: {line}", CONSOLE_WIDTH, subsequent_indent="fosmodel:     "),
        file=sys.stderr, flush=True)
    title = args.title or (f"{args.column} of " + ", ".join(Path(f).name for f in args.files)
                           + window_label(args))
    if several:
        return _close_sessions(args, recs, channels, config, say, title, out, json_path,
                               model_path)
    result = run_loop(rec.column(args.column), channels[0], config, progress=say)
    handoff = hand_off(result, rec.column(args.column), channels[0], sensor=config.sensor,
                       units=config.units, column=args.column)
    meta = {"source": rec.source, "column": args.column, "rate_hz": rec.rate,
            "n_samples": rec.n_samples,
            "fitted_on": "all the record; structure chosen on the close-loop segments"}

    def write_report(tmp: Path) -> None:
        write_loop_report(result, tmp, title)
        handoff.write(tmp / "filter", {"source": rec.source, "column": args.column})
        handoff.append_to(tmp / "report.md")

    return _loop_outputs(args, result, write_report, console_summary(result), meta, out,
                         json_path, model_path, ("residual loop report", "final model"),
                         handoff)


def _loop_outputs(args: argparse.Namespace, result: LoopOutcome,
                  write_report: Callable[[Path], object], console: str, meta: dict,
                  out: Path, json_path: Path | None, model_path: Path | None,
                  names: tuple[str, str], handoff: Handoff | None = None) -> int:
    """Write a loop's report, model and JSON, and say where: one record's or the sessions'.

    ``names`` are what the last line calls the report and the model; with ``handoff`` the
    model is its refit on all the data, and the JSON gains its ``"filter"`` entry.
    """
    from ..io.model_file import write_model

    with report_directory(out, args.files) as tmp:
        write_report(tmp)
    if model_path:
        bound, which = result.handed_on()
        meta = {**meta, "effects": [step.effect.describe() for step in result.steps],
                "model": which}
        write_model(model_path, handoff.final if handoff else bound.model, meta)
    print(console)
    if json_path:
        found = result.to_json_dict()
        if handoff is not None:
            found["filter"] = handoff.to_dict()
        write_text(json_path, json.dumps(found, indent=1) + "\n")
    print(f"{names[0]} written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else "")
          + (f"; {names[1]} written to {model_path}" if model_path else ""))
    return 0


def _close_sessions(args: argparse.Namespace, recs: list[Record], channels: list[dict],
                    config: LoopConfig, say: Progress, title: str, out: Path,
                    json_path: Path | None, model_path: Path | None) -> int:
    """``close-loop A B C``: the loop over sessions, its report, JSON and shared model."""
    from ..loop.sessions import Session, close_sessions
    from ..loop.sessions_report import sessions_console, write_sessions_report

    rates = {r.require_rate() for r in recs}
    if len(rates) > 1:
        raise InputError("the sessions' rates differ: " + ", ".join(
            f"{r.source} {r.rate:g} Hz" for r in recs))
    sessions = [Session(r.column(args.column), ch, Path(f).stem)
                for r, ch, f in zip(recs, channels, args.files)]
    result = close_sessions(sessions, config, progress=say)
    meta = {"column": args.column, "rate_hz": recs[0].rate,
            "fitted_on": "close-loop deciding parts of every session",
            **_sessions_meta(recs, result.constants)}
    return _loop_outputs(args, result, lambda tmp: write_sessions_report(result, tmp, title),
                         sessions_console(result), meta, out, json_path, model_path,
                         (f"residual loop report of {len(recs)} sessions", "shared model"))


def allan(args: argparse.Namespace) -> int:
    json_path = writable_file(args.json, created=args.out) if args.json else None
    out = writable_directory(args.out)
    refuse_overwrite({"--json": json_path}, {"the record": args.file})
    if args.columns:
        return _allan_axes(args, out, json_path)
    if args.inflate != 1.0:
        from ..noise.exports import consumers

        raise InputError(f"--inflate scales the exports of --columns ({consumers()}); "
                         "one --column has none")
    from ..noise.allan import allan_deviation
    from ..noise.allan_fit import fit_noise
    from ..noise.allan_report import write_allan

    rec = _load(args, columns=[args.column], notes=False)
    axis = _axes(args, [args.column], rec, optional=True)
    rec = _checked(args, rec, axis)
    result = allan_deviation(rec.column(args.column), rec.require_rate(),
                             units=axis[0].units if axis else None,
                             sensor=axis[0].sensor if axis else None)
    fit = fit_noise(result, min_tau=args.min_tau)
    with report_directory(out, [args.file]) as tmp:
        write_allan(result, fit, tmp, args.title or f"{args.column} of {Path(args.file).name}"
                    f"{window_label(args)}")
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


def _allan_axes(args: argparse.Namespace, out: Path, json_path: Path | None) -> int:
    from ..filter.joint_noise import joint_noise
    from ..noise.imu_noise import imu_noise, write_imu_noise

    rec = _load(args, columns=[spec.partition(":")[0] for spec in args.columns], notes=False)
    axes = _axes(args, args.columns, rec)
    rec = _checked(args, rec, axes)
    for axis in axes:
        print(f"fosmodel: {axis.describe()}", file=sys.stderr)
    columns = {a.column: rec.column(a.column) for a in axes}
    noise = imu_noise(columns, axes, rec.require_rate(), rec.source, min_tau=args.min_tau)
    joint = joint_noise(columns, noise) if len(axes) > 1 else None
    with report_directory(out, [args.file]) as tmp:
        write_imu_noise(noise, tmp, args.title or Path(args.file).name + window_label(args),
                        inflate=args.inflate)
        if joint is not None:
            write_text(tmp / "joint_model.json", json.dumps(joint.to_dict(), indent=1) + "\n")
    print(noise.summary())
    for line in noise.export_notes(args.inflate):
        print(f"warning: {line}", file=sys.stderr)
    for line in noise.fit_warnings():
        print(f"warning: {line}", file=sys.stderr)
    if json_path:
        write_text(json_path, json.dumps(noise.to_dict(args.inflate), indent=1) + "\n")
    print(f"Allan noise report of {len(axes)} axes written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else ""))
    return 0


def synth(args: argparse.Namespace) -> int:
    from data_synth.cli import run

    return run(args)


def demo(args: argparse.Namespace) -> int:
    from ..demo import run_demo

    run_demo(Path(args.out))
    return 0
