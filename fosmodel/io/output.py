"""Safe file output: never over an input, and either the old version or the complete new one.

Every report file fosmodel writes goes through :func:`atomic_write`:
:func:`fosmodel.core.files.atomic_write` (a temporary file renamed over the destination, so an
interrupted run never leaves a half-written result) put in place through the command's journal.
A report directory is written beside its destination and moved into place in one step
(:func:`publish`).  :func:`refuse_overwrite` checks, before anything is read,
that no output names a file the command reads, however the two are spelt.
:func:`writable_file` and :func:`writable_directory` check an output's path before anything
is read, and that its directory can be written.  An operating system's refusal to write (a
read-only folder, a full disk, a directory where a file goes) is an :class:`InputError`
naming the output, its temporary files removed; the command line publishes a command's
outputs all or none (:mod:`fosmodel.io.journal`).  :func:`write_tables` and
:func:`save_figure` write a table (Markdown, CSV, LaTeX with booktabs rules, a caption and a
label) and a figure (a 300 dpi PNG and an SVG, plain tick labels on a log axis of less than
two decades) that way.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, TYPE_CHECKING

from ..core import files
from ..core.exceptions import InputError, error_line
from ..typeset.latex import table_label
from ..typeset.markdown import markdown_table
from ..typeset.tables import latex_table
from . import journal
from .figures import log_problems, tidy

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

Paths = Mapping[str, "str | os.PathLike[str] | None"]


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether two paths name one file: through symlinks, hard links and relative spellings."""
    a, b = Path(a), Path(b)
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)  # hard links: the same device and inode
    except OSError:  # one of them does not exist (yet)
        return False


def refuse_overwrite(outputs: Paths, inputs: Paths) -> None:
    """Refuse outputs that would replace an input, or each other.

    Parameters
    ----------
    outputs, inputs : mapping of a label (``"--out"``, ``"the record"``) to a path
        None values are skipped.

    Raises
    ------
    InputError
        An output names the same file as an input or as another output.
    """
    outs = [(k, v) for k, v in outputs.items() if v is not None]
    ins = [(k, v) for k, v in inputs.items() if v is not None]
    files.protect(*(source for _, source in ins))  # no cleanup of temporaries removes them
    for label, path in outs:
        for what, source in ins:
            if same_file(path, source):
                raise InputError(f"{label} {path} is {what} {source}: fosmodel never writes over "
                                 "a file it reads; choose another output name")
    for i, (label, path) in enumerate(outs):
        for other, second in outs[i + 1:]:
            if same_file(path, second):
                raise InputError(f"{label} {path} and {other} {second} name the same file; "
                                 "give each output its own name")


def writable_file(path: str | os.PathLike[str],
                  created: str | os.PathLike[str] | None = None) -> Path:
    """Return ``path`` as an output file, checked before anything is read or computed.

    ``created`` is a report directory the command makes before it writes ``path``
    (:func:`writable_directory`): a file directly in it is accepted though it does not exist yet.

    Raises
    ------
    InputError
        If its directory does not exist (nor is ``created``) or cannot be written, or it is
        a directory, a device, a FIFO or a socket (an output replaces only a regular file).
    """
    out = Path(path)
    if created is not None and out.parent.absolute() == Path(created).absolute():
        writable_directory(created)
        if out.is_dir():
            raise InputError(f"cannot write {out}: it is a directory")
        files.check_replaceable(out)
        return out
    if not out.parent.is_dir():
        raise InputError(f"cannot write {out}: directory {out.parent} does not exist")
    if out.is_dir():
        raise InputError(f"cannot write {out}: it is a directory")
    files.check_replaceable(out)
    _check_writable(out, out.parent)
    return out


