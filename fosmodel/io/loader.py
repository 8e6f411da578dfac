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
    (``time``, ``time_s`` or ``t_s``, in seconds) gives the sample rate;
    otherwise pass ``rate``.
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
"""

from __future__ import annotations

import bz2
import contextlib
import csv
import gzip
import io
import itertools
import lzma
import os
import re
import warnings
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, NamedTuple, TypeAlias

import numpy as np
import pandas as pd

from ..core.exceptions import InputError, error_line
from ..core.median import median
from ..core.validation import did_you_mean
from .record import Record
from .sensor_log import SensorLog
from .topics import FORMATS, TopicError, is_sensor_log, read_topic

if TYPE_CHECKING:
    import pyarrow as pa
    from _typeshed import WriteableBuffer

TIME_COLUMNS = ("time", "time_s", "t_s")
OUTLIER_MODES = ("keep", "clip", "drop")
GAP_MODES = ("refuse", "contiguous", "fill", "segments")
_REFUSING = ("refuse", "contiguous")  # the gap modes that refuse a record with gaps
#: An outlier is farther than ``OUTLIER_K`` robust standard deviations from the column median.
OUTLIER_K = 10.0
_MAD_TO_SIGMA = 1.4826
_RATE_TOLERANCE = 0.01
_PREAMBLE_MAX_LINES = 50
_RATE_KEYS = frozenset({"fs", "rate", "samplerate", "samplingrate", "samplefrequency",
                        "samplingfrequency", "outputdatarate", "odr"})
_BURSTY_MIN_SAMPLES = 100
_SHOWN = 5  # positions listed in a note
#: The openers of compressed files (their signatures differ: each is called as open is).
_OPENERS: dict[str, Callable[..., Any]] = {".gz": gzip.open, ".bz2": bz2.open, ".xz": lzma.open}
_NOT_REAL = {"c": "complex numbers", "M": "dates", "m": "time spans"}  # by numpy dtype kind
#: Larger values overflow the sums of products the models form (degree 4 and more).
_MAX_ABS = 1e30
#: A compressed record may decompress to this many times its size (CSV of sensor readings
#: compresses 3-20 times; a file of one repeated line, a thousand times), or at least:
_EXPANSION, _EXPANSION_FLOOR = 100, 64 * 2**20
#: A time column that stands still over this many rows of a block is no sensor's.
_STILL_ROWS = 1000
#: Rows looked at first to tell a column of readings (a fraction there) from raw counts.
_INTEGER_HEAD = 1000
#: Sample rates outside this range (Hz) are a unit mistake, not a sensor.
_RATE_RANGE = (1e-6, 1e9)
#: Rows per block read from a file: a long record is converted block by block.
CHUNK_ROWS = 500_000
_Block: TypeAlias = "pd.DataFrame | dict[str, np.ndarray]"  # a block of rows, by column


class _Preamble(NamedTuple):
    header_index: int  # 0-based line of the header
    entries: list[tuple[int, str, str]]  # (file line, key, value)


class _Outliers(NamedTuple):
    samples: np.ndarray
    low: float
    high: float


def load_record(
    path: str | Path,
    *,
    columns: Sequence[str] | None = None,
    rate: float | None = None,
    scale: Mapping[str, float] | None = None,
    uniform: bool = False,
    outliers: str = "keep",
    gaps: str = "refuse",
    topic: str | None = None,
    temperature_topic: str | None = None,
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
        nor a preamble rate; checked against them when it has.
    scale : mapping of str to float, optional
        Factor per column, e.g. ``{"gx": 1 / 131}`` to turn raw counts into
        deg/s (the time column may be scaled too, e.g. from ms to s).
    uniform : bool, default False
        Take the samples as uniformly spaced at the time column's effective
        rate (N - 1 intervals over its span), as a host's bursty receive time
        needs; the time gap check is then skipped and ``Record.time`` becomes
        sample number / rate.
    outliers : {"keep", "clip", "drop"}, default "keep"
        What to do with samples farther than ``OUTLIER_K`` robust standard
        deviations (1.4826 MAD) from their column's median: report them only,
        clip them to that bound, or drop their rows (only from a record with a
        time column).  They are reported in ``Record.notes`` and ``Record.outliers``.
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

    Returns
    -------
    Record

    Raises
    ------
    InputError
        Missing, empty or damaged file, a header naming a column twice, a
        column asked for that the file lacks, no data
        rows, a non-numeric or non-finite cell, a value beyond ``_MAX_ABS`` (after
        scaling), a bad preamble rate or scale, a time column that is not strictly
        increasing or not uniform (a bursty one without ``uniform``), a rate
        outside ``_RATE_RANGE`` or that disagrees with it, or a drop of samples
        from a record without time.  For a log, also what
        :func:`fosmodel.io.topics.read_topic` raises (a :class:`TopicError` when the
        topic is to be chosen), and a topic given for a file that has none.
    """
    path = Path(path)
    src = str(path)
    if rate is not None and not _RATE_RANGE[0] <= rate <= _RATE_RANGE[1]:
        raise InputError(f"the sample rate must be a positive number of Hz, from "
                         f"{_RATE_RANGE[0]:g} to {_RATE_RANGE[1]:g}, got {rate!r}")
    if outliers not in OUTLIER_MODES:
        raise InputError(f"outliers must be one of {', '.join(OUTLIER_MODES)}, got {outliers!r}")
    if gaps not in GAP_MODES:
        raise InputError(f"gaps must be one of {', '.join(GAP_MODES)}, got {gaps!r}")
    log = _sensor_log(path, topic, temperature_topic)
    names, first_line, preamble = (list(log.columns), 0, _Preamble(0, [])) if log else (
        _header(path))
    if not names:
        raise InputError(f"{src}: no columns")
    if all(n in TIME_COLUMNS for n in names):
        raise InputError(f"{src}: only a time column, no data columns")
    keep = _kept(names, columns, scale or {}, src)
    blocks, n_rows = ((iter([pd.DataFrame(log.columns)[keep or names]]), None) if log else
                      _blocks(path, preamble.header_index, names, keep))
    data = _convert(blocks, n_rows, src, first_line)
    if not len(next(iter(data.values()))):
        raise InputError(f"{src}: header only, no data rows")
    notes: list[str] = log.notes if log else []
    rate, given_by, metadata = _preamble_rate(preamble, rate, src, notes)
    _apply_scale(data, scale or {}, src, notes)
    _check_magnitude(data, scale or {}, src, first_line)
    time_name = next((c for c in TIME_COLUMNS if c in data), "")
    time = data.pop(time_name) if time_name else None
    if not data:
        raise InputError(f"{src}: only a time column, no data columns")
    units = {name: unit for name, unit in (log.units if log else {}).items()
             if name in data and name not in (scale or {})}
    _note_integer_columns(data, [*(scale or {}), *units], notes)
    segments = None
    if time is not None:
        rate, time = _time_base(time, rate, given_by, uniform, src, time_name, first_line,
                                notes, gaps)
        if gaps not in _REFUSING and not uniform:
            time, segments = _handle_gaps(data, time, gaps, src, time_name, first_line, notes)
    elif uniform:
        notes.append("--uniform has no effect: the record has no time column")
    found = _find_outliers(data)
    record = Record(src, data, float(rate) if rate is not None else None, time, notes,
                    log.metadata if log else metadata,
                    {name: out.samples for name, out in found.items()}, segments, units)
    _handle_outliers(record, found, outliers, first_line)
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
        factor = _factor(value) if sep and name else None
        if factor is None:
            raise InputError(f"--scale {text!r}: expected NAME=FACTOR or NAME=A/B with a finite, "
                             "non-zero factor (e.g. gx=1/131)")
        if name in scales:
            raise InputError(f"--scale: column {name!r} is given twice")
        scales[name] = factor
    return scales


