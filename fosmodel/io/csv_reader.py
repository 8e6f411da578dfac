"""CSV records: a preamble, a header row of names, then one row per sample.

Optional ``key,value`` preamble lines (``Fs,100`` gives the sample rate,
:func:`preamble_rate`), one header row of column names, comma-separated, then one row per
sample, read by pandas in blocks; gzip, bz2 or xz compressed when the name ends so
(:mod:`fosmodel.io.compression`).  Every way a read can fail is one message naming the line.
"""

from __future__ import annotations

import contextlib
import csv
import itertools
import lzma
import re
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd

from ..core.exceptions import InputError, error_line
from .compression import OPENERS, capped_source
from .timebase import RATE_RANGE, RATE_TOLERANCE
from .values import number_or_ratio

_PREAMBLE_MAX_LINES = 50
_RATE_KEYS = frozenset({"fs", "rate", "samplerate", "samplingrate", "samplefrequency",
                        "samplingfrequency", "outputdatarate", "odr"})


class Preamble(NamedTuple):
    """The ``key,value`` lines above a CSV's header, and where the header is."""

    header_index: int  # 0-based line of the header
    entries: list[tuple[int, str, str]]  # (file line, key, value)


def read_header(path: Path) -> tuple[list[str], int, Preamble]:
    """Column names, the file line of the first data row, the preamble."""
    preamble = _find_preamble(path)
    return _csv_names(path, preamble.header_index), preamble.header_index + 2, preamble


def read_blocks(path: Path, skip: int, names: list[str], keep: list[str] | None,
                chunk_rows: int) -> tuple[Iterator[pd.DataFrame], None]:
    """Yield the kept columns, ``chunk_rows`` rows at a time (the row count is not known)."""
    return _csv_blocks(path, skip, keep, chunk_rows), None


def preamble_rate(
    preamble: Preamble, rate: float | None, src: str, notes: list[str]
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
        found = number_or_ratio(value)
        if found is None or not RATE_RANGE[0] <= found <= RATE_RANGE[1]:
            raise InputError(f"{src}: line {line}: the preamble sample rate {key},{value} is not "
                             f"a positive number of Hz from {RATE_RANGE[0]:g} to "
                             f"{RATE_RANGE[1]:g}")
        here = f"the preamble's {key},{value} (line {line})"
        if rate is not None and abs(found - rate) > RATE_TOLERANCE * rate:
            raise InputError(f"{src}: {given_by} disagrees with {here}")
        said += f": sample rate {found:g} Hz from line {line} ({key},{value})"
        rate, given_by = (rate, given_by) if rate is not None else (found, here)
    if metadata:
        said += "; kept in metadata: " + ", ".join(f"{k}={v}" for k, v in metadata.items())
    notes.append(said)
    return rate, given_by, metadata


def _find_preamble(path: Path) -> Preamble:
    """Locate the header: the first all-names line followed by a numeric row of as many fields.

    The lines before it are a preamble when each is a ``key,value`` pair with a
    non-numeric key (blank lines allowed).  Otherwise (a units row under a
    header of three or more columns, say), or when no such header is found, the
    header is the first line and the usual checks report what is wrong.
    """
    try:
        rows = list(csv.reader(_head_lines(path, _PREAMBLE_MAX_LINES + 1), skipinitialspace=True))
    except csv.Error:  # a field over the csv module's limit, say: pandas says what is wrong
        return Preamble(0, [])
    header = next((i for i in range(len(rows) - 1)
                   if _is_names(rows[i]) and _is_numbers(rows[i + 1], len(rows[i]))), 0)
    before = rows[:header]
    if any(row and (len(row) != 2 or not _is_names(row[:1])) for row in before):
        return Preamble(0, [])
    return Preamble(header, [(n + 1, r[0].strip(), r[1].strip()) for n, r in enumerate(before)
                              if r])


def _head_lines(path: Path, n: int) -> list[str]:
    opener = OPENERS.get(path.suffix.lower(), open)
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


def _csv_blocks(path: Path, skip: int, keep: list[str] | None,
                chunk_rows: int) -> Iterator[pd.DataFrame]:
    """Yield the rows under the header, in blocks.

    ``index_col=False``: a first data row longer than the header is an error,
    never a silent shift of the columns onto an index.  Every field is parsed
    (pandas' ``usecols`` would drop a row's extra fields without a word) and
    the ``keep`` columns taken from each block; a row shorter than the header
    (its last field missing) is refused even when that column is not kept,
    since the missing field may be any of them.
    """
    try:
        with warnings.catch_warnings(), capped_source(path) as source:
            warnings.simplefilter("error", pd.errors.ParserWarning)
            with pd.read_csv(source, low_memory=False, index_col=False, skiprows=skip,
                             chunksize=chunk_rows, **_CSV_OPTIONS) as reader:
                first_line = skip + 2
                for block in reader:
                    if keep is not None:
                        _check_last_field(block, keep, path, first_line)
                        first_line += len(block)
                    yield block if keep is None else block[keep]
    except Exception as exc:  # noqa: BLE001 - one message for every way a read can fail
        raise _csv_error(path, skip, exc) from None


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
        with OPENERS.get(path.suffix.lower(), open)(path, "rb") as fh:
            for number, line in enumerate(fh, 1):
                try:
                    line.decode("utf-8")
                except UnicodeDecodeError:
                    return f"line {number}: "
    return ""
