"""A command's outputs published together: kept all, or, if the command fails, undone all.

A command writes each output atomically (:func:`fosmodel.io.output.atomic_write`), but one
after the other: a report, then a model, then a JSON summary.  When the last one fails (the
disk is full, its folder is read-only, Ctrl-C), the first ones would be left changed.  Within
:func:`all_or_nothing` every output put in place goes through :func:`replace`, which keeps the
file it replaces as a hard link (a copy where links are refused) until the command ends: on an
exception the outputs are undone in reverse order, the replaced files put back and the new ones
removed; on success the kept files are removed.  The command line runs every command so;
:func:`durable` marks the outputs that must stay whatever follows (a fleet's finished
records, from which a rerun resumes).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import threading
from collections.abc import Iterator
from contextvars import ContextVar
from pathlib import Path

from ..core import files

#: The outputs put in place so far in this context: (destination, the file it replaced or
#: None); None outside :func:`all_or_nothing` or inside :func:`durable`.
_PUBLISHED: ContextVar[list[tuple[Path, Path | None]] | None] = ContextVar("published",
                                                                          default=None)
#: The suffix of a replaced file kept until the command ends.
KEPT = ".kept"


@contextlib.contextmanager
def all_or_nothing() -> Iterator[None]:
    """Undo every output put in place inside the block if the block raises."""
    published: list[tuple[Path, Path | None]] = []
    token = _PUBLISHED.set(published)
    try:
        with files.given_files():  # the command's inputs: no cleanup of temporaries removes them
            yield
    except BaseException:
        with _uninterrupted():  # a second Ctrl-C must not leave the undo half done
            _undo(published)
        raise
    else:
        for _, kept in published:
            if kept is not None:
                _remove(kept)
    finally:
        _PUBLISHED.reset(token)


@contextlib.contextmanager
def durable() -> Iterator[None]:
    """Keep the outputs put in place inside the block, whatever happens after it."""
    token = _PUBLISHED.set(None)
    try:
        yield
    finally:
        _PUBLISHED.reset(token)


def replace(source: Path, destination: Path) -> None:
    """Rename ``source`` onto ``destination`` (``os.replace``), undoably inside all_or_nothing."""
    published = _PUBLISHED.get()
    if published is None:
        files.check_replaceable(destination)
        os.replace(source, destination)
        return
    files.check_replaceable(destination)
    kept = None
    if destination.is_symlink() or destination.is_file():  # a symbolic link is kept as one
        kept = files.temporary_path(destination, KEPT)
        try:
            os.link(destination, kept, follow_symlinks=False)
        except OSError:  # a file system without hard links
            shutil.copy2(destination, kept, follow_symlinks=False)
    os.replace(source, destination)
    published.append((destination, kept))


def created(path: Path) -> None:
    """Record that ``path`` (a directory made for an output) did not exist before."""
    published = _PUBLISHED.get()
    if published is not None:
        published.append((path, None))


@contextlib.contextmanager
def _uninterrupted() -> Iterator[None]:
    """Ignore Ctrl-C inside the block (in the main thread, where signals are handled)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, handler)


def _undo(published: list[tuple[Path, Path | None]]) -> None:
    """Put back what each output replaced, newest first; remove what did not exist."""
    for destination, kept in reversed(published):
        with contextlib.suppress(OSError):
            if kept is not None:
                os.replace(kept, destination)
            elif destination.is_dir() and not destination.is_symlink():
                shutil.rmtree(destination)
            else:
                destination.unlink()


def _remove(path: Path) -> None:
    with contextlib.suppress(FileNotFoundError):
        path.unlink()