def _factor(text: str) -> float | None:
    num, sep, den = text.partition("/")
    try:
        value = float(num) / float(den) if sep else float(num)
    except (ValueError, ZeroDivisionError):
        return None
    return value if np.isfinite(value) and value != 0 else None


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


def _header(path: Path) -> tuple[list[str], int, _Preamble]:
    """Column names, the file line of the first data row (0 if rows, not lines), the preamble."""
    _check_regular(path)
    kind = _kind(path)
    if kind == "npy":
        return _npy_names(_open_npy(path), path), 0, _Preamble(0, [])
    if kind == "parquet":
        return _parquet_file(path).schema_arrow.names, 0, _Preamble(0, [])
    preamble = _find_preamble(path)
    return _csv_names(path, preamble.header_index), preamble.header_index + 2, preamble


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


def _kind(path: Path) -> str:
    suffix = "".join(path.suffixes[-2:]).lower()
    return next((k for k in ("npy", "parquet") if suffix.endswith("." + k)), "csv")


def _kept(names: list[str], columns: Sequence[str] | None, scale: Mapping[str, float],
          src: str) -> list[str] | None:
    """Return the columns to read (None: all): those asked for, the time and the scaled ones."""
    unknown = [c for c in scale if c not in names]
    if unknown:
        raise InputError(f"{src}: --scale names no column {unknown[0]!r}"
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
            keep: list[str] | None) -> tuple[Iterator[_Block], int | None]:
    """Yield the kept columns, ``CHUNK_ROWS`` rows at a time; and the row count if known."""
    kind = _kind(path)
    if kind == "npy":
        arr = _open_npy(path)
        return _npy_blocks(arr, names, keep), len(arr)
    if kind == "parquet":
        return _parquet_blocks(path, keep), _parquet_file(path).metadata.num_rows
    return _csv_blocks(path, skip, keep), None


