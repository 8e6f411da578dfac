"""Compressed records: the openers by suffix, and the stream that bounds what they give.

A CSV named ``.gz``, ``.bz2`` or ``.xz`` is decompressed as it is read, through
:class:`BoundedStream`, which refuses (an :class:`InputError` saying the limit) once it has
given more than the file may hold, ``EXPANSION`` times its size (at least
``EXPANSION_FLOOR``), or a line longer than ``MAX_LINE``: a line is what a parser holds whole,
and a file of one endless line (a megabyte of gzip that expands to a gibibyte of zeros) is no
record.  Every read of a record goes through it, the first lines where the header is looked for
(:func:`head`, at most ``HEAD_BYTES`` of them, compressed or not) as much as the rows
(:func:`capped_source`), so that a few megabytes of a file never make fosmodel hold gigabytes.
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
#: The longest line of a record (a row of a thousand columns of 30 characters takes 30 kB).
MAX_LINE = 16 * 2**20
#: The most read of a file's head to find its header (a preamble of 50 lines, then the header).
HEAD_BYTES = 2**20


class BoundedStream(io.RawIOBase):
    """A binary stream that refuses to give more than ``limit`` bytes, or a line over ``MAX_LINE``.

    Parameters
    ----------
    raw : binary file
        The decompressing stream.
    path : Path
        The file, for the messages.
    limit : int
        The most bytes it gives.
    """

    def __init__(self, raw: IO[bytes], path: Path, limit: int) -> None:
        self.raw, self.path, self.limit = raw, path, limit
        self.given = 0
        self.line = 0  # bytes of the current line so far
        self.lines = 1  # the current line's number

    def readable(self) -> bool:
        """Return True: the stream is read."""
        return True

    def readinto(self, buffer: WriteableBuffer) -> int:
        """Read into ``buffer`` from the decompressing stream, within the limits."""
        view = memoryview(buffer).cast("B")
        data = self.raw.read(min(len(view), self.limit + 1 - self.given))
        self.given += len(data)
        if self.given > self.limit:
            size = self.path.stat().st_size
            raise InputError(f"{self.path}: decompresses to more than {EXPANSION} times its size "
                             f"({size:,} bytes): fosmodel stops at {self.limit:,} bytes (a damaged "
                             "file, or not a record?)")
        self._count_lines(data)
        view[: len(data)] = data
        return len(data)

    def _count_lines(self, data: bytes) -> None:
        last = data.rfind(b"\n")
        self.line = self.line + len(data) if last < 0 else len(data) - last - 1
        self.lines += data.count(b"\n")
        if self.line > MAX_LINE:
            raise InputError(f"{self.path}: line {self.lines} is longer than "
                             f"{MAX_LINE // 2**20} MiB once decompressed: fosmodel stops there "
                             "(a damaged file, or not a record?)")


def is_compressed(path: Path) -> bool:
    """Whether ``path`` is read through a decompressor (by its suffix)."""
    return path.suffix.lower() in OPENERS


@contextlib.contextmanager
def capped_source(path: Path) -> Iterator[Path | io.RawIOBase]:
    """Give the file to parse: its path, or for a compressed file a :class:`BoundedStream`."""
    if not is_compressed(path):
        yield path
        return
    limit = max(EXPANSION * path.stat().st_size, EXPANSION_FLOOR)
    with OPENERS[path.suffix.lower()](path, "rb") as raw:
        yield BoundedStream(raw, path, limit)


def head(path: Path, n_lines: int) -> bytes:
    """Return the first ``n_lines`` lines of a file, decompressed, read no further than needed.

    At most ``HEAD_BYTES`` are read: a line that does not end within them ends the head (its
    start is returned), so that a file of one endless line costs no more than that.
    """
    with capped_source(path) as source:
        stream = (open(source, "rb") if isinstance(source, Path)  # noqa: SIM115 - closed below
                  else io.BufferedReader(source))
        with stream:
            lines: list[bytes] = []
            size = 0
            while len(lines) < n_lines and size < HEAD_BYTES:
                line = stream.readline(HEAD_BYTES - size)
                if not line:
                    break
                lines.append(line)
                size += len(line)
    return b"".join(lines)


def head_lines(path: Path, n_lines: int) -> list[str]:
    """Return the first ``n_lines`` lines of a file as text (bytes not UTF-8 replaced).

    Lines end as those of a text file read with ``newline=""`` do: at LF, CR or CR LF.
    """
    text = head(path, n_lines).decode("utf-8", errors="replace")
    return list(io.StringIO(text, newline=""))[:n_lines]