def writable_directory(path: str | os.PathLike[str]) -> Path:
    """Return ``path`` as a report's directory (:func:`report_directory` creates it at the end).

    Raises
    ------
    InputError
        If it is a file, or it (or the folder it is to be made in) cannot be written.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        kind = "a file" if out.is_file() else ("a FIFO" if out.is_fifo() else "a socket"
                                               if out.is_socket() else "a device")
        raise InputError(f"cannot write a report into {out}: it is {kind}, not a directory")
    base = out
    while not base.is_dir():  # itself, or where it will be made
        base = base.parent
    _check_writable(out, base)
    return out


def _check_writable(out: Path, directory: Path) -> None:
    """Refuse an output whose ``directory`` the process may not write (or enter)."""
    if os.access(directory, os.W_OK | os.X_OK):
        return
    with contextlib.suppress(OSError):
        if os.statvfs(directory).f_flag & os.ST_RDONLY:
            raise InputError(f"cannot write {out}: {directory} is on a read-only file system")
    raise InputError(f"cannot write {out}: permission denied on directory {directory}")


class OutputError(InputError):
    """The operating system refused to write an output: ``cannot write PATH: REASON``."""

    def __init__(self, path: Path, reason: str) -> None:
        super().__init__(f"cannot write {path}: {reason}")
        self.path, self.reason = path, reason


def _cannot_write(path: Path, exc: OSError, staging: Path | None = None) -> OutputError:
    """Return the one-line error of the system's refusal to write ``path``.

    A file of a report staged in ``staging`` is named in the reason, by its place in it.
    """
    reason = exc.strerror or error_line(exc)
    name = Path(exc.filename) if isinstance(exc.filename, str) else None
    if staging is not None and name is not None and name.is_relative_to(staging) \
            and name != staging:
        reason += f" ({name.relative_to(staging)})"
    return OutputError(path, reason)


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO]:
    """Open a temporary file beside ``path``; rename it onto ``path`` on success.

    :func:`fosmodel.core.files.atomic_write`, put in place through the command's journal (so
    that a failed command undoes it) and with the system's refusal to write as one line.

    Parameters
    ----------
    path : path-like
        Destination.  Its directory must exist.
    mode : {"w", "wb"}
        Text or binary mode.

    Yields
    ------
    file object
        Write the content to it.  If the body raises, the temporary file is
        removed and ``path`` is left untouched.

    Raises
    ------
    OutputError
        The system refused to write (the disk full, a directory where the file goes, ...).
    """
    path = Path(path)
    try:
        with files.atomic_write(path, mode, replace=journal.replace,
                                stale=(".tmp", journal.KEPT)) as fh:
            yield fh
    except OSError as exc:
        raise _cannot_write(path, exc) from None


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_write(path, "w") as fh:
        fh.write(text)


@contextlib.contextmanager
def report_directory(out: str | os.PathLike[str],
                     protected: Iterable[str | os.PathLike[str]] = ()) -> Iterator[Path]:
    """Give a fresh directory to write a report into, published onto ``out`` on success.

    The directory is created beside ``out``; when the body returns, every file
    in it is checked against ``protected`` (the inputs) and the whole is moved
    onto ``out`` (renamed, or its files moved into an existing ``out``).  If
    the body raises, or a file would replace an input, nothing of ``out``
    changes and the directory is removed.
    """
    out = Path(out)
    base = out.parent
    while not base.is_dir():  # beside out, or in its nearest existing ancestor
        base = base.parent
    target = base / out.name
    for item in files.stale_temporaries(target, ".tmpdir"):
        files.remove_path(item)
    tmp = files.temporary_path(target, ".tmpdir")
    try:
        tmp.mkdir()
    except OSError as exc:
        raise _cannot_write(out, exc) from None
    try:
        yield tmp
        publish(tmp, out, protected)
    except OutputError as exc:  # a file of the report: named by its place in the report
        if not exc.path.is_relative_to(tmp):
            raise
        raise OutputError(out, f"{exc.reason} ({exc.path.relative_to(tmp)})") from None
    except OSError as exc:
        raise _cannot_write(out, exc, tmp) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def publish(tmp: Path, out: Path, protected: Iterable[str | os.PathLike[str]] = ()) -> None:
    """Move the files of ``tmp`` onto ``out``, after checking that each can take its place.

    A file that would replace a ``protected`` file, or a directory, and a folder that would
    replace a file, are named in an InputError, and nothing is moved.
    """
    protected = list(protected)
    for item in tmp.rglob("*"):
        target = out / item.relative_to(tmp)
        if not target.exists():
            continue
        if not (target.is_file() or target.is_dir()):
            files.check_replaceable(target)
        for source in protected:
            if same_file(target, source):
                raise InputError(f"writing the report into {out} would replace {source}, a "
                                 "file this command reads; choose another output directory")
        if item.is_dir() != target.is_dir():
            raise InputError(f"cannot write the report into {out}: {target} is "
                             f"{'a file' if item.is_dir() else 'a directory'}, where the report "
                             f"has {'a folder' if item.is_dir() else 'a file'} of that name")
    _move(tmp, out)


def _move(tmp: Path, out: Path) -> None:
    if out.is_dir():
        for item in tmp.iterdir():
            target = out / item.name
            if item.is_dir() and target.is_dir():
                _move(item, target)
            else:
                journal.replace(item, target)
    else:
        missing = [d for d in reversed(out.parents) if not d.exists()]
        out.parent.mkdir(parents=True, exist_ok=True)
        for folder in missing:
            journal.created(folder)
        journal.replace(tmp, out)


def path_name(name: str) -> str:
    """Return a column's name as a file or folder name: ``Gyro X (deg/s)`` -> ``Gyro_X_deg_s_``.

    Headers hold spaces, brackets and slashes; a slash would make a folder of its own.
    """
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip(".") or "column"


def write_tables(frame: pd.DataFrame, out_dir: Path, stem: str, caption: str | None = None,
                 report: str = "") -> list[Path]:
    """``stem.md``, ``stem.csv`` and ``stem.tex`` in ``out_dir``, each written atomically.

    Parameters
    ----------
    frame : DataFrame
        The table.
    out_dir : Path
        An existing directory.
    stem : str
        The files' name without the extension.
    caption : str, optional
        The LaTeX table's caption (default: the stem in words).
    report : str, optional
        The report's name or title: the LaTeX label is ``tab:fosmodel-<report>-<stem>``
        (:func:`fosmodel.typeset.latex.table_label`), the same on every run.

    Returns
    -------
    list of Path
        The three files.
    """
    paths = [out_dir / f"{stem}.{ext}" for ext in ("md", "csv", "tex")]
    write_text(paths[0], markdown_table(frame, digits=4) + "\n")
    write_text(paths[1], frame.to_csv(index=False))
    write_text(paths[2], latex_table(frame, caption or stem.replace("_", " ").capitalize(),
                                     table_label(report, stem)))
    return paths


#: Resolution of the PNG figures: print quality.
FIGURE_DPI = 300


def save_figure(fig: Figure, out_dir: Path, stem: str) -> list[Path]:
    """Write ``stem.png`` (at :data:`FIGURE_DPI`) and ``stem.svg`` in ``out_dir``.

    Each is written atomically, after :func:`fosmodel.io.figures.tidy` (plain, distinct tick
    labels that bracket the data); the drawn figure is checked when ``FOSMODEL_FIGURE_LOG``
    names a file (:func:`fosmodel.io.figures.log_problems`).
    """
    from matplotlib import rc_context  # here: writing tables or text needs no matplotlib

    tidy(fig)
    paths = []
    for ext in ("png", "svg"):
        path = out_dir / f"{stem}.{ext}"
        with atomic_write(path, "wb") as fh:
            fig.savefig(fh, format=ext, dpi=FIGURE_DPI)
        paths.append(path)
        if ext == "png":
            log_problems(fig, path)
        # Laid out by the first save: the second keeps that layout.  No engine at all, not
        # "none", whose placeholder engine still makes savefig walk the whole figure once more
        # before drawing it (a third of an SVG's time); and the rc settings that would put an
        # engine back in its place off.
        with rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
            fig.set_layout_engine(None)
    return paths