def _convert(blocks: Iterator[_Block], n_rows: int | None, src: str,
             first_line: int) -> dict[str, np.ndarray]:
    """Gather the blocks' columns as finite float64, or an error naming the first bad cell.

    With the row count known (``.npy``, Parquet) each column is written into an
    array of its final length, so the record is never held twice.  The time
    column is checked block by block (a time that goes backwards, or does not
    advance over a whole block, fails there), and the memory the columns take
    is held to :func:`_memory_budget`, so a file far larger than the machine
    fails early (at its first block, when its length is known) and says how
    much it would take.
    """
    columns = _Columns(n_rows, src)
    for block in blocks:
        converted = {str(c): _numeric(block[c], src, str(c), first_line, columns.offset)
                     for c in block}
        _check_time_block(converted, columns.last_time, src, first_line, columns.offset)
        columns.add(converted)
    data = columns.gathered()
    for name, arr in data.items():
        _check_finite(arr, src, name, first_line)
    return data


class _Columns:
    """Float64 columns filled block by block, into their final arrays when the length is known."""

    def __init__(self, n_rows: int | None, src: str) -> None:
        self.n_rows, self.src, self.offset = n_rows, src, 0
        self.budget = _memory_budget()
        self.parts: dict[str, list[np.ndarray]] = {}
        self.full: dict[str, np.ndarray] = {}
        self.last_time = np.empty(0)  # the time column's last value so far

    def add(self, block: dict[str, np.ndarray]) -> None:
        if not block:
            return
        rows = len(next(iter(block.values())))
        self._check_budget(rows, len(block))
        time_name = next((c for c in TIME_COLUMNS if c in block), None)
        for name, values in block.items():
            if self.n_rows is None:
                self.parts.setdefault(name, []).append(values)
            else:
                self.full.setdefault(name, np.empty(self.n_rows))[
                    self.offset : self.offset + rows] = values
            if name == time_name and rows:
                self.last_time = values[-1:].copy()
        self.offset += rows

    def _check_budget(self, rows: int, width: int) -> None:
        total = self.n_rows if self.n_rows is not None else self.offset + rows
        held = total * 8 * width
        if held > self.budget:
            verb = "take" if self.n_rows is not None else "already take"
            raise InputError(f"{self.src}: too large to read: {total:,} rows of {width} "
                             f"column(s) {verb} {held / 2**30:.1f} GiB as float64, more "
                             f"than the {self.budget / 2**30:.1f} GiB this machine has free; "
                             "read fewer columns (--column) or a shorter stretch")

    def gathered(self) -> dict[str, np.ndarray]:
        if self.n_rows is not None:
            return {name: x[: self.offset] for name, x in self.full.items()}
        return {name: np.concatenate(p) if len(p) > 1 else p[0] for name, p in self.parts.items()}


def _check_time_block(block: dict[str, np.ndarray], previous: np.ndarray, src: str,
                      first_line: int, offset: int) -> None:
    """Check the time column of a block (``offset`` its first sample).

    It must not go backwards (from ``previous``, the last time of the block before,
    on either), nor stand still over a whole block (no sensor repeats its time
    that long).
    """
    name = next((c for c in TIME_COLUMNS if c in block), None)
    if name is None:
        return
    time = np.concatenate([previous, block[name]])
    if not _within(time, _MAX_ABS):  # the finite and magnitude checks name the cell
        return
    _check_order(time, np.diff(time), src, name, first_line, repeats_allowed=True,
                 offset=offset - len(previous))
    rows = block[name]
    if len(rows) >= _STILL_ROWS and rows[-1] == rows[0]:
        raise InputError(f"{src}: column {name!r}, {_where(offset + 1, first_line)}: time repeats "
                         f"({float(rows[0])!r} then {float(rows[1])!r}) and does not advance "
                         f"over {len(rows):,} rows")


def _within(x: np.ndarray, bound: float) -> bool:
    """Whether every value is finite and within +-bound: two reductions, no temporary array."""
    if not x.size:
        return True
    lo, hi = x.min(), x.max()  # a NaN anywhere makes both NaN
    return bool(np.isfinite(lo) and np.isfinite(hi) and -bound <= lo and hi <= bound)


def _memory_budget() -> int:
    """Return the bytes the kept columns may take: most of the machine's free memory.

    ``FOSMODEL_MAX_MEMORY`` (in bytes) sets it.
    """
    if "FOSMODEL_MAX_MEMORY" in os.environ:
        return int(float(os.environ["FOSMODEL_MAX_MEMORY"]))
    try:
        free = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 2**62
    return int(0.6 * free)


def _find_preamble(path: Path) -> _Preamble:
    """Locate the header: the first all-names line followed by a numeric row of as many fields.

    The lines before it are a preamble when each is a ``key,value`` pair with a
    non-numeric key (blank lines allowed).  Otherwise (a units row under a
    header of three or more columns, say), or when no such header is found, the
    header is the first line and the usual checks report what is wrong.
    """
    try:
        rows = list(csv.reader(_head_lines(path, _PREAMBLE_MAX_LINES + 1), skipinitialspace=True))
    except csv.Error:  # a field over the csv module's limit, say: pandas says what is wrong
        return _Preamble(0, [])
    header = next((i for i in range(len(rows) - 1)
                   if _is_names(rows[i]) and _is_numbers(rows[i + 1], len(rows[i]))), 0)
    before = rows[:header]
    if any(row and (len(row) != 2 or not _is_names(row[:1])) for row in before):
        return _Preamble(0, [])
    return _Preamble(header, [(n + 1, r[0].strip(), r[1].strip()) for n, r in enumerate(before)
                              if r])


