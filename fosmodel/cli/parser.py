"""The command line's grammar: argument types, the loader options and the parser."""

from __future__ import annotations

import argparse

import numpy as np

from .._version import __version__
from ..core.fos import STOP_RULES
from ..io.loader import OUTLIER_K, OUTLIER_MODES
from ..io.split import SplitSpec
from ..noise.axes import UnitsSpec
from . import commands
from .parsing import CommandParser, Refused, parsed

#: What a record argument may be.
RECORD_HELP = ("record: CSV, .npy, .parquet, a ROS bag (.bag, a ROS 2 bag directory, .db3, "
               ".mcap) or a PX4 ULog (.ulg)")


def _exog_arg(text: str) -> list[tuple[str, int]]:
    """``temp:5`` or ``temp:5,hum:2`` -> ``[(name, K), ...]``."""
    out = []
    for part in text.split(","):
        name, sep, lag = part.strip().partition(":")
        if not sep or not name or not lag.isdigit():
            raise argparse.ArgumentTypeError(f"expected NAME:K[,NAME:K...] (e.g. temp:5), "
                                             f"got {text!r}")
        out.append((name, int(lag)))
    return out


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
    out: list[int] = []
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


_SPLIT_HELP = ("training and evaluation lengths, each in seconds (180s; also min, h) or in "
               "percent of the record (50%%); the rest is predicted")
_UNITS_HELP = ("units of every column (deg/s) or per column (gx=deg/s,ax=g), which tell the "
               "sensor: rad/s, deg/s, deg/h (gyro); m/s^2, g, mg (accel)")


def _add_loader_options(parser: argparse.ArgumentParser, contiguous: str | None = None) -> None:
    """Add the loader's options.

    ``contiguous`` names what needs a record without gaps: ``--segments`` is refused for it.
    """
    parser.add_argument("--rate", type=_positive_float,
                        help="sample rate in Hz (if no time column)")
    parser.add_argument("--scale", type=_name_list, action="extend",
                        metavar="NAME=FACTOR[,...]",
                        help="multiply column NAME by FACTOR, e.g. gx=1/131 for raw counts "
                             "(comma-separated or repeated)")
    parser.add_argument("--uniform", action="store_true",
                        help="take the samples as uniformly spaced at the time column's "
                             "effective rate (a host's bursty receive time)")
    parser.add_argument("--outliers", choices=OUTLIER_MODES, default="keep",
                        help=f"outliers (|x - median| > {OUTLIER_K:g} x 1.4826 MAD): keep (and "
                             "report), clip or drop")
    gaps = parser.add_mutually_exclusive_group()
    gaps.add_argument("--fill", dest="gaps", action="store_const", const="fill",
                      help="fill gaps of the time column by linear interpolation")
    if contiguous:
        gaps.add_argument("--segments", action=Refused, why=f"{contiguous} needs a contiguous "
                          "record; pass --fill to interpolate across the gaps")
    else:
        gaps.add_argument("--segments", dest="gaps", action="store_const", const="segments",
                          help="keep gaps and use the contiguous segments")
    parser.add_argument("--topic", metavar="NAME",
                        help="IMU topic of a ROS bag or PX4 ULog file that has several "
                             "(e.g. /imu/data, sensor_gyro:1)")
    parser.add_argument("--temperature-topic", metavar="NAME",
                        help="topic of a log whose temperature becomes the column temperature, "
                             "interpolated onto the IMU samples (default: a bag's only "
                             "sensor_msgs/msg/Temperature topic)")
    parser.set_defaults(gaps="refuse")


