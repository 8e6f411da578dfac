"""Parquet records, read in record batches with pyarrow (the ``parquet`` extra)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.exceptions import InputError, error_line
from .csv_reader import Preamble
from .values import Block

if TYPE_CHECKING:
    import pyarrow as pa


def read_header(path: Path) -> tuple[list[str], int, Preamble]:
    """Column names; rows, not lines, and no preamble."""
    return _parquet_file(path).schema_arrow.names, 0, Preamble(0, [])


def read_blocks(path: Path, skip: int, names: list[str], keep: list[str] | None,
                chunk_rows: int) -> tuple[Iterator[Block], int]:
    """Yield the kept columns, ``chunk_rows`` rows at a time; and the row count."""
    return _parquet_blocks(path, keep, chunk_rows), _parquet_file(path).metadata.num_rows


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


def _parquet_blocks(path: Path, keep: list[str] | None,
                    chunk_rows: int) -> Iterator[Block]:
    file = _parquet_file(path)
    try:
        empty = True
        for batch in file.iter_batches(batch_size=chunk_rows, columns=keep):
            empty = False
            yield _arrow_columns(batch)
        if empty:
            table = file.schema_arrow.empty_table()
            yield table.select(keep or table.column_names).to_pandas()
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types for a damaged file
        raise InputError(f"{path}: not a readable Parquet file ({error_line(exc)})") from None


def _arrow_columns(batch: pa.RecordBatch) -> Block:
    """Return a record batch as numpy columns when all are numbers without nulls, else a frame.

    pandas' conversion of a batch assembles a frame (a copy), which costs more
    than reading the batch; numbers need no frame.
    """
    import pyarrow.types as pat

    if all((pat.is_floating(c.type) or pat.is_integer(c.type)) and not c.null_count
           for c in batch.columns):
        return {name: c.to_numpy() for name, c in zip(batch.schema.names, batch.columns)}
    return batch.to_pandas()
