"""``.npy`` records: a structured array (its field names are the columns), or a 1-D or 2-D one.

A 1-D array is one column ``c0``, a 2-D one columns ``c0``, ``c1``, ...  The file is
memory-mapped and read in blocks of rows.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..core.exceptions import InputError, error_line
from .csv_reader import Preamble


def read_header(path: Path) -> tuple[list[str], int, Preamble]:
    """Column names; rows, not lines, and no preamble."""
    return _npy_names(_open_npy(path), path), 0, Preamble(0, [])


def read_blocks(path: Path, skip: int, names: list[str], keep: list[str] | None,
                chunk_rows: int) -> tuple[Iterator[dict[str, np.ndarray]], int]:
    """Yield the kept columns, ``chunk_rows`` rows at a time; and the row count."""
    arr = _open_npy(path)
    return _npy_blocks(arr, names, keep, chunk_rows), len(arr)


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


def _npy_blocks(arr: np.ndarray, names: list[str], keep: list[str] | None,
                chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
    """Yield views of the memory-mapped rows; :func:`~fosmodel.io.values.convert` copies them."""
    keep = names if keep is None else keep
    for lo in range(0, len(arr), chunk_rows):
        rows = arr[lo : lo + chunk_rows]
        if arr.dtype.names:
            yield {name: rows[name] for name in keep}
        else:
            rows = rows.reshape(len(rows), -1)
            yield {name: rows[:, names.index(name)] for name in keep}
    if not len(arr):
        yield {name: np.empty(0) for name in keep}
