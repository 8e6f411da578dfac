"""The ``tempcal`` command: a thermal calibration of an IMU from static records.

Every gyro and accelerometer axis of the records (each record a session) gets its bias
against temperature, judged out of sample beside PX4's procedure, and the files PX4 and
ArduPilot load (:mod:`fosmodel.workflows.tempcal`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..noise.axes import UnitsSpec
from .arguments import RECORD_HELP, add_loader_options, name_list, positive_float
from .parsing import parsed


def fraction(text: str) -> float:
    """Read a fraction strictly between 0 and 1: ``0.7`` or ``70%``."""
    try:
        value = float(text[:-1]) / 100 if text.endswith("%") else float(text)
    except ValueError:
        value = -1.0
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"expected a fraction like 0.7 or 70%, got {text!r}")
    return value


def _device_id(text: str) -> int:
    """Read a ``device_id``: an unsigned 32-bit integer, decimal or 0x hexadecimal."""
    try:
        value = int(text, 0)
    except ValueError:
        value = -1
    if not 0 < value < 2**32:
        raise argparse.ArgumentTypeError(f"expected a device_id like 2424842 or 0x250052, "
                                         f"got {text!r}")
    return value


def configure_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the ``tempcal`` command's arguments to ``parser`` and return it."""
    parser.add_argument("files", nargs="+", metavar="RECORD",
                        help=RECORD_HELP.replace("record:", "static records of one IMU with a "
                                                 "temperature column, each a session:"))
    parser.add_argument("--columns", type=name_list, metavar="COL[:SENSOR:UNITS],...",
                        help="the axes (default: every column whose name or file tells a gyro "
                             "or an accelerometer, e.g. gx..az, gx_dps, acc_y_mps2)")
    parser.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS,...",
                        help="units of every column (deg/s) or per column (gx=deg/s,ax=g) "
                             "(default: from the names, or the file's)")
    parser.add_argument("--temperature", metavar="COL",
                        help="the temperature column (default: one named temperature, temp or "
                             "temp_c)")
    add_loader_options(parser, contiguous="a thermal calibration")
    parser.add_argument("--instance", type=int, default=0, choices=range(4), metavar="N",
                        help="a PX4 ULog's sensor instance (sensor_gyro:N, sensor_accel:N), and "
                             "the firmware's slot: PX4's TC_GN/TC_AN, ArduPilot's "
                             "INS_TCAL(N+1)")
    parser.add_argument("--degree", type=int, choices=(1, 2, 3), metavar="K",
                        help="the highest power of temperature, 1 to 3 (default: the firmware's "
                             "3, as far as the temperature's span supports it)")
    parser.add_argument("--min-span", type=positive_float, default="5", metavar="C",
                        help="the least temperature span fitted over, in degC, and the span "
                             "each power of the polynomial needs")
    parser.add_argument("--block", type=positive_float, default="30", metavar="S",
                        help="blocks (s) of the slow bias the fits and the judge read")
    parser.add_argument("--head", type=positive_float, default="60", metavar="S",
                        help="a held-out session's constant (turn-on bias) from its first S "
                             "seconds, which are not judged")
    parser.add_argument("--train", type=fraction, default="70%", metavar="FRACTION",
                        help="with one record, the part of it fitted on; the rest is judged")
    parser.add_argument("--gyro-id", type=_device_id, metavar="ID",
                        help="the gyro's PX4 device_id (TC_GN_ID), where the records do not "
                             "give it (a ULog's do)")
    parser.add_argument("--accel-id", type=_device_id, metavar="ID",
                        help="the accelerometer's PX4 device_id (TC_AN_ID)")
    parser.add_argument("--title", help="title of the report")
    parser.add_argument("--out", required=True, help="output directory (created)")
    return parser


def tempcal(args: argparse.Namespace) -> int:
    """Calibrate ``args.files`` and publish the report and the firmware's files in ``args.out``."""
    from ..io.loader import parse_scales
    from ..io.output import refuse_overwrite, report_directory, writable_directory
    from ..workflows.tempcal import TempcalConfig, run_tempcal
    from ..workflows.tempcal_records import tempcal_groups
    from ..workflows.tempcal_report import console_summary, write_tempcal
    from .flags import with_flags

    config = TempcalConfig(degree=args.degree, min_span_c=args.min_span, block_s=args.block,
                           head_s=args.head, train=args.train)
    out = writable_directory(args.out)
    refuse_overwrite({"--out": out}, {f"the record {i + 1}": f for i, f in enumerate(args.files)})
    notes: list[str] = []
    groups = tempcal_groups(args.files, columns=args.columns, units=args.units,
                            temperature=args.temperature, instance=args.instance,
                            topic=args.topic, notes=notes, rate=args.rate,
                            scale=parse_scales(args.scale or []), uniform=args.uniform,
                            outliers=args.outliers, gaps=args.gaps,
                            temperature_topic=args.temperature_topic)
    for note in notes:
        print(f"fosmodel: note: {with_flags(note)}", file=sys.stderr)
    result = run_tempcal(groups, config, progress=lambda line: print(f"fosmodel: {line}",
                                                                   file=sys.stderr, flush=True))
    title = args.title or ", ".join(Path(f).name for f in args.files)
    with report_directory(out, args.files) as tmp:
        said = write_tempcal(result, tmp, title, args.instance,
                             {"gyro": args.gyro_id, "accel": args.accel_id})
    for note in said:
        print(f"fosmodel: note: {with_flags(note)}", file=sys.stderr)
    print(console_summary(result))
    print(f"thermal calibration of {len(result.axes)} axes written to {out.resolve()}/")
    return 0

