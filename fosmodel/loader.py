"""Load and validate a sensor record from CSV, ``.npy`` or Parquet.

This is the one place where files are read and checked.  Every problem is an
:class:`~fosmodel.exceptions.InputError` naming the file, the column and the
first offending row (CSV rows are counted as file lines, the header being
line 1).

Formats
-------
CSV
    One header row of column names, comma-separated, then one row per
    sample.  An optional time column (``time``, ``time_s`` or ``t_s``, in
    seconds) gives the sample rate; otherwise pass ``rate``.
``.npy``
    A structured array (its field names are the columns), a 1-D array (one
    column ``c0``) or a 2-D array (columns ``c0``, ``c1``, ...).
Parquet
    Read with pandas when pyarrow is installed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .exceptions import InputError
from .validation import did_you_mean

TIME_COLUMNS = ("time", "time_s", "t_s")
_RATE_TOLERANCE = 0.01


@dataclass
class Record:
    """A validated record: equally long, finite float columns and their sample rate.

    Attributes
    ----------
    source : str
        File it came from.
    data : dict of str to ndarray
        Numeric columns in file order (the time column excluded).
    rate : float or None
        Sample rate in Hz (None when the file has no time and none was given).
    time : ndarray or None
        Time column in seconds, if the file had one.
    """

    source: str
    data: dict[str, np.ndarray]
    rate: float | None
    time: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def n_samples(self) -> int:
        return len(next(iter(self.data.values())))

    @property
    def names(self) -> list[str]:
        return list(self.data)

    def column(self, name: str) -> np.ndarray:
        """One column by name; a missing name gets the closest existing one suggested."""
        if name not in self.data:
            raise InputError(
                f"{self.source}: no column {name!r}{did_you_mean(name, self.data)}; "
                f"columns: {', '.join(self.data)}"
            )
        return self.data[name]

    def require_rate(self) -> float:
        if self.rate is None:
            raise InputError(f"{self.source}: no time column; give the sample rate with --rate HZ")
        return self.rate


def load_record(path: str | Path, *, rate: float | None = None) -> Record:
    """Read and validate a record.

    Parameters
    ----------
    path : str or Path
        CSV (optionally gzip-compressed), ``.npy`` or ``.parquet`` file.
    rate : float, optional
        Sample rate in Hz.  Required when the file has no time column; checked
        against the time column when it has one.

    Returns
    -------
    Record

    Raises
    ------
    InputError
        Missing or empty file, no data rows, a non-numeric or non-finite cell,
        a time column that is not strictly increasing or not uniform, or a
        rate that disagrees with it.
    """
    path = Path(path)
    src = str(path)
    if rate is not None and not (np.isfinite(rate) and rate > 0):
        raise InputError(f"the sample rate must be a positive number of Hz, got {rate!r}")
    if not path.is_file():
        raise InputError(f"{src}: no such file")
    if path.stat().st_size == 0:
        raise InputError(f"{src}: the file is empty")
    suffix = "".join(path.suffixes[-2:]).lower()
    if suffix.endswith(".npy"):
        frame, first_line = _read_npy(path), 0
    elif suffix.endswith(".parquet"):
        frame, first_line = _read_parquet(path), 0
    else:
        frame, first_line = _read_csv(path), 2
    if frame.shape[1] == 0:
        raise InputError(f"{src}: no columns")
    if len(frame) == 0:
        raise InputError(f"{src}: header only, no data rows")
    data = {str(c): _numeric(frame[c], src, str(c), first_line) for c in frame.columns}
    time_name = next((c for c in TIME_COLUMNS if c in data), None)
    time = data.pop(time_name) if time_name else None
    if not data:
        raise InputError(f"{src}: only a time column, no data columns")
    notes: list[str] = []
    if time is not None:
        rate = _rate_from_time(time, rate, src, time_name, first_line, notes)
    return Record(src, data, float(rate) if rate is not None else None, time, notes)


def _read_csv(path: Path) -> pd.DataFrame:
    try:
        frame = pd.read_csv(path, sep=",", skipinitialspace=True, low_memory=False)
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: the file is empty") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not a readable CSV file ({_first_line(exc)})") from None
    if frame.shape[1] == 1:
        header = str(frame.columns[0])
        for sep, label in ((";", "semicolons"), ("\t", "tabs"), ("|", "bars")):
            if sep in header:
                raise InputError(
                    f"{path}: the header {header!r} looks separated by {label}; "
                    "fosmodel reads comma-separated files"
                )
    unnamed = [c for c in frame.columns if str(c).startswith("Unnamed:")]
    if unnamed:
        raise InputError(f"{path}: column {frame.columns.get_loc(unnamed[0]) + 1} has no name")
    return frame


def _read_npy(path: Path) -> pd.DataFrame:
    try:
        arr = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise InputError(f"{path}: not a readable .npy file ({_first_line(exc)})") from None
    if arr.dtype.names:
        return pd.DataFrame({name: arr[name] for name in arr.dtype.names})
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise InputError(f"{path}: a .npy record must be 1-D or 2-D, got shape {arr.shape}")
    return pd.DataFrame(arr, columns=[f"c{i}" for i in range(arr.shape[1])])


def _read_parquet(path: Path) -> pd.DataFrame:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise InputError(
            f"{path}: reading Parquet needs pyarrow: pip install 'fosmodel[parquet]'"
        ) from None
    try:
        return pd.read_parquet(path)
    except Exception as exc:  # pyarrow raises many types for a damaged file
        raise InputError(f"{path}: not a readable Parquet file ({_first_line(exc)})") from None


def _first_line(exc: BaseException) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__


def _numeric(col: pd.Series, src: str, name: str, first_line: int) -> np.ndarray:
    """The column as finite float64, or an error naming the first bad row."""
    where = "line" if first_line else "row"
    if not (pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col)):
        values = pd.to_numeric(col, errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & col.notna().to_numpy())
        if bad.size:
            i = int(bad[0])
            raise InputError(
                f"{src}: column {name!r}, {where} {i + first_line}: "
                f"{str(col.iloc[i])!r} is not a number"
            )
        col = values
    arr = col.to_numpy(dtype=float)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        i = int(bad[0])
        kind = "an empty cell" if np.isnan(arr[i]) else "an infinite value"
        raise InputError(
            f"{src}: column {name!r}, {where} {i + first_line}: {kind} or NaN "
            f"({bad.size} such cell(s) in the column)"
        )
    return arr


def _rate_from_time(time, rate, src, name, first_line, notes) -> float:
    where = "line" if first_line else "row"
    if len(time) < 2:
        if rate is None:
            raise InputError(f"{src}: a single sample cannot give a rate; pass --rate")
        return rate
    dt = np.diff(time)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        kind = "repeats" if dt[bad[0]] == 0 else "goes backwards"
        raise InputError(f"{src}: column {name!r}, {where} {i + first_line}: time {kind} "
                         f"({time[i - 1]!r} then {time[i]!r})")
    step = float(np.median(dt))
    gaps = np.flatnonzero(dt > 1.5 * step)
    if gaps.size:
        i = int(gaps[0]) + 1
        raise InputError(
            f"{src}: column {name!r}, {where} {i + first_line}: a gap of {dt[gaps[0]]:.6g} s "
            f"where the sample interval is {step:.6g} s ({gaps.size} gap(s) in the record)"
        )
    measured = (len(time) - 1) / (time[-1] - time[0])  # uniform: the span is the best estimate
    if rate is not None and abs(measured - rate) > _RATE_TOLERANCE * rate:
        raise InputError(f"{src}: --rate {rate:g} Hz disagrees with the time column "
                         f"({measured:.6g} Hz)")
    notes.append(f"sample rate {measured:.6g} Hz from column {name!r}")
    return rate if rate is not None else measured
