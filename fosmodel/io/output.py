"""Safe file output: never over an input, and either the old version or the complete new one.

Every file fosmodel writes goes through :func:`~fosmodel.core.files.atomic_write` (a
temporary file renamed over the destination, so an interrupted run never leaves a
half-written result; imported here with :func:`~fosmodel.core.files.write_text` for the
writers of reports).  A report
directory is written beside its destination and moved into place in one step
(:func:`publish`).  :func:`refuse_overwrite` checks, before anything is read,
that no output names a file the command reads, however the two are spelt.
:func:`writable_file` and :func:`writable_directory` check an output's path before anything
is read.  :func:`write_tables` and :func:`save_figure` write a table (Markdown, CSV,
LaTeX with booktabs rules, a caption and a label) and a figure (a 300 dpi PNG and an SVG, tick
labels that read: :mod:`fosmodel.io.figures`) that way.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.exceptions import InputError
from ..core.files import atomic_write, remove_path, stale_temporaries, temporary_path, write_text
from ..typeset.latex import table_label
from ..typeset.markdown import markdown_table
from ..typeset.tables import latex_table
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
    for item in stale_temporaries(target, ".tmpdir"):
        remove_path(item)
    tmp = temporary_path(target, ".tmpdir")
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
