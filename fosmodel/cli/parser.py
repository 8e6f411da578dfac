"""The command line's grammar: each command's parser (argument types in :mod:`.arguments`)."""

from __future__ import annotations

import argparse

from .._version import __version__
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
    durations,
    exog_arg,
    inflation,
    int_list,
    levels_arg,
    name_list,
    positive_float,
    positive_int,
)
from .parsing import Command, CommandParser, parsed

#: The stopping rules of :data:`fosmodel.core.fos.STOP_RULES`, spelt here: importing the
#: search would load SciPy whenever the parser is built (a test holds the two equal).
STOP_RULES = ("korenberg", "max_terms", "variance", "mean_square", "aic", "bic", "fpe", "mdl")


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
    fit.add_argument("files", nargs="+", metavar="FILE",
                     help=RECORD_HELP.replace("record:", "record, or several sessions of one "
                                              "sensor (shared weights, a constant each):"))
    fit.add_argument("--column", required=True, help="column to model")
    add_loader_options(fit)
    fit.add_argument("--max-lag", type=int, default=10, help="L, output lags 1..L")
    fit.add_argument("--degree", type=int, default=1, help="CP, cross-product degree")
    fit.add_argument("--exog", type=exog_arg, action="extend", metavar="NAME:K[,NAME:K...]",
                     help="exogenous columns NAME with lags 0..K (comma-separated or repeated)")
    fit.add_argument("--max-terms", type=int, help="most terms besides the constant")
    fit.add_argument("--stop", choices=STOP_RULES, default="korenberg", help="stopping rule")
    fit.add_argument("--tol", type=float, help="fraction for --stop variance / mean_square")
    fit.add_argument("--levels", type=levels_arg, metavar="auto|T1,T2,...",
                     help="local levels of the output to offer: their time constants in "
                          "seconds, or 'auto' for a grid below the record's Allan floor")
    fit.add_argument("--max-candidates", type=positive_int, default=100_000,
                     help="refuse a candidate set larger than this")
    fit.add_argument("--out", required=True, help="model file to write (JSON)")
    fit.set_defaults(func=Command("commands", "fit"))

    pred = sub.add_parser("predict", help="one-step-ahead prediction with a saved model")
    pred.add_argument("file", help=RECORD_HELP)
    pred.add_argument("--model", required=True, help="model file written by 'fosmodel fit'")
    pred.add_argument("--column", help="column to predict (default: the one the model was fit on)")
    add_loader_options(pred)
    pred.add_argument("--out", required=True, help="CSV to write")
    pred.set_defaults(func=Command("commands", "predict"))

    study = sub.add_parser("study", help="model-order study: every method, order and degree")
    study.add_argument("files", nargs="+", metavar="FILE",
                       help=RECORD_HELP.replace("record:", "records:") + "; with several "
                            "files or columns, a report directory per file and column")
    study.add_argument("--columns", "--column", dest="columns", type=name_list, required=True,
                       metavar="COL[:SENSOR:UNITS],...",
                       help="columns to model, in every file (COL:SENSOR:UNITS also gives a "
                            "column's sensor and units)")
    add_loader_options(study, contiguous="the model-order study")
    study.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS,...",
                       help=UNITS_HELP + " (default: from the column names, e.g. gx_dps, ax_g)")
    study.add_argument("--sensor", choices=("accel", "gyro"),
                       help="sensor of every column (the units tell it; checked against them)")
    study.add_argument("--orders", type=int_list, default="1-10",
                       help="model orders, e.g. 1-10 or 1,2,5")
    study.add_argument("--degrees", type=int_list, default="1,2",
                       help="FOS cross-product degrees")
    study.add_argument("--methods", type=name_list, default="fos,yw,cov,burg,gm",
                       help="comma-separated among fos,yw,cov,burg,gm")
    study.add_argument("--protocol", choices=("paper", "fair", "both"), default="both",
                       help="paper: the baselines on denoised data; fair: every method on the "
                            "raw data")
    study.add_argument("--no-levels", action="store_true",
                       help="leave out the methods about the local level (fair protocol)")
    study.add_argument("--split", type=parsed(SplitSpec.parse), default="180s,180s",
                       metavar="TRAIN,EVALUATE", help=SPLIT_HELP)
    study.add_argument("--horizon", type=positive_float, default="30",
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
    dask.add_argument("--workers", type=positive_int, metavar="N",
                      help="run the fits on a local Dask cluster of N single-threaded processes")
    study.add_argument("--connect-timeout", type=positive_float, default="10", metavar="S",
                       help="seconds to wait for --scheduler")
    study.set_defaults(func=Command("commands", "study"))

    loop = sub.add_parser("close-loop", help="find what the model lacks in its residual, "
                          "add it, report the error before and after")
    loop.add_argument("files", nargs="+", metavar="FILE",
                      help=RECORD_HELP.replace("record:", "record, or several sessions of one "
                                               "sensor, each judged with the others fitted:"))
    loop.add_argument("--column", required=True, help="column to model")
    add_loader_options(loop, contiguous="the residual loop")
    add_window_options(loop)
    loop.add_argument("--aux", type=name_list, metavar="COL[,COL...]",
                      help="companions to take as inputs all the same: other axes of the same "
                           "IMU and kind, and columns named as a magnetometer, attitude, "
                           "velocity or position, which measure the motion in use (default: "
                           "none; every other column is read, the companions as cross-axis "
                           "noise, the rest as drivers)")
    loop.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS",
                      help="units of the column (deg/s, or gx=deg/s), which tell the sensor, "
                           "for position errors (default: from the column's name, e.g. gz_dps; "
                           "else none, no position errors)")
    loop.add_argument("--sensor", choices=("accel", "gyro"),
                      help="sensor of the column (the units tell it; checked against them)")
    loop.add_argument("--max-lag", type=int, default=10, help="L of the starting model")
    loop.add_argument("--split", type=parsed(SplitSpec.parse), default=str(PROPORTIONAL),
                      metavar="TRAIN,EVALUATE", help=SPLIT_HELP)
    loop.add_argument("--horizons", type=durations, default="30s,5min,30min",
                      metavar="T[,T...]",
                      help="outage lengths judged and reported, each where the segments hold "
                           "enough windows (s, min or h)")
    loop.add_argument("--title", help="title of the report")
    loop.add_argument("--out", required=True, help="output directory (created)")
    loop.add_argument("--json", help="also write the before/after metrics and effects as JSON")
    loop.add_argument("--model", help="also write the final model as JSON (as 'fosmodel fit' "
                                      "does), for 'fosmodel predict' and a filter")
    loop.set_defaults(func=Command("commands", "close_loop"))

    allan = sub.add_parser("allan", help="Allan deviation with confidence intervals and the "
                           "IEEE Std 952 noise coefficients")
    allan.add_argument("file", help=RECORD_HELP)
    which = allan.add_mutually_exclusive_group(required=True)
    which.add_argument("--column", help="column to analyse (a rate signal)")
    which.add_argument("--columns", type=name_list, metavar="COL[:SENSOR:UNITS],...",
                       help="several axes in one run, e.g. gx,gy,gz,ax,ay,az: one table, one "
                            "figure per sensor, Kalibr/MATLAB/JSON exports; the sensor and "
                            "units come from the names (gx_dps, acc_y_mps2) where not given")
    add_loader_options(allan, contiguous="the Allan deviation")
    add_window_options(allan)
    allan.add_argument("--units", type=parsed(UnitsSpec.parse), metavar="UNITS|COL=UNITS,...",
                       help=UNITS_HELP + "; for navigation units (default: from the "
                                          "names, e.g. gx_dps; a --column whose name tells "
                                          "none in its own units)")
    allan.add_argument("--sensor", choices=("accel", "gyro"),
                       help="sensor of every column (the units tell it; checked against them)")
    allan.add_argument("--gyro-units", metavar="UNITS",
                       help="units of the gyro columns --units and the names do not give "
                            "(rad/s, deg/s, deg/h)")
    allan.add_argument("--accel-units", metavar="UNITS",
                       help="units of the accelerometer columns --units and the names do not "
                            "give (m/s^2, g, mg)")
    allan.add_argument("--min-tau", type=duration,
                       help="shortest averaging time fitted, e.g. 0.1s (a bare number is in "
                            "seconds; default: found from the curve, leaving out taus bent by "
                            "the sensor's own filtering)")
    allan.add_argument("--static-only", action="store_true", help=STATIC_ONLY_HELP)
    allan.add_argument("--inflate", type=inflation, default="1", metavar="K",
                       help=INFLATE_HELP + " (with --columns)")
    allan.add_argument("--title", help="title of the figure")
    allan.add_argument("--out", required=True, help="output directory (created)")
    allan.add_argument("--json", help="also write the Allan deviation and coefficients as JSON")
    allan.set_defaults(func=Command("commands", "allan"))

    from . import fleet, imu, tempcal

    six = sub.add_parser("imu", help="every axis of an IMU record: Allan noise, model-order "
                         "study and residual loop, one report")
    imu.configure_parser(six).set_defaults(func=Command("imu", "imu"))

    many = sub.add_parser("fleet", help="a batch of IMU records through the six-axis workflow, "
                          "in this process or on Dask; a rerun resumes")
    fleet.configure_parser(many).set_defaults(func=Command("fleet", "fleet"))

    cal = sub.add_parser("tempcal", help="thermal calibration of an IMU: every axis's bias "
                         "against temperature, judged out of sample, for PX4 and ArduPilot")
    tempcal.configure_parser(cal).set_defaults(func=Command("tempcal", "tempcal"))

    from data_synth.cli import configure_parser

    synth = sub.add_parser("synth", help="write a synthetic record with its ground truth")
    configure_parser(synth).set_defaults(func=Command("commands", "synth"))

    demo = sub.add_parser("demo", help="the main job on embedded synthetic data")
    demo.add_argument("--out", default="fosmodel-out", help="output directory")
    demo.set_defaults(func=Command("commands", "demo"))
    for command in sub.choices.values():  # -v after the command too; SUPPRESS keeps one before
        command.add_argument("-v", "--verbose", action="store_true", default=argparse.SUPPRESS,
                             help="log details and tracebacks")
    return parser