def _head_lines(path: Path, n: int) -> list[str]:
    opener = _OPENERS.get(path.suffix.lower(), open)
    try:
        with opener(path, "rt", errors="replace", newline="") as fh:
            return list(itertools.islice(fh, n))
    except (OSError, EOFError, lzma.LZMAError):  # a damaged file: pandas says what is wrong
        return []


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _is_names(row: list[str]) -> bool:
    return bool(row) and all(c.strip() and not _is_number(c) for c in row)


def _is_numbers(row: list[str], width: int) -> bool:
    return len(row) == width and all(_is_number(c) for c in row)


_CSV_OPTIONS = {"sep": ",", "skipinitialspace": True}


def _csv_names(path: Path, skip: int) -> list[str]:
    """Return the header on line ``skip + 1``, as written (pandas would rename a repeated name)."""
    try:
        names = pd.read_csv(path, header=None, nrows=1, dtype=str, keep_default_na=False,
                            skiprows=skip, **_CSV_OPTIONS).iloc[0].tolist()
    except Exception as exc:  # noqa: BLE001 - one message for every way a read can fail
        raise _csv_error(path, skip, exc) from None
    _check_header(path, skip, names)
    unnamed = [i for i, n in enumerate(names) if not str(n).strip()]
    if unnamed:
        raise InputError(f"{path}: column {unnamed[0] + 1} has no name")
    return [str(n) for n in names]


def _csv_blocks(path: Path, skip: int, keep: list[str] | None) -> Iterator[pd.DataFrame]:
    """Yield the rows under the header, in blocks.

    ``index_col=False``: a first data row longer than the header is an error,
    never a silent shift of the columns onto an index.  Every field is parsed
    (pandas' ``usecols`` would drop a row's extra fields without a word) and
    the ``keep`` columns taken from each block; a row shorter than the header
    (its last field missing) is refused even when that column is not kept,
    since the missing field may be any of them.
    """
    try:
        with warnings.catch_warnings(), _source(path) as source:
            warnings.simplefilter("error", pd.errors.ParserWarning)
            with pd.read_csv(source, low_memory=False, index_col=False, skiprows=skip,
                             chunksize=CHUNK_ROWS, **_CSV_OPTIONS) as reader:
                first_line = skip + 2
                for block in reader:
                    if keep is not None:
                        _check_last_field(block, keep, path, first_line)
                        first_line += len(block)
                    yield block if keep is None else block[keep]
    except Exception as exc:  # noqa: BLE001 - one message for every way a read can fail
        raise _csv_error(path, skip, exc) from None


@contextlib.contextmanager
def _source(path: Path):
    """Give the file to parse: its path, or for a compressed file a capped stream.

    The stream stops (InputError) once it has given more than ``_EXPANSION`` times the file's
    size (and ``_EXPANSION_FLOOR``).
    """
    opener = _OPENERS.get(path.suffix.lower())
    if opener is None:
        yield path
        return
    limit = max(_EXPANSION * path.stat().st_size, _EXPANSION_FLOOR)
    with opener(path, "rb") as raw:
        yield _Capped(raw, limit, path)


class _Capped(io.RawIOBase):
    """A binary stream that refuses to give more than ``limit`` bytes."""

    def __init__(self, raw: IO[bytes], limit: int, path: Path) -> None:
        self.raw, self.limit, self.path, self.given = raw, limit, path, 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: WriteableBuffer) -> int:
        view = memoryview(buffer).cast("B")
        data = self.raw.read(len(view))
        self.given += len(data)
        if self.given > self.limit:
            size = self.path.stat().st_size
            raise InputError(f"{self.path}: decompresses to more than {_EXPANSION} times its size "
                             f"({size:,} bytes, so far {self.given:,}); fosmodel stops there (a "
                             "damaged file, or not a record?)")
        view[: len(data)] = data
        return len(data)


def _check_last_field(block: pd.DataFrame, keep: list[str], path: Path, first_line: int) -> None:
    """Refuse a row whose last field, in a column not kept, is missing or empty."""
    last = block.columns[-1]
    if last in keep:  # checked cell by cell with the kept columns
        return
    short = np.flatnonzero(block[last].isna().to_numpy())
    if short.size:
        raise InputError(f"{path}: column {last!r}, line {first_line + short[0]}: an empty cell "
                         f"or a row shorter than the header ({block.shape[1]} fields)")


