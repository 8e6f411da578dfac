"""Files written whole or not at all, and regular files read bounded with one-line errors.

Every file fosmodel writes goes through :func:`atomic_write`: the content is written to a
temporary file in the destination directory and renamed over the destination, so an
interrupted run never leaves a half-written result.  The temporary file's name carries the
writer's process id, a random token and a signature of the three (:func:`temporary_path`):
one left behind by a killed run is removed by the next write to the same destination, and
only when it proves its own (:func:`stale_temporaries`): its signature holds, its writer is
gone, it belongs to this user, a file is no hard link of another, and it is no file a
command was given (:func:`protect`).  An output goes only to a regular file or a new path:
never over a device, a FIFO or a socket (:func:`check_replaceable`).  Here, at the bottom
of the layers, so that a fitted model can save itself
(:meth:`fosmodel.models.model.FOSModel.save`); :mod:`fosmodel.io.output` builds reports on it.

Every file fosmodel reads whole into memory (a model file) goes through :func:`read_bounded`:
a path that is no regular file (a FIFO, a device such as ``/dev/zero``, a directory) is refused
from its metadata, and at most a given number of bytes is read.  Here too, so that
``FOSModel.load`` and the commands' ``read_model`` share the one bounded read.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import stat
import uuid
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from pathlib import Path
from typing import IO

from .exceptions import InputError

#: Signs the temporary files' names: a name no user file matches by accident.
_SIGNATURE_KEY = b"fosmodel temporary file"
#: The files and directories the running command was given, by real path and by (device,
#: inode): never removed.  None outside :func:`given_files`.
_GIVEN: ContextVar[tuple[set[str], set[tuple[int, int]]] | None] = ContextVar("given",
                                                                               default=None)


def _signature(name: str, pid: int, token: str, suffix: str) -> str:
    text = f"{name}\0{pid}\0{token}\0{suffix}".encode()
    return hashlib.blake2b(text, key=_SIGNATURE_KEY, digest_size=8).hexdigest()


def _temporary_name(path: Path, pid: int, token: str, suffix: str) -> str:
    return f".{path.name}.{pid}.{token}{_signature(path.name, pid, token, suffix)}{suffix}"


def temporary_path(path: Path, suffix: str) -> Path:
    """Return a fresh name beside ``path``: this process's id, a random token, their signature."""
    return path.parent / _temporary_name(path, os.getpid(), uuid.uuid4().hex[:12], suffix)


@contextlib.contextmanager
def given_files() -> Iterator[None]:
    """Scope of one command: the files :func:`protect` marks inside it are never removed."""
    token = _GIVEN.set((set(), set()))
    try:
        yield
    finally:
        _GIVEN.reset(token)


def protect(*paths: str | os.PathLike[str]) -> None:
    """Mark files or directories the command was given: no cleanup inside its scope removes them.

    Outside :func:`given_files` (a library call) the signed names alone keep a user's files.
    """
    given = _GIVEN.get()
    if given is None:
        return
    for path in paths:
        given[0].add(os.path.realpath(path))
        with contextlib.suppress(OSError):
            info = os.stat(path)
            given[1].add((info.st_dev, info.st_ino))


def _given(path: Path, info: os.stat_result) -> bool:
    given = _GIVEN.get()
    return given is not None and ((info.st_dev, info.st_ino) in given[1]
                                  or os.path.realpath(path) in given[0])


def stale_temporaries(path: Path, suffix: str) -> Iterator[Path]:
    """Temporary files or directories for ``path`` that a writer no longer running left.

    Only those that prove their own: a name of :func:`temporary_path` whose signature holds,
    a dead writer's id, this user's, a regular file that is no hard link of another file (or
    a real directory, none of whose files is so), and nothing :func:`protect` marked.
    """
    pattern = re.compile(rf"^\.{re.escape(path.name)}\.(\d+)\.([0-9a-f]{{12}})([0-9a-f]{{16}})"
                         rf"{re.escape(suffix)}$")
    with contextlib.suppress(OSError):
        for item in path.parent.iterdir():
            m = pattern.match(item.name)
            if (m and m.group(3) == _signature(path.name, int(m.group(1)), m.group(2), suffix)
                    and not _alive(int(m.group(1))) and _ours(item, path)):
                yield item


def _ours(item: Path, path: Path) -> bool:
    """Whether ``item`` is as this process's writers leave it, and no file a command was given.

    A regular file has no other link, but for ``path`` itself: the copy of a destination kept
    by a writer killed before it replaced it is a second link to it.
    """
    try:
        info = item.lstat()
    except OSError:
        return False
    if info.st_uid != os.getuid() or _given(item, info):
        return False
    if stat.S_ISREG(info.st_mode):
        if info.st_nlink == 2:
            with contextlib.suppress(OSError):
                target = path.lstat()
                return (target.st_dev, target.st_ino) == (info.st_dev, info.st_ino)
        return info.st_nlink == 1
    if not stat.S_ISDIR(info.st_mode):
        return False
    try:
        for inner in item.rglob("*"):
            inner_info = inner.lstat()
            if _given(inner, inner_info) or (stat.S_ISREG(inner_info.st_mode)
                                             and inner_info.st_nlink != 1):
                return False
    except OSError:
        return False
    return True


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):  # another user's, or no pid at all
        return True
    return True


def remove_path(item: Path) -> None:
    """Remove a file or a directory tree, if it is still there."""
    if item.is_dir() and not item.is_symlink():
        shutil.rmtree(item, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            item.unlink()


def check_replaceable(path: str | os.PathLike[str]) -> None:
    """Refuse an output path that names something other than a regular file or nothing.

    A device, a FIFO or a socket (or a symbolic link to one) is never replaced: renaming a
    file over ``/dev/null`` would replace the system's node.

    Raises
    ------
    InputError
        ``cannot write PATH: a device, not a regular file; ...``.
    """
    try:
        info = os.stat(path)
    except OSError:  # nothing there (or a broken link): a new path
        return
    if stat.S_ISREG(info.st_mode) or stat.S_ISDIR(info.st_mode):
        return  # a directory is the callers' to name (a report's, or a refusal of their own)
    target = f" ({os.path.realpath(path)})" if os.path.islink(path) else ""
    raise InputError(f"cannot write {path}{target}: {_kind(info)}, not a regular file; "
                     "fosmodel writes outputs only to regular files or new paths")


def _kind(info: os.stat_result) -> str:
    return ("a directory" if stat.S_ISDIR(info.st_mode) else
            "a FIFO" if stat.S_ISFIFO(info.st_mode) else
            "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode) else
            "a socket" if stat.S_ISSOCK(info.st_mode) else "not a regular file")


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
        check_replaceable(path)
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
    protect(path)
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
    target = f" ({os.path.realpath(path)})" if path.is_symlink() else ""
    raise InputError(f"cannot read {what} {path}{target}: {_kind(info)}, not a {what} file")
