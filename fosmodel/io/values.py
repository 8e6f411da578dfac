"""A record's values: a file's blocks as float64 columns, checked and scaled.

Each block's cells become float64 (:func:`convert`; the first cell that is not a real number
is named) within the memory budget, its time column checked as it comes; a whole column
must then be finite, and within ``MAX_ABS`` once scaled (:func:`apply_scale`,
:func:`check_magnitude`); columns of raw integer counts are noted.
"""

from __future__ import annotations

import os
from collections.abc import Collection, Iterator, Mapping
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from ..core.exceptions import InputError
from .positions import where
from .timebase import STILL_ROWS, TIME_COLUMNS, check_order

if TYPE_CHECKING:  # pandas is imported where a record is read: not by the CLI's help
    import pandas as pd  # here: loaded by the first record read, not by the parser

_NOT_REAL = {"c": "complex numbers", "M": "dates", "m": "time spans"}  # by numpy dtype kind
#: Larger values overflow the sums of products the models form (degree 4 and more).
MAX_ABS = 1e30
#: Rows looked at first to tell a column of readings (a fraction there) from raw counts.
_INTEGER_HEAD = 1000
Block: TypeAlias = "pd.DataFrame | dict[str, np.ndarray]"  # a block of rows, by column


def convert(blocks: Iterator[Block], n_rows: int | None, src: str,
             first_line: int, held: dict[str, str] | None = None) -> dict[str, np.ndarray]:
    """Gather the blocks' columns as finite float64, or an error naming the first bad cell.

    With the row count known (``.npy``, Parquet) each column is written into an
    array of its final length, so the record is never held twice.  The time
    column is checked block by block (a time that goes backwards, or does not
    advance over a whole block, fails there), and the memory the columns take
    is held to :func:`_memory_budget`, so a file far larger than the machine
    fails early (at its first block, when its length is known) and says how
    much it would take.

    With ``held`` (a dict to fill), a column other than the time whose cells are no finite
    real numbers does not refuse the record: its refusal is put in ``held`` and the column
    left out (the caller refuses it if it is analysed).
    """
    columns = _Columns(n_rows, src)
    for block in blocks:
        converted = {}
        for c in block:
            name = str(c)
            if held is not None and name in held:
                continue
            try:
                converted[name] = _numeric(block[c], src, name, first_line, columns.offset)
            except InputError as exc:
                if held is None or name in TIME_COLUMNS:
                    raise
                held[name] = str(exc)
                columns.forget(name)
        _check_time_block(converted, columns.last_time, src, first_line, columns.offset)
        columns.add(converted)
    data = columns.gathered()
    for name in list(data):
        try:
            _check_finite(data[name], src, name, first_line)
        except InputError as exc:
            if held is None or name in TIME_COLUMNS:
                raise
            held[name] = str(exc)
            del data[name]
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
                self.full.setdefault(name, np.empty(self.n_rows, dtype=values.dtype))[
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
                             "read fewer columns (columns=) or a shorter stretch")

    def forget(self, name: str) -> None:
        """Drop a column read so far (one left out of the record)."""
        self.parts.pop(name, None)
        self.full.pop(name, None)

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
    if not _within(time, MAX_ABS):  # the finite and magnitude checks name the cell
        return
    check_order(time, np.diff(time), src, name, first_line, repeats_allowed=True,
                 offset=offset - len(previous))
    rows = block[name]
    if len(rows) >= STILL_ROWS and rows[-1] == rows[0]:
        raise InputError(f"{src}: column {name!r}, {where(offset + 1, first_line)}: time repeats "
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


def _numeric(col: pd.Series | np.ndarray, src: str, name: str, first_line: int,
             offset: int) -> np.ndarray:
    """Return the block's column as float64; an error names its first cell that is no number.

    ``offset`` is the block's first sample.  Empty cells become NaN (reported by
    :func:`_check_finite` once the whole column is read).
    """
    import pandas as pd  # here: loaded by the first record read, not by the parser

    if name in TIME_COLUMNS and col.dtype.kind in "iu" and _fits_int64(col):
        return np.asarray(col, dtype=np.int64)  # counts, differenced as integers
    if isinstance(col, np.ndarray):
        if col.dtype.kind in "fiu":
            return col.astype(float, copy=False)
        col = pd.Series(col)
    kind = _NOT_REAL.get(col.dtype.kind)
    if kind:
        raise InputError(f"{src}: column {name!r} holds {kind} ({col.dtype}); fosmodel reads real "
                         "numbers (time in seconds)")
    if col.dtype.kind == "b" or (col.dtype == object
                                 and pd.api.types.infer_dtype(col, skipna=True) == "boolean"):
        raise InputError(f"{src}: column {name!r} holds booleans (True/False), not a sensor's "
                         "readings; read the signal's columns only")
    if not pd.api.types.is_numeric_dtype(col):
        values = pd.to_numeric(col, errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & col.notna().to_numpy())
        if bad.size:
            i = int(bad[0])
            raise InputError(
                f"{src}: column {name!r}, {where(i + offset, first_line)}: "
                f"{str(col.iloc[i])!r} is not a number"
            )
        col = values
    return col.to_numpy(dtype=float)


def _fits_int64(col: pd.Series | np.ndarray) -> bool:
    """Whether a column of integers fits in int64 (a uint64 one may not)."""
    return col.dtype.kind == "i" or not len(col) or int(np.max(col)) < 2**63


def _check_finite(arr: np.ndarray, src: str, name: str, first_line: int) -> None:
    if _within(arr, np.inf):
        return
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        i = int(bad[0])
        kind = "an empty cell" if np.isnan(arr[i]) else "an infinite value"
        raise InputError(
            f"{src}: column {name!r}, {where(i, first_line)}: {kind} or NaN "
            f"({bad.size} such cell(s) in the column)"
        )


def apply_scale(data: dict[str, np.ndarray], scale: Mapping[str, float], src: str,
                 notes: list[str]) -> None:
    """Multiply each column named in ``scale`` by its factor, and note it."""
    for name, factor in scale.items():  # the names are checked against the header by _kept
        if name not in data:  # a column left out (its refusal held): nothing to scale
            continue
        if not (np.isfinite(factor) and factor != 0):
            raise InputError(f"{src}: scale={{{name!r}: {factor!r}}}: the factor must be finite "
                             "and non-zero")
        with np.errstate(over="ignore"):  # an overflow is reported by check_magnitude
            data[name] = data[name] * factor
    if scale:
        notes.append("scaled " + ", ".join(f"{n} by {f:.6g}" for n, f in scale.items()))


def check_magnitude(data: dict[str, np.ndarray], scale: Mapping[str, float], src: str,
                     first_line: int) -> None:
    """Refuse values beyond ``MAX_ABS`` (after scaling): the models' sums would overflow."""
    for name, x in data.items():
        if _within(x, MAX_ABS):
            continue
        bad = np.flatnonzero(np.abs(x) > MAX_ABS)
        if bad.size:
            i = int(bad[0])
            scaled = f" (scaled by {scale[name]:g})" if name in scale else ""
            raise InputError(f"{src}: column {name!r}, {where(i, first_line)}: {x[i]:g}{scaled} "
                             f"is too large to model (over {MAX_ABS:g} in magnitude); check its "
                             f"units or pass scale={{{name!r}: FACTOR}}")


def note_integer_columns(data: dict[str, np.ndarray], known: Collection[str],
                          notes: list[str]) -> None:
    """Note columns of integers, but those whose scale or units are ``known``."""
    integer = [n for n, x in data.items() if n not in known and _all_integers(x)]
    if integer:
        notes.append(f"column(s) {', '.join(integer)} hold only integers: if they are raw "
                     f"counts, scale them, e.g. scale={{{integer[0]!r}: 1/16384}} for 16384 counts "
                     "per unit")


def _all_integers(x: np.ndarray) -> bool:
    head = x[:_INTEGER_HEAD]  # a column of readings shows a fraction within its first rows
    return np.array_equal(head, np.rint(head)) and np.array_equal(x, np.rint(x))


def number_or_ratio(text: str) -> float | None:
    """Read ``FLOAT`` or ``A/B`` as a finite non-zero number; None if it is not one."""
    num, sep, den = text.partition("/")
    try:
        value = float(num) / float(den) if sep else float(num)
    except (ValueError, ZeroDivisionError):
        return None
    return value if np.isfinite(value) and value != 0 else None