def _csv_error(path: Path, skip: int, exc: Exception) -> Exception:
    """Return the InputError for a failed CSV read (other exceptions pass through)."""
    if isinstance(exc, InputError):
        return exc
    if isinstance(exc, pd.errors.EmptyDataError):
        return InputError(f"{path}: the file is empty")
    if isinstance(exc, pd.errors.ParserWarning):
        return InputError(f"{path}: line {skip + 2} has more fields than the header on line "
                          f"{skip + 1} has names")
    if isinstance(exc, UnicodeDecodeError):
        return InputError(f"{path}: {_non_utf8_line(path)}not UTF-8 text; save the file as "
                          "UTF-8")
    if isinstance(exc, (pd.errors.ParserError, OSError, EOFError, lzma.LZMAError)):
        return InputError(f"{path}: not a readable CSV file ({error_line(exc)})")
    return exc


def _check_header(path: Path, skip: int, names: list[str]) -> None:
    """Refuse a header separated by another delimiter, or naming a column twice."""
    if len(names) == 1:
        for sep, label in ((";", "semicolons"), ("\t", "tabs"), ("|", "bars")):
            if sep in names[0]:
                raise InputError(
                    f"{path}: the header {names[0]!r} looks separated by {label}; "
                    "fosmodel reads comma-separated files"
                )
    twice = [i + 1 for i, name in enumerate(names) if name and names.count(name) > 1]
    if twice:
        raise InputError(f"{path}: line {skip + 1}: column name {names[twice[0] - 1]!r} appears "
                         f"{len(twice)} times in the header (columns "
                         f"{', '.join(map(str, twice))}); names must be unique")


def _non_utf8_line(path: Path) -> str:
    """``"line N: "`` for the first line of ``path`` that is not UTF-8 text, if it can be read."""
    with contextlib.suppress(OSError, EOFError, lzma.LZMAError):  # damaged: no line to name
        with _OPENERS.get(path.suffix.lower(), open)(path, "rb") as fh:
            for number, line in enumerate(fh, 1):
                try:
                    line.decode("utf-8")
                except UnicodeDecodeError:
                    return f"line {number}: "
    return ""


def _open_npy(path: Path) -> np.ndarray:
    """Open the array memory-mapped: blocks are read from it as they are converted."""
    try:
        arr = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise InputError(f"{path}: not a readable .npy file ({error_line(exc)})") from None
    if not isinstance(arr, np.ndarray):  # np.load opens an .npz archive whatever its name
        raise InputError(f"{path}: an .npz archive, not a .npy array")
    return arr


def _npy_names(arr: np.ndarray, path: Path) -> list[str]:
    if arr.dtype.names:
        if arr.ndim != 1 or any(arr.dtype[name].shape for name in arr.dtype.names):
            raise InputError(f"{path}: a structured .npy record must be 1-D with one number per "
                             f"field, got shape {arr.shape} of {arr.dtype}")
        return list(arr.dtype.names)
    if arr.ndim not in (1, 2):
        raise InputError(f"{path}: a .npy record must be 1-D or 2-D, got shape {arr.shape}")
    return [f"c{i}" for i in range(1 if arr.ndim == 1 else arr.shape[1])]


def _npy_blocks(arr: np.ndarray, names: list[str],
                keep: list[str] | None) -> Iterator[dict[str, np.ndarray]]:
    """Yield views of the memory-mapped rows; :func:`_convert` copies them once."""
    keep = names if keep is None else keep
    for lo in range(0, len(arr), CHUNK_ROWS):
        rows = arr[lo : lo + CHUNK_ROWS]
        if arr.dtype.names:
            yield {name: rows[name] for name in keep}
        else:
            rows = rows.reshape(len(rows), -1)
            yield {name: rows[:, names.index(name)] for name in keep}
    if not len(arr):
        yield {name: np.empty(0) for name in keep}


def _parquet_file(path: Path):
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise InputError(
            f"{path}: reading Parquet needs pyarrow: pip install 'fosmodel[parquet]'"
        ) from None
    try:
        return pq.ParquetFile(path)
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types for a damaged file
        raise InputError(f"{path}: not a readable Parquet file ({error_line(exc)})") from None


def _parquet_blocks(path: Path, keep: list[str] | None) -> Iterator[_Block]:
    file = _parquet_file(path)
    try:
        empty = True
        for batch in file.iter_batches(batch_size=CHUNK_ROWS, columns=keep):
            empty = False
            yield _arrow_columns(batch)
        if empty:
            table = file.schema_arrow.empty_table()
            yield table.select(keep or table.column_names).to_pandas()
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types for a damaged file
        raise InputError(f"{path}: not a readable Parquet file ({error_line(exc)})") from None


def _arrow_columns(batch: pa.RecordBatch) -> _Block:
    """Return a record batch as numpy columns when all are numbers without nulls, else a frame.

    pandas' conversion of a batch assembles a frame (a copy), which costs more
    than reading the batch; numbers need no frame.
    """
    import pyarrow.types as pat

    if all((pat.is_floating(c.type) or pat.is_integer(c.type)) and not c.null_count
           for c in batch.columns):
        return {name: c.to_numpy() for name, c in zip(batch.schema.names, batch.columns)}
    return batch.to_pandas()


def _where(i: int, first_line: int) -> str:
    """Sample ``i`` as a file line (CSV) or a row number (``.npy``, Parquet)."""
    return f"line {i + first_line}" if first_line else f"row {i}"


