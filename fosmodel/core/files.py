"""Files written whole or not at all, and regular files read bounded with one-line errors.

Every file fosmodel writes goes through :func:`atomic_write`: the content is written to a
temporary file in the destination directory and renamed over the destination, so an
interrupted run never leaves a half-written result.  The temporary file's name carries the
writer's process id: one left behind by a killed run is removed by the next write to the
same destination.  Here, at the bottom of the layers, so that a fitted model can save itself
(:meth:`fosmodel.models.model.FOSModel.save`); :mod:`fosmodel.io.output` builds reports on it.

Every file fosmodel reads whole into memory (a model file) goes through :func:`read_bounded`:
a path that is no regular file (a FIFO, a device such as ``/dev/zero``, a directory) is refused
from its metadata, and at most a given number of bytes is read.  Here too, so that
``FOSModel.load`` and the commands' ``read_model`` share the one bounded read.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import stat
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

from .exceptions import InputError


def temporary_path(path: Path, suffix: str) -> Path:
    """Return a fresh name beside ``path`` that carries this process's id."""
    return path.parent / f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}{suffix}"


def stale_temporaries(path: Path, suffix: str) -> Iterator[Path]:
    """Temporary files or directories for ``path`` whose writer is no longer running."""
    pattern = re.compile(rf"^\.{re.escape(path.name)}\.(\d+)\.[0-9a-f]{{12}}{re.escape(suffix)}$")
    with contextlib.suppress(OSError):
        for item in path.parent.iterdir():
            m = pattern.match(item.name)
            if m and not _alive(int(m.group(1))):
                yield item


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_path(item: Path) -> None:
    """Remove a file or a directory tree, if it is still there."""
    if item.is_dir() and not item.is_symlink():
        shutil.rmtree(item, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            item.unlink()


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "w", *,
                 replace: Callable[[Path, Path], None] = os.replace,
                 stale: tuple[str, ...] = (".tmp",)) -> Iterator[IO]:
    """Open a temporary file beside ``path``; rename it onto ``path`` on success.

    Parameters
    ----------
    path : path-like
        Destination.  Its directory must exist.
    mode : {"w", "wb"}
        Text or binary mode.
    replace : callable, default os.replace
        Puts the written temporary file in place: ``replace(temporary, path)``
        (:mod:`fosmodel.io.output` passes one that can undo it).
    stale : tuple of str, default (".tmp",)
        Suffixes of the files beside ``path`` that a killed writer may have left; removed
        before writing.

    Yields
    ------
    file object
        Write the content to it.  If the body raises, the temporary file is
        removed and ``path`` is left untouched.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', not {mode!r}")
    path = Path(path)
    for suffix in stale:  # left behind by a killed run
        for item in stale_temporaries(path, suffix):
            remove_path(item)
    tmp = temporary_path(path, ".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, _mode())
    try:
        fh = (os.fdopen(fd, "w", encoding="utf-8", newline="") if mode == "w"
              else os.fdopen(fd, "wb"))
        with fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_write(path, "w") as fh:
        fh.write(text)


def _mode() -> int:
    """Return the permission bits of a new file under the process's umask (0666 & ~umask)."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def read_bounded(path: str | os.PathLike[str], what: str, max_bytes: int) -> bytes:
    """Return the bytes of ``path``, a regular file of at most ``max_bytes``; refuse anything else.

    What the path is comes from its metadata before it is opened, and again from the opened
    file (it may have been swapped between the two); the file is opened without blocking, so
    that a FIFO swapped in is refused rather than waited on, and a device such as
    ``/dev/zero`` is never read to its (missing) end.

    Parameters
    ----------
    path : path-like
        The file.
    what : str
        What the caller reads (``"model"``), named in every message.
    max_bytes : int
        The largest file read.

    Raises
    ------
    InputError
        The path cannot be read, is no regular file, or holds more than ``max_bytes`` (the
        message names it and why).
    """
    path = Path(path)
    try:
        _check_regular(path, os.stat(path), what)
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as exc:
        raise InputError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        _check_regular(path, info, what)
        if info.st_size > max_bytes:
            raise InputError(f"{path}: not a {what} file ({info.st_size:,} bytes; a {what} file "
                             f"holds at most {max_bytes // 2**20} MiB)")
        chunks, size = [], 0
        while size <= max_bytes:
            chunk = os.read(fd, min(2**20, max_bytes + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise InputError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if size > max_bytes:  # it grew while read
        raise InputError(f"{path}: not a {what} file (over {max_bytes:,} bytes; a {what} file "
                         f"holds at most {max_bytes // 2**20} MiB)")
    return b"".join(chunks)


def _check_regular(path: Path, info: os.stat_result, what: str) -> None:
    if stat.S_ISREG(info.st_mode):
        return
    kind = ("a directory" if stat.S_ISDIR(info.st_mode) else
            "a FIFO" if stat.S_ISFIFO(info.st_mode) else
            "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode) else
            "a socket" if stat.S_ISSOCK(info.st_mode) else "not a regular file")
    target = f" ({os.path.realpath(path)})" if path.is_symlink() else ""
    raise InputError(f"cannot read {what} {path}{target}: {kind}, not a {what} file")
