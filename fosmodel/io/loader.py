"""Load and validate a sensor record from CSV, ``.npy``, Parquet, a ROS bag or a PX4 ULog.

This is the one place where files are read and checked.  Every problem is an
:class:`~fosmodel.core.exceptions.InputError` naming the file, the column and the
first offending row (CSV rows are counted as file lines, the first line being
line 1); everything worth knowing that is not an error goes to
:attr:`Record.notes`.

Formats
-------
CSV
    Optional ``key,value`` preamble lines (``Fs,100`` gives the sample rate),
    one header row of column names, comma-separated, then one row per sample;
    gzip, bz2 or xz compressed when the name ends so.  An optional time column
    (``time``, ``time_s``, ``t_s`` or ``timestamp``, in seconds or, of integers, in the unit
    :func:`fosmodel.io.time_units.time_unit` tells; ``time_ms``, ``t_us``, ``timestamp_ns``
    in the unit they name) gives the sample rate; otherwise pass ``rate``.
``.npy``
    A structured array (its field names are the columns), a 1-D array (one
    column ``c0``) or a 2-D array (columns ``c0``, ``c1``, ...).
Parquet
    Read with pandas when pyarrow is installed.
ROS bags, PX4 ULog
    One IMU topic (``topic``), read by :mod:`fosmodel.io.topics` into columns
    and a time column that go through the same checks (rows are messages).

Checks and repairs
------------------
Raw integer counts are scaled per column (``scale``); a time column that is a
host's bursty receive time is detected and, on request, replaced by uniform
sample times (``uniform``); outliers are found per column and kept, clipped or
dropped (``outliers``).

:func:`load_record` puts together the modules that do each: a reader per format
(:mod:`~fosmodel.io.csv_reader`, :mod:`~fosmodel.io.npy_reader`,
:mod:`~fosmodel.io.parquet_reader`; logs through :mod:`~fosmodel.io.topics`), the values
(:mod:`~fosmodel.io.values`: cells to float64, finite, magnitude, scale), the time base
(:mod:`~fosmodel.io.timebase`: rate, order, gaps, bursts) and the outliers
(:mod:`~fosmodel.io.outliers`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path

import pandas as pd

from ..core import files
from ..core.exceptions import InputError
from ..core.validation import did_you_mean
from .column_names import units_from_name
from .csv_reader import Preamble, preamble_rate
from .formats import table_format
from .outliers import DEFAULT_OUTLIERS, OUTLIER_MODES, find_outliers, handle_outliers
from .record import Record
from .sensor_log import SensorLog
from .time_units import time_unit
from .timebase import (
    GAP_MODES,
    RATE_RANGE,
    REFUSING,
    TIME_COLUMNS,
    check_imu_rate,
    handle_gaps,
    time_base,
)
from .topics import FORMATS, TopicError, is_sensor_log, read_topic
from .values import (
    Block,
    apply_scale,
    check_magnitude,
    convert,
    note_integer_columns,
    number_or_ratio,
)

#: Rows per block read from a file: a long record is converted block by block.
CHUNK_ROWS = 500_000


def load_record(
    path: str | Path,
    *,
    columns: Sequence[str] | None = None,
    rate: float | None = None,
    scale: Mapping[str, float] | None = None,
    uniform: bool = False,
    outliers: str = DEFAULT_OUTLIERS,
    gaps: str = "refuse",
    topic: str | None = None,
    temperature_topic: str | None = None,
    hold: bool = False,
) -> Record:
    """Read and validate a record.

    Parameters
    ----------
    path : str or Path
        CSV (optionally compressed), ``.npy`` or ``.parquet`` file; or a ROS bag
        (``.bag``, a ROS 2 bag directory, ``.db3``, ``.mcap``) or PX4 ULog (``.ulg``),
        of which one IMU topic is read (:func:`fosmodel.io.topics.read_topic`: columns
        ``gx``, ``gy``, ``gz`` in rad/s, ``ax``, ``ay``, ``az`` in m/s^2, ``temperature``
        in degC, their units in ``Record.units``, and its stamps as the time column).
    columns : sequence of str, optional
        Keep only these columns (with the time column and the columns named in
        ``scale``); the others are neither converted nor kept.  Files are read
        in blocks of ``CHUNK_ROWS`` rows (a ``.npy`` file memory-mapped), so
        memory holds the kept columns as float64 and one block, whatever the
        file's width.  A name the file lacks is an error.
    rate : float, optional
        Sample rate in Hz.  Required when the file has neither a time column
        nor a preamble rate; checked against them when it has.  A rate the file gives
        outside ``IMU_RATES`` (1 Hz to 100 kHz) is refused unless ``rate`` confirms it.
    scale : mapping of str to float, optional
        Factor per column, e.g. ``{"gx": 1 / 131}`` to turn raw counts into
        deg/s (the time column may be scaled too, e.g. from ms to s).
    uniform : bool, default False
        Take the samples as uniformly spaced at the time column's effective
        rate (N - 1 intervals over its span), as a host's bursty receive time
        needs; the time gap check is then skipped and ``Record.time`` becomes
        sample number / rate.
    outliers : {"refuse", "keep", "clip", "drop"}, default "refuse"
        What to do with samples farther than ``OUTLIER_K`` robust standard
        deviations (1.4826 MAD) from their column's median: refuse the record when a
        column's carry more than ``OUTLIER_SHARE`` (1 %) of its mean square about its
        median and keep them otherwise (:mod:`fosmodel.io.outliers` says why), report
        them only, clip them to that bound, or drop their rows (only from a record with
        a time column).  They are reported in ``Record.notes`` and ``Record.outliers``.
    gaps : {"refuse", "contiguous", "fill", "segments"}, default "refuse"
        What to do with gaps in a regular time column (intervals over 1.5 times
        the median one): refuse the record, fill them by linear interpolation
        onto the regular grid, or keep them and list the contiguous runs in
        ``Record.segments`` (to fit on them).  Always reported.  "contiguous"
        refuses too, for a caller that needs a record without gaps: its
        message offers filling, not segments.
    topic : str, optional
        The IMU topic of a log to read; may be left out when the log has one.
    temperature_topic : str, optional
        The topic of a log whose temperature becomes the ``temperature`` column,
        interpolated onto the IMU samples' times (a bag's only temperature topic
        by default).
    hold : bool, default False
        Hold, rather than raise, the refusals a column's content earns (cells that are no
        finite real numbers, booleans, outliers under "refuse"): the column is left out and
        its refusal put in ``Record.held``, for :func:`fosmodel.io.content.settle` to raise
        if the column is analysed and to note otherwise.  The time column is never held.

    Returns
    -------
    Record

    Raises
    ------
    InputError
        Missing, empty or damaged file, a header naming a column twice, a
        column asked for that the file lacks, no data
        rows, a non-numeric or non-finite cell, a value beyond ``MAX_ABS`` (after
        scaling), a bad preamble rate or scale, a time column that is not strictly
        increasing or not uniform (a bursty one without ``uniform``), a rate
        outside ``RATE_RANGE`` or that disagrees with it, or a drop of samples
        from a record without time.  For a log, also what
        :func:`fosmodel.io.topics.read_topic` raises (a :class:`TopicError` when the
        topic is to be chosen), and a topic given for a file that has none.
    """
    path = Path(path)
    src = str(path)
    files.protect(path)  # no cleanup of an output's temporaries removes it
    if rate is not None and not RATE_RANGE[0] <= rate <= RATE_RANGE[1]:
        raise InputError(f"the sample rate must be a positive number of Hz, from "
                         f"{RATE_RANGE[0]:g} to {RATE_RANGE[1]:g}, got {rate!r}")
    if outliers not in OUTLIER_MODES:
        raise InputError(f"outliers must be one of {', '.join(OUTLIER_MODES)}, got {outliers!r}")
    if gaps not in GAP_MODES:
        raise InputError(f"gaps must be one of {', '.join(GAP_MODES)}, got {gaps!r}")
    log = _sensor_log(path, topic, temperature_topic)
    names, first_line, preamble = (list(log.columns), 0, Preamble(0, [])) if log else (
        _header(path))
    if not names:
        raise InputError(f"{src}: no columns")
    if all(n in TIME_COLUMNS for n in names):
        raise InputError(f"{src}: only a time column, no data columns")
    keep = _kept(names, columns, scale or {}, src)
    blocks, n_rows = ((iter([pd.DataFrame(log.columns)[keep or names]]), None) if log else
                      _blocks(path, preamble.header_index, names, keep))
    held: dict[str, str] | None = {} if hold else None
    data = convert(blocks, n_rows, src, first_line, held)
    if held and not [c for c in data if c not in TIME_COLUMNS]:  # nothing else to analyse
        raise InputError(next(iter(held.values())))
    if not len(next(iter(data.values()))):
        raise InputError(f"{src}: header only, no data rows")
    notes: list[str] = log.notes if log else []
    rate, given_by, metadata = preamble_rate(preamble, rate, src, notes)
    apply_scale(data, scale or {}, src, notes)
    check_magnitude(data, scale or {}, src, first_line)
    time_name = next((c for c in TIME_COLUMNS if c in data), "")
    time = data.pop(time_name) if time_name else None
    for other in [c for c in TIME_COLUMNS if c in data]:  # one time base: the first
        del data[other]
        notes.append(f"column {other!r} is another time column: the time is {time_name!r}; "
                     f"{other!r} is not read")
    if not data:
        raise InputError(f"{src}: only a time column, no data columns")
    counts = None  # an integer time column and its counts per second, for an exact rate
    if time is not None and time_name not in (scale or {}):
        unit = time_unit(time_name, time, rate)
        if time.dtype.kind == "i" and round(1 / unit.seconds) * unit.seconds == 1.0:
            counts = (time, round(1 / unit.seconds))
        if unit.unit != "s":
            notes.append(unit.note(time_name))
        time = (time - time[0]) * unit.seconds + float(time[0]) * unit.seconds \
            if time.dtype.kind == "i" else time * unit.seconds
    elif time is not None:
        time = time.astype(float)
    named = {name: spelled for name in data if (spelled := units_from_name(name))}
    units = {name: unit for name, unit in {**named, **(log.units if log else {})}.items()
             if name in data and name not in (scale or {})}
    note_integer_columns(data, [*(scale or {}), *units], notes)
    segments = None
    if time is not None:
        rate, time = time_base(time, rate, given_by, uniform, src, time_name, first_line,
                                notes, gaps, counts)
        if gaps not in REFUSING and not uniform:
            time, segments = handle_gaps(data, time, gaps, src, time_name, first_line, notes)
    else:
        if rate is not None:
            check_imu_rate(rate, given_by, f"{given_by} gives", src)
        if uniform:
            notes.append("uniform=True has no effect: the record has no time column")
    found = find_outliers(data)
    record = Record(src, data, float(rate) if rate is not None else None, time, notes,
                    log.metadata if log else metadata,
                    {name: out.samples for name, out in found.items()}, segments, units,
                    dict(held or {}))
    handle_outliers(record, found, outliers, first_line, hold)
    return record


def parse_scales(texts: Iterable[str]) -> dict[str, float]:
    """Scale factors from ``NAME=FLOAT`` or ``NAME=A/B`` texts (the ``--scale`` option).

    Examples
    --------
    >>> parse_scales(["gx=1/131", "ax=0.5"])
    {'gx': 0.007633587786259542, 'ax': 0.5}

    Raises
    ------
    InputError
        A text of another form, a factor that is zero or not finite, a name given twice.
    """
    scales: dict[str, float] = {}
    for text in texts:
        name, sep, value = (part.strip() for part in text.partition("="))
        factor = number_or_ratio(value) if sep and name else None
        if factor is None:
            raise InputError(f"scale={text!r}: expected NAME=FACTOR or NAME=A/B with a finite, "
                             "non-zero factor (e.g. gx=1/131)")
        if name in scales:
            raise InputError(f"column {name!r} is given twice in scale=")
        scales[name] = factor
    return scales


def _sensor_log(path: Path, topic: str | None, temperature_topic: str | None) -> SensorLog | None:
    """Read the IMU topic of a log (a ROS bag, a PX4 ULog); None for a table."""
    if not is_sensor_log(path):
        asked = next((key for key, value in (("topic", topic),
                                             ("temperature_topic", temperature_topic)) if value),
                     None)
        if asked:
            raise TopicError(f"{path}: not {FORMATS}, so no topic to choose; leave out "
                             "{option}", asked)
        return None
    if not path.is_dir():  # a ROS 2 bag is a directory
        _check_regular(path)
    return read_topic(path, topic, temperature_topic)


def _header(path: Path) -> tuple[list[str], int, Preamble]:
    """Column names, the file line of the first data row (0 if rows, not lines), the preamble."""
    _check_regular(path)
    return table_format(path).read_header(path)


def _check_regular(path: Path) -> None:
    """Refuse what is not a regular file, and an empty one.

    A record is read, and re-read, to its end.
    """
    if not path.exists():
        raise InputError(f"{path}: no such file" + (" (a broken symbolic link)"
                                                    if path.is_symlink() else ""))
    if path.is_dir():
        raise InputError(f"{path}: a directory, not a record")
    if not path.is_file():
        kind = ("a FIFO" if path.is_fifo() else "a device" if path.is_char_device()
                or path.is_block_device() else "a socket" if path.is_socket() else
                "not a regular file")
        target = f" ({path.resolve()})" if path.is_symlink() else ""
        raise InputError(f"{path}{target}: {kind}, not a regular file; fosmodel reads records "
                         "from files")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: the file is empty")


def _kept(names: list[str], columns: Sequence[str] | None, scale: Mapping[str, float],
          src: str) -> list[str] | None:
    """Return the columns to read (None: all): those asked for, the time and the scaled ones."""
    unknown = [c for c in scale if c not in names]
    if unknown:
        raise InputError(f"{src}: scale= names no column {unknown[0]!r}"
                         f"{did_you_mean(unknown[0], names)}; columns: {', '.join(names)}")
    if columns is None:
        return None
    missing = [c for c in columns if c not in names or c in TIME_COLUMNS]
    if missing:
        shown = [n for n in names if n not in TIME_COLUMNS]
        raise InputError(f"{src}: no column {missing[0]!r}{did_you_mean(missing[0], shown)}; "
                         f"columns: {', '.join(shown)}")
    wanted = {*columns, *scale, *TIME_COLUMNS}
    return [n for n in names if n in wanted]


def _blocks(path: Path, skip: int, names: list[str],
            keep: list[str] | None) -> tuple[Iterator[Block], int | None]:
    """Yield the kept columns, ``CHUNK_ROWS`` rows at a time; and the row count if known."""
    return table_format(path).read_blocks(path, skip, names, keep, CHUNK_ROWS)