def build_parser() -> argparse.ArgumentParser:
    """Build the parser of every command, each calling its function of :mod:`.commands`."""
    parser = CommandParser(
        prog="fosmodel",
        description="Fast Orthogonal Search error models for MEMS inertial sensors.",
    )
    parser.add_argument("--version", action="version", version=f"fosmodel {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log details and tracebacks")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    fit = sub.add_parser("fit", help="fit a FOS model to one column of a record")
    fit.add_argument("file", help=RECORD_HELP)
    fit.add_argument("--column", required=True, help="column to model")
    _add_loader_options(fit)
    fit.add_argument("--max-lag", type=int, default=10, help="L, output lags 1..L")
    fit.add_argument("--degree", type=int, default=1, help="CP, cross-product degree")
    fit.add_argument("--exog", type=_exog_arg, action="extend", metavar="NAME:K[,NAME:K...]",
                     help="exogenous columns NAME with lags 0..K (comma-separated or repeated)")
    fit.add_argument("--max-terms", type=int, help="most terms besides the constant")
    fit.add_argument("--stop", choices=STOP_RULES, default="korenberg", help="stopping rule")
    fit.add_argument("--tol", type=float, help="fraction for --stop variance / mean_square")
    fit.add_argument("--levels", type=_levels_arg, metavar="auto|T1,T2,...",
                     help="local levels of the output to offer: their time constants in "
                          "seconds, or 'auto' for a grid below the record's Allan floor")
    fit.add_argument("--max-candidates", type=_positive_int, default=100_000,
                     help="refuse a candidate set larger than this")
    fit.add_argument("--out", required=True, help="model file to write (JSON)")
    fit.set_defaults(func=commands.fit)

    pred = sub.add_parser("predict", help="one-step-ahead prediction with a saved model")
    pred.add_argument("file", help=RECORD_HELP)
    pred.add_argument("--model", required=True, help="model file written by 'fosmodel fit'")
    pred.add_argument("--column", help="column to predict (default: the one the model was fit on)")
    _add_loader_options(pred)
    pred.add_argument("--out", required=True, help="CSV to write")
    pred.set_defaults(func=commands.predict)

    study = sub.add_parser("study", help="model-order study: every method, order and degree")
    study.add_argument("files", nargs="+", metavar="FILE",
                       help=RECORD_HELP.replace("record:", "records:") + "; with several "
                            "files or columns, a report directory per file and column")
    study.add_argument("--columns", "--column", dest="columns", type=_name_list, required=True,
                       metavar="COL[:SENSOR:UNITS],...",
                       help="columns to model, in every file (COL:SENSOR:UNITS also gives a "
                            "column's sensor and units)")
    _add_loader_options(study, contiguous="the model-order study")
    study.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS,...",
                       help=_UNITS_HELP + " (default: from the column names, e.g. gx_dps, ax_g)")
    study.add_argument("--sensor", choices=("accel", "gyro"),
                       help="sensor of every column (the units tell it; checked against them)")
    study.add_argument("--orders", type=_int_list, default="1-10",
                       help="model orders, e.g. 1-10 or 1,2,5")
    study.add_argument("--degrees", type=_int_list, default="1,2",
                       help="FOS cross-product degrees")
    study.add_argument("--methods", type=_name_list, default="fos,yw,cov,burg,gm",
                       help="comma-separated among fos,yw,cov,burg,gm")
    study.add_argument("--protocol", choices=("paper", "fair", "both"), default="both",
                       help="paper: the baselines on denoised data; fair: every method on the "
                            "raw data")
    study.add_argument("--no-levels", action="store_true",
                       help="leave out the methods about the local level (fair protocol)")
    study.add_argument("--split", type=parsed(SplitSpec.parse), default="180s,180s",
                       metavar="TRAIN,EVALUATE", help=_SPLIT_HELP)
    study.add_argument("--horizon", type=_positive_float, default="30",
                       help="outage horizon in seconds")
    study.add_argument("--starts", type=int, default=20, help="outage starts")
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
    study.add_argument("--connect-timeout", type=_positive_float, default="10", metavar="S",
                       help="seconds to wait for --scheduler")
    study.set_defaults(func=commands.study)

    loop = sub.add_parser("close-loop", help="find what the model lacks in its residual, "
                          "add it, report the error before and after")
    loop.add_argument("file", help=RECORD_HELP)
    loop.add_argument("--column", required=True, help="column to model")
    _add_loader_options(loop, contiguous="the residual loop")
    loop.add_argument("--aux", type=_name_list, metavar="COL[,COL...]",
                      help="columns that may explain the residual (default: every other column)")
    loop.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS",
                      help="units of the column (deg/s, or gx=deg/s), which tell the sensor, "
                           "for position errors (default: none, no position errors)")
    loop.add_argument("--sensor", choices=("accel", "gyro"),
                      help="sensor of the column (the units tell it; checked against them)")
    loop.add_argument("--max-lag", type=int, default=10, help="L of the starting model")
    loop.add_argument("--split", type=parsed(SplitSpec.parse), default="50%,20%",
                      metavar="TRAIN,EVALUATE", help=_SPLIT_HELP)
    loop.add_argument("--title", help="title of the report")
    loop.add_argument("--out", required=True, help="output directory (created)")
    loop.add_argument("--json", help="also write the before/after metrics and effects as JSON")
    loop.add_argument("--model", help="also write the final model as JSON (as 'fosmodel fit' "
                                      "does), for 'fosmodel predict' and a filter")
    loop.set_defaults(func=commands.close_loop)

    allan = sub.add_parser("allan", help="Allan deviation with confidence intervals and the "
                           "IEEE Std 952 noise coefficients")
    allan.add_argument("file", help=RECORD_HELP)
    which = allan.add_mutually_exclusive_group(required=True)
    which.add_argument("--column", help="column to analyse (a rate signal)")
    which.add_argument("--columns", type=_name_list, metavar="COL[:SENSOR:UNITS],...",
                       help="several axes in one run, e.g. gx,gy,gz,ax,ay,az: one table, one "
                            "figure per sensor, Kalibr/MATLAB/JSON exports; the sensor and "
                            "units come from the names (gx_dps, acc_y_mps2) where not given")
    _add_loader_options(allan, contiguous="the Allan deviation")
    allan.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS,...",
                       help=_UNITS_HELP + "; for navigation units (default: --columns from "
                                          "the names; --column in its own units)")
    allan.add_argument("--sensor", choices=("accel", "gyro"),
                       help="sensor of every column (the units tell it; checked against them)")
    allan.add_argument("--gyro-units", metavar="UNITS",
                       help="units of the gyro columns --units and the names do not give "
                            "(rad/s, deg/s, deg/h)")
    allan.add_argument("--accel-units", metavar="UNITS",
                       help="units of the accelerometer columns --units and the names do not "
                            "give (m/s^2, g, mg)")
    allan.add_argument("--min-tau", type=_positive_float,
                       help="shortest averaging time fitted, in s (default: found from the "
                            "curve, leaving out taus bent by the sensor's own filtering)")
    allan.add_argument("--title", help="title of the figure")
    allan.add_argument("--out", required=True, help="output directory (created)")
    allan.add_argument("--json", help="also write the Allan deviation and coefficients as JSON")
    allan.set_defaults(func=commands.allan)

    from data_synth.cli import configure_parser

    synth = sub.add_parser("synth", help="write a synthetic record with its ground truth")
    configure_parser(synth).set_defaults(func=commands.synth)

    demo = sub.add_parser("demo", help="the main job on embedded synthetic data")
    demo.add_argument("--out", default="fosmodel-out", help="output directory")
    demo.set_defaults(func=commands.demo)
    for command in sub.choices.values():  # -v after the command too; SUPPRESS keeps one before
        command.add_argument("-v", "--verbose", action="store_true", default=argparse.SUPPRESS,
                             help="log details and tracebacks")
    return parser