def _numeric(col: pd.Series | np.ndarray, src: str, name: str, first_line: int,
             offset: int) -> np.ndarray:
    """Return the block's column as float64; an error names its first cell that is no number.

    ``offset`` is the block's first sample.  Empty cells become NaN (reported by
    :func:`_check_finite` once the whole column is read).
    """
    if isinstance(col, np.ndarray):
        if col.dtype.kind in "fiu":
            return col.astype(float, copy=False)
        col = pd.Series(col)
    kind = _NOT_REAL.get(col.dtype.kind)
    if kind:
        raise InputError(f"{src}: column {name!r} holds {kind} ({col.dtype}); fosmodel reads real "
                         "numbers (time in seconds)")
    if not (pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col)):
        values = pd.to_numeric(col, errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & col.notna().to_numpy())
        if bad.size:
            i = int(bad[0])
            raise InputError(
                f"{src}: column {name!r}, {_where(i + offset, first_line)}: "
                f"{str(col.iloc[i])!r} is not a number"
            )
        col = values
    return col.to_numpy(dtype=float)


def _check_finite(arr: np.ndarray, src: str, name: str, first_line: int) -> None:
    if _within(arr, np.inf):
        return
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        i = int(bad[0])
        kind = "an empty cell" if np.isnan(arr[i]) else "an infinite value"
        raise InputError(
            f"{src}: column {name!r}, {_where(i, first_line)}: {kind} or NaN "
            f"({bad.size} such cell(s) in the column)"
        )


def _preamble_rate(
    preamble: _Preamble, rate: float | None, src: str, notes: list[str]
) -> tuple[float | None, str, dict[str, str]]:
    """Return the rate (given, else from the preamble), what gave it, and the other entries."""
    given_by = f"--rate {rate:g} Hz" if rate is not None else ""
    keys = [re.sub(r"[^a-z]", "", key.lower()).removesuffix("hz") for _, key, _ in
            preamble.entries]
    at = next((i for i, key in enumerate(keys) if key in _RATE_KEYS), None)
    metadata = {key: value for i, (_, key, value) in enumerate(preamble.entries) if i != at}
    if not preamble.entries:
        return rate, given_by, metadata
    said = f"preamble on lines 1-{preamble.header_index} before the header"
    if at is not None:
        line, key, value = preamble.entries[at]
        found = _factor(value)
        if found is None or not _RATE_RANGE[0] <= found <= _RATE_RANGE[1]:
            raise InputError(f"{src}: line {line}: the preamble sample rate {key},{value} is not "
                             f"a positive number of Hz from {_RATE_RANGE[0]:g} to "
                             f"{_RATE_RANGE[1]:g}")
        here = f"the preamble's {key},{value} (line {line})"
        if rate is not None and abs(found - rate) > _RATE_TOLERANCE * rate:
            raise InputError(f"{src}: {given_by} disagrees with {here}")
        said += f": sample rate {found:g} Hz from line {line} ({key},{value})"
        rate, given_by = (rate, given_by) if rate is not None else (found, here)
    if metadata:
        said += "; kept in metadata: " + ", ".join(f"{k}={v}" for k, v in metadata.items())
    notes.append(said)
    return rate, given_by, metadata


def _apply_scale(data: dict[str, np.ndarray], scale: Mapping[str, float], src: str,
                 notes: list[str]) -> None:
    for name, factor in scale.items():  # the names are checked against the header by _kept
        if not (np.isfinite(factor) and factor != 0):
            raise InputError(f"{src}: --scale {name}={factor!r}: the factor must be finite and "
                             "non-zero")
        with np.errstate(over="ignore"):  # an overflow is reported by _check_magnitude
            data[name] = data[name] * factor
    if scale:
        notes.append("scaled " + ", ".join(f"{n} by {f:.6g}" for n, f in scale.items()))


def _check_magnitude(data: dict[str, np.ndarray], scale: Mapping[str, float], src: str,
                     first_line: int) -> None:
    """Refuse values beyond ``_MAX_ABS`` (after scaling): the models' sums would overflow."""
    for name, x in data.items():
        if _within(x, _MAX_ABS):
            continue
        bad = np.flatnonzero(np.abs(x) > _MAX_ABS)
        if bad.size:
            i = int(bad[0])
            scaled = f" (scaled by {scale[name]:g})" if name in scale else ""
            raise InputError(f"{src}: column {name!r}, {_where(i, first_line)}: {x[i]:g}{scaled} "
                             f"is too large to model (over {_MAX_ABS:g} in magnitude); check its "
                             f"units or pass --scale {name}=FACTOR")


def _note_integer_columns(data: dict[str, np.ndarray], known: Collection[str],
                          notes: list[str]) -> None:
    """Note columns of integers, but those whose scale or units are ``known``."""
    integer = [n for n, x in data.items() if n not in known and _all_integers(x)]
    if integer:
        notes.append(f"column(s) {', '.join(integer)} hold only integers: if they are raw "
                     f"counts, scale them, e.g. --scale {integer[0]}=1/16384 for 16384 counts "
                     "per unit")


