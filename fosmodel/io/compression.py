"""Compressed records: the openers by suffix, and a stream that caps what it gives.

A CSV named ``.gz``, ``.bz2`` or ``.xz`` is read through its opener; the stream
:func:`capped_source` gives the parser stops once it has given more than ``EXPANSION`` times
the file's size, so that a small file cannot fill the memory.
"""

from __future__ import annotations

import bz2
import contextlib
import gzip
import io
import lzma
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ..core.exceptions import InputError

if TYPE_CHECKING:
    from _typeshed import WriteableBuffer

#: The openers of compressed files (their signatures differ: each is called as open is).
OPENERS: dict[str, Callable[..., Any]] = {".gz": gzip.open, ".bz2": bz2.open, ".xz": lzma.open}
#: A compressed record may decompress to this many times its size (CSV of sensor readings
#: compresses 3-20 times; a file of one repeated line, a thousand times), or at least:
EXPANSION, EXPANSION_FLOOR = 100, 64 * 2**20


@contextlib.contextmanager
def capped_source(path: Path) -> Iterator[Path | io.RawIOBase]:
    """Give the file to parse: its path, or for a compressed file a capped stream.

    The stream stops (InputError) once it has given more than ``EXPANSION`` times the file's
    size (and ``EXPANSION_FLOOR``).
    """
    opener = OPENERS.get(path.suffix.lower())
    if opener is None:
        yield path
        return
    limit = max(EXPANSION * path.stat().st_size, EXPANSION_FLOOR)
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
            raise InputError(f"{self.path}: decompresses to more than {EXPANSION} times its size "
                             f"({size:,} bytes, so far {self.given:,}); fosmodel stops there (a "
                             "damaged file, or not a record?)")
        view[: len(data)] = data
        return len(data)
