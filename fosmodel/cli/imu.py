"""The ``imu`` command: the six-axis workflow of :mod:`fosmodel.workflows` on one record.

Every axis of an IMU record goes through the Allan analysis, the model-order study and the
residual loop, and one report holds them all.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ..io.split import PROPORTIONAL, SplitSpec
from ..noise.axes import UnitsSpec
from .arguments import (
    INFLATE_HELP,
    RECORD_HELP,
    SPLIT_HELP,
    STATIC_ONLY_HELP,
    UNITS_HELP,
    add_loader_options,
    add_window_options,
    duration,
    inflation,
    int_list,
    name_list,
    positive_int,
)
from .flags import with_flags
from .parsing import parsed

#: The methods of :data:`fosmodel.study.harness.METHODS`, spelt here: importing the harness
#: would load every estimator whenever the parser is built (a test holds the two equal).
METHODS = ("fos", "yw", "cov", "burg", "gm")


def configure_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the ``imu`` command's arguments to ``parser`` and return it."""
    parser.add_argument("file", help=RECORD_HELP)
    add_workflow_options(parser)
    add_window_options(parser)
    parser.add_argument("--jobs", type=positive_int, default=2,
                        help="studies and loops run at once, in worker processes")
    parser.add_argument("--title", help="title of the report")
    parser.add_argument("--out", required=True, help="output directory (created)")
    parser.add_argument("--json", help="also write the report's tables and the noise "
                                       "parameters as JSON")
    return parser


def add_workflow_options(parser: argparse.ArgumentParser) -> None:
    """Add the options of the six-axis workflow's steps (shared with the ``fleet`` command)."""
    parser.add_argument("--columns", type=name_list, metavar="COL[:SENSOR:UNITS],...",
                        help="the axes (default: every column whose name or file tells a gyro "
                             "or an accelerometer, e.g. gx..az, gx_dps, acc_y_mps2)")
    add_loader_options(parser, contiguous="the six-axis workflow")
    parser.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS,...",
                        help=UNITS_HELP + " (default: from the names, or the file's)")
    parser.add_argument("--temperature", metavar="COL",
                        help="temperature column the loop may use (default: a column named "
                             "temperature, temp or temp_c, if any)")
    parser.add_argument("--orders", type=int_list, default="1-10",
                        help="model orders of the study, e.g. 1-10 or 1,2,5")
    parser.add_argument("--degrees", type=int_list, default="1,2",
                        help="FOS cross-product degrees of the study")
    parser.add_argument("--methods", type=name_list, default=",".join(METHODS),
                        help="comma-separated among " + ",".join(METHODS))
    parser.add_argument("--protocol", choices=("paper", "fair", "both"), default="fair",
                        help="the study's protocol (paper: baselines on denoised data)")
    parser.add_argument("--split", type=parsed(SplitSpec.parse), default=str(PROPORTIONAL),
                        metavar="TRAIN,EVALUATE",
                        help="the study's segments: " + SPLIT_HELP + ", in proportion to "
                        "the record by default, as close-loop's (default: "
                        + str(PROPORTIONAL).replace("%", "%%") + ")")
    parser.add_argument("--loop-split", type=parsed(SplitSpec.parse), metavar="TRAIN,EVALUATE",
                        help="the loop's segments, if not those of --split: " + SPLIT_HELP
                        + " (default: the study's, so that both score on one prediction "
                          "segment)")
    parser.add_argument("--horizon", type=duration, default="30s",
                        help="outage horizon: 30s, 2min (a bare number is in seconds)")
    parser.add_argument("--min-tau", type=duration,
                        help="shortest averaging time of the Allan fits, e.g. 0.1s (default: "
                             "found per axis)")
    parser.add_argument("--static-only", action="store_true", help=STATIC_ONLY_HELP)
    parser.add_argument("--inflate", type=inflation, default="1", metavar="K", help=INFLATE_HELP)


def workflow_settings(args: argparse.Namespace) -> dict[str, Any]:
    """Return the settings of :class:`~fosmodel.workflows.imu.ImuConfig` the options give."""
    return dict(orders=args.orders, degrees=args.degrees, methods=args.methods,
                protocols=("paper", "fair") if args.protocol == "both" else (args.protocol,),
                horizon_s=args.horizon, min_tau=args.min_tau, inflate=args.inflate)


def imu(args: argparse.Namespace) -> int:
    """Run the six-axis workflow on ``args.file`` and publish its report in ``args.out``."""
    from ..core.exceptions import InputError
    from ..io.output import (
        refuse_overwrite,
        report_directory,
        writable_directory,
        writable_file,
        write_text,
    )
    from ..io.record import Record
    from ..workflows.imu import TEMPERATURE, ImuConfig, record_axes, run_imu
    from ..workflows.imu_report import axis_handoffs, console_summary, write_imu_report
    from .commands import _checked, _load, window_label

    json_path = writable_file(args.json, created=args.out) if args.json else None
    out = writable_directory(args.out)
    refuse_overwrite({"--json": json_path}, {"the record": args.file})
    from ..noise.checks import unused_columns

    def analysed(r: Record) -> list[str]:  # the axes and the temperature
        try:
            axes, aux = record_axes(r, args.columns, args.units, args.temperature)
        except InputError:  # said below, by record_axes itself
            return []
        # a temperature column the loader held (an empty cell) is still the loops' driver
        held = [c for c in r.held if c == args.temperature
                or (args.temperature is None and TEMPERATURE.match(c))]
        return [*(a.column for a in axes), *aux, *held]

    rec = _load(args, notes=False, analysed=analysed)  # every column: its temperature too
    axes, aux = record_axes(rec, args.columns, args.units, args.temperature)
    rec = _checked(args, rec, axes)
    aux = {name: rec.column(name) for name in aux}  # the static stretch's, if one was kept
    for axis in axes:
        print(f"fosmodel: {axis.describe()}", file=sys.stderr)
    for column, why in unused_columns(rec.names, [*(a.column for a in axes), *aux],
                                      named=bool(args.columns)):
        print(f"fosmodel: note: column {column!r} skipped: {with_flags(why)}", file=sys.stderr)
    rate = rec.require_rate()

    settings = ImuConfig(**workflow_settings(args), n_jobs=args.jobs)

    def at(n: int) -> ImuConfig:  # the settings for a record of n samples
        return settings.on_record(n, rate, args.split, args.loop_split)

    at(rec.n_samples).check(rec.n_samples, rate, axes, at=at)  # too short: one message
    config = at(rec.n_samples)
    result = run_imu({a.column: rec.column(a.column) for a in axes}, axes, rate, rec.source,
                     aux=aux, config=config,
                     progress=lambda line: print(f"fosmodel: {line}", file=sys.stderr,
                                                 flush=True))
    handoffs = axis_handoffs(result, {a.column: rec.column(a.column) for a in axes}, aux)
    with report_directory(out, [args.file]) as tmp:
        write_imu_report(result, tmp, args.title or Path(args.file).name + window_label(args),
                         handoffs)
    print(console_summary(result))
    for line in [*result.noise.fit_warnings(), *result.noise.export_notes(config.inflate)]:
        print(f"warning: {line}", file=sys.stderr)
    if json_path:
        found = result.to_dict()
        found["filter"] = {column: h.to_dict() for column, h in handoffs.items()}
        write_text(json_path, json.dumps(found, indent=1) + "\n")
    print(f"six-axis report of {len(axes)} axes written to {out.resolve()}/"
          + (f" and {json_path}" if json_path else ""))
    return 0