def _all_integers(x: np.ndarray) -> bool:
    head = x[:_INTEGER_HEAD]  # a column of readings shows a fraction within its first rows
    return np.array_equal(head, np.rint(head)) and np.array_equal(x, np.rint(x))


def _time_base(time: np.ndarray, rate: float | None, given_by: str, uniform: bool, src: str,
               name: str, first_line: int, notes: list[str],
               gaps: str = "refuse") -> tuple[float, np.ndarray]:
    """Return the rate and time of a record with a time column, after checking the column.

    With ``gaps`` that do not refuse, the gap check is left to :func:`_handle_gaps`
    and the rate is the median interval's.
    """
    if len(time) < 2:
        if rate is None:
            raise InputError(f"{src}: a single sample cannot give a rate; pass --rate")
        return rate, time
    dt = np.diff(time)
    step = median(dt)
    bursty = _is_bursty(time, dt, step)
    _check_order(time, dt, src, name, first_line, repeats_allowed=bursty)
    if not (bursty or uniform or gaps not in _REFUSING):
        _check_gaps(dt, step, src, name, first_line, segments=gaps == "refuse")
    with np.errstate(over="ignore"):  # a span of a few subnormal seconds: checked below
        measured = (len(time) - 1) / (time[-1] - time[0])  # uniform: the span is the best one
        if gaps not in _REFUSING and not (bursty or uniform):
            measured = 1.0 / step  # with gaps, the span would count them
    if not _RATE_RANGE[0] <= measured <= _RATE_RANGE[1]:
        raise InputError(f"{src}: column {name!r} gives a sample rate of {measured:.6g} Hz, "
                         f"outside {_RATE_RANGE[0]:g} to {_RATE_RANGE[1]:g} Hz; is it in seconds? "
                         f"(--scale {name}=0.001 turns milliseconds into seconds)")
    kind = "the effective rate of the bursty time column" if bursty else "the time column"
    if rate is not None and abs(measured - rate) > _RATE_TOLERANCE * rate:
        raise InputError(f"{src}: {given_by} disagrees with {kind} ({measured:.6g} Hz)")
    rate = rate if rate is not None else measured
    if bursty:
        n = len(time)
        lines = f"lines {first_line}-{first_line + n - 1}" if first_line else f"rows 0-{n - 1}"
        said = (f"column {name!r} ({lines}) looks like a host's bursty receive time (median "
                f"interval {step:.3g} s, mean {np.mean(dt):.3g} s); effective rate "
                f"{measured:.6g} Hz ((N - 1) / span)")
        if not (uniform or given_by):
            raise InputError(f"{src}: {said}: pass --uniform to take the samples as uniformly "
                             "spaced at that rate, or --rate HZ")
        notes.append(f"{said}: samples taken as uniformly spaced at {rate:.6g} Hz; time is "
                     "sample number / rate")
    elif uniform:
        n_gaps = int(np.count_nonzero(dt > 1.5 * step))
        notes.append(f"--uniform: samples taken as uniformly spaced at {rate:.6g} Hz, the rate of "
                     f"column {name!r} ({n_gaps} gap(s) in it ignored); time is sample number / "
                     "rate")
    if bursty or uniform:
        time = np.arange(len(time)) / rate
    return rate, time


def _handle_gaps(data: dict[str, np.ndarray], time: np.ndarray, gaps: str, src: str, name: str,
                 first_line: int, notes: list[str]):
    """Fill the gaps of a regular time column, or list its contiguous segments."""
    dt = np.diff(time)
    step = median(dt)
    at = np.flatnonzero(dt > 1.5 * step)
    if not at.size:
        return time, None
    where = f"first at {_where(int(at[0]) + 1, first_line)}"
    if gaps == "segments":
        bounds = [0, *(at + 1).tolist(), len(time)]
        segments = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
        notes.append(f"column {name!r}: {at.size} gap(s), {where}; kept as {len(segments)} "
                     f"contiguous segments of {', '.join(str(s.stop - s.start) for s in segments)}"
                     " samples")
        return time, segments
    grid = time[0] + step * np.arange(int(round((time[-1] - time[0]) / step)) + 1)
    for key in data:
        data[key] = np.interp(grid, time, data[key])
    notes.append(f"column {name!r}: {at.size} gap(s), {where}; filled by linear interpolation "
                 f"({len(grid) - len(time)} samples added onto the {step:.6g} s grid)")
    return grid, None


def _is_bursty(time: np.ndarray, dt: np.ndarray, step: float) -> bool:
    """Whether time is a host's receive time: most intervals far below the mean, a steady rate.

    Bursty when the record has at least ``_BURSTY_MIN_SAMPLES`` samples, the
    median interval is under half the mean interval (samples arrive in bursts
    separated by long waits), and every tenth of the time span holds within
    25 % of a tenth of the samples (unlike a record with a long gap).
    """
    if len(time) < _BURSTY_MIN_SAMPLES or not time[-1] > time[0] or np.any(dt < 0):
        return False
    if step >= 0.5 * np.mean(dt):
        return False
    counts = _tenths(time)
    return bool(np.all(np.abs(counts - len(time) / 10) <= 0.25 * len(time) / 10))


