"""Safe file output: never over an input, and either the old version or the complete new one.

Every file fosmodel writes goes through :func:`atomic_write`: the content is
written to a temporary file in the destination directory and renamed over the
destination, so an interrupted run never leaves a half-written result.  The
temporary file's name carries the writer's process id: one left behind by a
killed run is removed by the next write to the same destination.  A report
directory is written beside its destination and moved into place in one step
(:func:`publish`).  :func:`refuse_overwrite` checks, before anything is read,
that no output names a file the command reads, however the two are spelt.
:func:`writable_file` and :func:`writable_directory` check an output's path before anything
is read.  :func:`write_tables` and :func:`save_figure` write a table (Markdown, CSV,
LaTeX with booktabs rules, a caption and a label) and a figure (a 300 dpi PNG and an SVG, plain
tick labels on a log axis of less than two decades) that way.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import shutil
import uuid
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, TYPE_CHECKING

import numpy as np

from ..core.exceptions import InputError
from ..typeset.latex import latex_table, table_label
from ..typeset.markdown import markdown_table

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


def writable_file(path: str | os.PathLike[str]) -> Path:
    """Return ``path`` as an output file, checked before anything is read or computed.

    Raises
    ------
    InputError
        If its directory does not exist, or it is a directory.
    """
    out = Path(path)
    if not out.parent.is_dir():
        raise InputError(f"cannot write {out}: directory {out.parent} does not exist")
    if out.is_dir():
        raise InputError(f"cannot write {out}: it is a directory")
    return out


def writable_directory(path: str | os.PathLike[str]) -> Path:
    """Return ``path`` as a report's directory (:func:`report_directory` creates it at the end).

    Raises
    ------
    InputError
        If it is a file.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise InputError(f"cannot write a report into {out}: it is a file, not a directory")
    return out


def _temporary_name(path: Path, suffix: str) -> Path:
    return path.parent / f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}{suffix}"


def _stale(path: Path, suffix: str) -> Iterator[Path]:
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


def _remove(item: Path) -> None:
    if item.is_dir() and not item.is_symlink():
        shutil.rmtree(item, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            item.unlink()


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO]:
    """Open a temporary file beside ``path``; rename it onto ``path`` on success.

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
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', not {mode!r}")
    path = Path(path)
    for item in _stale(path, ".tmp"):  # left behind by a killed run
        _remove(item)
    tmp = _temporary_name(path, ".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, _mode())
    try:
        fh = (os.fdopen(fd, "w", encoding="utf-8", newline="") if mode == "w"
              else os.fdopen(fd, "wb"))
        with fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
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
    for item in _stale(target, ".tmpdir"):
        _remove(item)
    tmp = _temporary_name(target, ".tmpdir")
    tmp.mkdir()
    try:
        yield tmp
        publish(tmp, out, protected)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def publish(tmp: Path, out: Path, protected: Iterable[str | os.PathLike[str]] = ()) -> None:
    """Move the files of ``tmp`` onto ``out``, after checking none replaces a ``protected`` file.

    A file that would is named in an InputError, and nothing is moved.
    """
    protected = list(protected)
    for item in tmp.rglob("*"):
        target = out / item.relative_to(tmp)
        for source in protected:
            if target.exists() and same_file(target, source):
                raise InputError(f"writing the report into {out} would replace {source}, a "
                                 "file this command reads; choose another output directory")
    _move(tmp, out)


def _move(tmp: Path, out: Path) -> None:
    if out.is_dir():
        for item in tmp.iterdir():
            target = out / item.name
            if item.is_dir() and target.is_dir():
                _move(item, target)
            else:
                os.replace(item, target)
    else:
        out.parent.mkdir(parents=True, exist_ok=True)
        os.replace(tmp, out)


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

    Each is written atomically, after :func:`plain_log_ticks`.
    """
    from matplotlib import rc_context  # here: writing tables or text needs no matplotlib

    plain_log_ticks(fig)
    paths = []
    for ext in ("png", "svg"):
        path = out_dir / f"{stem}.{ext}"
        with atomic_write(path, "wb") as fh:
            fig.savefig(fh, format=ext, dpi=FIGURE_DPI)
        paths.append(path)
        # Laid out by the first save: the second keeps that layout.  No engine at all, not
        # "none", whose placeholder engine still makes savefig walk the whole figure once more
        # before drawing it (a third of an SVG's time); and the rc settings that would put an
        # engine back in its place off.
        with rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
            fig.set_layout_engine(None)
    return paths


def plain_log_ticks(fig: Figure) -> None:
    """Label every log axis of ``fig`` that spans less than two decades in plain numbers.

    Plain tick labels are ``0.02``, ``0.05``, ``0.1``.

    Left to itself matplotlib labels such an axis with powers of ten at the minor ticks, or,
    when no minor tick falls in view, with linear ticks such as ``1.22x10^1``.  Here the major
    ticks go to 1, 2 and 5 times the powers of ten over one to two decades and to evenly spaced
    round numbers within one decade, and every label is the number in positional notation
    (``0.00002``, never ``2e-05``); an axis spanning more keeps its labels at the powers of ten.
    """
    from matplotlib import ticker  # here: writing tables or text needs no matplotlib

    for ax in fig.axes:
        for axis, limits in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
            low, high = sorted(limits)
            if axis.get_scale() != "log" or low <= 0 or math.log10(high / low) >= 2:
                continue
            axis.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0))
                                   if high / low >= 10 else
                                   ticker.MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]))
            axis.set_major_formatter(ticker.FuncFormatter(_plain_number))
            axis.set_minor_formatter(ticker.NullFormatter())


def _plain_number(value: float, _position: int | None = None) -> str:
    """Format a tick value to three significant digits, without an exponent."""
    return np.format_float_positional(value, precision=3, unique=True, fractional=False,
                                      trim="-")
