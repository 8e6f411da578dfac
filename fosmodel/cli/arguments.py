"""The command line's argument types and the options every command that reads a record shares.

Each type reads one option's text into the value the library takes, and refuses it in one line
(``argparse.ArgumentTypeError``) naming the form it expects.
"""

from __future__ import annotations

import argparse
import re

import numpy as np

from ..io.formats import FORMATS, described
from ..io.outliers import DEFAULT_OUTLIERS, OUTLIER_K, OUTLIER_MODES, OUTLIER_SHARE
from ..noise.exports import consumers
from .parsing import Refused

#: What a record argument may be.
RECORD_HELP = f"record: {described(FORMATS)}"


def exog_arg(text: str) -> list[tuple[str, int]]:
    """``temp:5`` or ``temp:5,hum:2`` -> ``[(name, K), ...]``."""
    out = []
    for part in text.split(","):
        name, sep, lag = part.strip().partition(":")
        if not sep or not name or not lag.isdigit():
            raise argparse.ArgumentTypeError(f"expected NAME:K[,NAME:K...] (e.g. temp:5), "
                                             f"got {text!r}")
        out.append((name, int(lag)))
    return out


def positive_float(text: str) -> float:
    """Read a finite positive number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """Read an integer of at least 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def levels_arg(text: str) -> list[float] | str:
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


def int_list(text: str) -> list[int]:
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


_DURATION = re.compile(r"^([0-9]*\.?[0-9]+(?:e[+-]?[0-9]+)?)\s*(s|min|h)?$")
_SECONDS = {"s": 1.0, "min": 60.0, "h": 3600.0}


def durations(text: str) -> tuple[float, ...]:
    """``30s,5min,1h`` -> durations in seconds (a bare number is in seconds)."""
    out = []
    for part in text.split(","):
        m = _DURATION.match(part.strip())
        if not m or float(m.group(1)) <= 0:
            raise argparse.ArgumentTypeError(f"expected durations like 30s,5min,1h, got {text!r}")
        out.append(float(m.group(1)) * _SECONDS[m.group(2) or "s"])
    return tuple(out)


def duration(text: str) -> float:
    """``30s``, ``5min``, ``1h`` or a bare number of seconds -> one positive duration in s."""
    m = _DURATION.match(text.strip())
    if not m or not np.isfinite(float(m.group(1))) or float(m.group(1)) <= 0:
        raise argparse.ArgumentTypeError(f"expected a duration like 30s, 5min or 1h (a bare "
                                         f"number is in seconds), got {text!r}")
    return float(m.group(1)) * _SECONDS[m.group(2) or "s"]


def offset(text: str) -> float:
    """``0``, ``30s``, ``10min``, ``1h`` -> a time into the record in seconds (0 allowed)."""
    m = _DURATION.match(text.strip())
    if not m or not np.isfinite(float(m.group(1))):
        raise argparse.ArgumentTypeError(f"expected a time into the record like 90s, 10min or "
                                         f"1h (a bare number is in seconds), got {text!r}")
    return float(m.group(1)) * _SECONDS[m.group(2) or "s"]


def add_window_options(parser: argparse.ArgumentParser) -> None:
    """Add ``--start`` and ``--stop``: the stretch of the record analysed.

    Their destinations are ``window_start`` and ``window_stop``: ``--stop`` elsewhere is a
    stopping rule.
    """
    parser.add_argument("--start", type=offset, metavar="T", dest="window_start",
                        help="leave out the record before T after its first sample, e.g. a "
                             "warm-up (s, min or h; default: from the first sample)")
    parser.add_argument("--stop", type=offset, metavar="T", dest="window_stop",
                        help="leave out the record after T after its first sample (s, min or "
                             "h; default: to its end)")


def name_list(text: str) -> list[str]:
    """Read ``a,b,c`` into its names (blanks dropped)."""
    return [p.strip() for p in text.split(",") if p.strip()]


SPLIT_HELP = ("training and evaluation lengths, each in seconds (180s; also min, h) or in "
               "percent of the record (50%%); the rest is predicted")
UNITS_HELP = ("units of every column (deg/s) or per column (gx=deg/s,ax=g), which tell the "
               "sensor: rad/s, deg/s, deg/h (gyro); m/s^2, g, mg (accel)")


def add_loader_options(parser: argparse.ArgumentParser, contiguous: str | None = None) -> None:
    """Add the loader's options.

    ``contiguous`` names what needs a record without gaps: ``--segments`` is refused for it.
    """
    parser.add_argument("--rate", type=positive_float,
                        help="sample rate in Hz (if no time column)")
    parser.add_argument("--scale", type=name_list, action="extend",
                        metavar="NAME=FACTOR[,...]",
                        help="multiply column NAME by FACTOR, e.g. gx=1/131 for raw counts "
                             "(comma-separated or repeated)")
    parser.add_argument("--uniform", action="store_true",
                        help="take the samples as uniformly spaced at the time column's "
                             "effective rate (a host's bursty receive time)")
    parser.add_argument("--outliers", choices=OUTLIER_MODES, default=DEFAULT_OUTLIERS,
                        help=f"outliers (|x - median| > {OUTLIER_K:g} x 1.4826 MAD): refuse the "
                             f"record if a column's carry over {100 * OUTLIER_SHARE:g} %% of its "
                             "mean square (else keep them), keep, clip or drop them; all are "
                             "reported")
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
    parser.set_defaults(gaps="contiguous" if contiguous else "refuse")


def inflation(text: str) -> float:
    """Read an inflation factor: a finite number of at least 1."""
    value = positive_float(text)
    if value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a factor of at least 1 (a moving platform is "
                                         f"noisier than a static one), got {text!r}")
    return value


INFLATE_HELP = (f"multiply every exported noise value ({consumers()}, MATLAB) by K for a "
                "moving platform, and say so in each file; 1 keeps the static record's values")
STATIC_ONLY_HELP = ("analyse the longest static stretch of a record that moves (by default a "
                    "record that moves is refused: an Allan analysis needs the sensor at rest)")