def _tenths(time: np.ndarray) -> np.ndarray:
    """Count the samples in each tenth of the span, as ``np.histogram(time, 10)`` does (sorted).

    Counted by bisection at the bin edges rather than by a pass over the record.
    """
    edges = np.linspace(time[0], time[-1], 11)
    return np.diff([*np.searchsorted(time, edges[:-1]), len(time)])


def _check_order(time: np.ndarray, dt: np.ndarray, src: str, name: str, first_line: int, *,
                 repeats_allowed: bool, offset: int = 0) -> None:
    """Refuse time that goes backwards (or repeats, unless allowed).

    ``offset`` is the sample number of ``time[0]`` in the record.
    """
    bad = np.flatnonzero(dt < 0 if repeats_allowed else dt <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        kind = "repeats" if dt[bad[0]] == 0 else "goes backwards"
        raise InputError(f"{src}: column {name!r}, {_where(offset + i, first_line)}: time {kind} "
                         f"({float(time[i - 1])!r} then {float(time[i])!r})")


def _check_gaps(dt: np.ndarray, step: float, src: str, name: str, first_line: int,
                segments: bool) -> None:
    """Refuse gaps; the message offers filling them, and fitting on the pieces if ``segments``."""
    gaps = np.flatnonzero(dt > 1.5 * step)
    if gaps.size:
        i = int(gaps[0]) + 1
        raise InputError(
            f"{src}: column {name!r}, {_where(i, first_line)}: a gap of {dt[gaps[0]]:.6g} s "
            f"where the sample interval is {step:.6g} s ({gaps.size} gap(s) in the record); "
            "pass --fill to interpolate across them"
            + (" or --segments to fit on the pieces" if segments else "")
        )


def _find_outliers(data: dict[str, np.ndarray]) -> dict[str, _Outliers]:
    """Find samples farther than ``OUTLIER_K`` robust standard deviations from the median.

    The robust standard deviation is 1.4826 times the median absolute
    deviation; when more than half the column sits on its median (MAD = 0, as
    for a die temperature on 0.09 C steps) it is the column's resolution, the
    smallest step between its values.  A constant column has no outliers.
    """
    found = {}
    buffer = np.empty(max(len(x) for x in data.values()))  # one for every column's deviations
    for name, x in data.items():
        center = median(x)
        deviation = np.abs(np.subtract(x, center, out=buffer[: len(x)]), out=buffer[: len(x)])
        sigma = _MAD_TO_SIGMA * median(deviation)
        if sigma == 0:
            steps = np.diff(np.unique(x))
            sigma = float(steps.min()) if steps.size else 0.0
        index = np.flatnonzero(deviation > OUTLIER_K * sigma)
        if sigma > 0 and index.size:
            found[name] = _Outliers(index, center - OUTLIER_K * sigma, center + OUTLIER_K * sigma)
    return found


def _positions(index: np.ndarray, first_line: int) -> str:
    shown = [int(i) for i in index[:_SHOWN]]
    more = ", ..." if index.size > _SHOWN else ""
    text = "sample(s) " + ", ".join(map(str, shown)) + more
    if first_line:
        text += " (line(s) " + ", ".join(str(i + first_line) for i in shown) + more + ")"
    return text


def _handle_outliers(record: Record, found: dict[str, _Outliers], mode: str,
                     first_line: int) -> None:
    rule = f"|x - median| > {OUTLIER_K:g} x 1.4826 MAD"
    if not found:
        if mode != "keep":
            record.notes.append(f"--outliers {mode}: no outliers found ({rule})")
        return
    done = {"keep": "kept (--outliers clip or drop handles them)", "clip": "clipped to",
            "drop": "dropped"}[mode]
    for name, out in found.items():
        bounds = f"[{out.low:.6g}, {out.high:.6g}]"
        record.notes.append(
            f"column {name!r}: {out.samples.size} outlier(s) ({rule}, outside {bounds}) at "
            f"{_positions(out.samples, first_line)}; "
            f"{done}{' ' + bounds if mode == 'clip' else ''}")
        if mode == "clip":
            record.data[name] = np.clip(record.data[name], out.low, out.high)
    if mode == "drop":
        _drop_rows(record, np.unique(np.concatenate([o.samples for o in found.values()])))


def _drop_rows(record: Record, rows: np.ndarray) -> None:
    if record.time is None:
        raise InputError(
            f"{record.source}: --outliers drop would remove {rows.size} sample(s) from a record "
            "without a time column, which breaks the uniform sample spacing the models assume; "
            "use --outliers clip (or keep)")
    keep = np.ones(record.n_samples, dtype=bool)
    keep[rows] = False
    record.data = {name: x[keep] for name, x in record.data.items()}
    record.time = record.time[keep]
    record.notes.append(
        f"dropped {rows.size} row(s) with an outlier in any column: the record is no longer "
        "uniformly spaced; its time column keeps the gaps")
