r"""LaTeX tables laid out for a page: two head rows, aligned numbers, long and wide tables.

Every LaTeX table fosmodel writes goes through :func:`latex_table` (reports through
:func:`fosmodel.io.output.write_tables`, fit summaries through
:meth:`fosmodel.typeset.summary.Summary.as_latex`).  It measures the table as LaTeX will set
it in a plain article (Computer Modern at 10 pt, ``\textwidth`` 345 pt, ``\textheight``
550 pt: :func:`text_width`, from the fonts' metrics, with a margin) and sets it so that it fits:

* each column head is its name over its units, the units in a second head row
  (``Outage position error`` over ``(m, 30 s)``), a long name on two lines;
* the numbers of a column in one format, right-aligned: fixed decimals where their
  magnitudes allow (more where two values would read alike), else a fixed number of
  significant digits times a power of ten (:func:`number_format`); text left-aligned, escaped,
  its units typeset (:func:`fosmodel.typeset.latex.latex_text`);
* a table of more rows than its page holds is a ``longtable``, its heads repeated on every
  page (:func:`choose_layout`);
* a table wider than the text goes on a landscape page (``pdflscape``); wider still, it is
  split into parts that each repeat its leading text columns, then set smaller
  (``\small``, ``\footnotesize``), and only as a last resort scaled down (``\resizebox``).

Each table is a ``table`` float (or a ``longtable``) with booktabs rules, a caption and a
stable label (:func:`fosmodel.typeset.latex.table_label`); its first line is a comment naming
the packages it needs (``booktabs``, and ``longtable``, ``pdflscape``, ``graphicx`` where used,
all in TeX Live's ``latex-base`` and ``latex-recommended``).  ``tests/test_latex.py`` compiles
every table the commands write on a 10-minute record and holds each to the page.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import pandas as pd

from .latex import latex_number, latex_text

#: ``\textwidth`` and ``\textheight`` of a plain article at 10 pt (pt).
TEXT_WIDTH, TEXT_HEIGHT = 345.0, 550.0
#: Space between two columns (``2\tabcolsep``) and a margin on every measure (pt).
COLUMN_SEP, MARGIN = 12.0, 1.06
#: A row's height (``\baselineskip``) and what a table's caption, rules and heads take (pt).
ROW_HEIGHT, FRAME_HEIGHT = 12.0, 80.0
#: The sizes a table may be set in, smallest last, and their scale.
SIZES = (("", 1.0), ("\\small", 0.9), ("\\footnotesize", 0.8))
#: Widths of cmr10's printable ASCII characters at 10 pt (from its TFM file).
_CMR10 = dict(zip(
    "".join(map(chr, range(32, 127))),
    (2.78, 2.78, 5.0, 8.33, 5.0, 8.33, 7.78, 2.78, 3.89, 3.89, 5.0, 7.78, 2.78, 3.33, 2.78, 5.0,
     5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 2.78, 2.78, 2.78, 7.78, 4.72, 4.72, 7.78,
     7.5, 7.08, 7.22, 7.64, 6.81, 6.53, 7.85, 7.5, 3.61, 5.14, 7.78, 6.25, 9.17, 7.5, 7.78, 6.81,
     7.78, 7.36, 5.56, 7.22, 7.5, 7.5, 10.28, 7.5, 7.5, 6.11, 2.78, 5.0, 2.78, 5.0, 5.0, 2.78,
     5.0, 5.56, 4.44, 5.56, 4.44, 3.06, 5.0, 5.56, 2.78, 3.06, 5.28, 2.78, 8.33, 5.56, 5.0, 5.56,
     5.28, 3.92, 3.94, 3.89, 5.56, 5.28, 7.22, 5.28, 5.28, 4.44, 5.0, 10.0, 5.0, 5.0)))
_WIDE = 7.5  # a character outside the table: as wide as a capital
_SUPERSCRIPT = 0.7  # a power's digits are set at 7 pt
_TIMES, _MEDMUSKIP = 7.78, 2.22  # cmsy10's \times; 4 mu at 10 pt
_DIGIT7, _MINUS7, _SCRIPTSPACE = 3.99, 6.25, 0.5  # a power's digit (cmr7), minus (cmsy7)
_HEAD_UNITS = re.compile(r"^(?P<name>.*?)\s*(?P<units>\([^()]*(?:\([^()]*\)[^()]*)*\)(?:\^\S+)?)$")


def text_width(text: str) -> float:
    """Estimate the width (pt) of plain ``text`` in cmr10 at 10 pt, powers (``^2``) raised."""
    width, power = 0.0, False
    for c in text:
        if c == "^":
            power = True
            continue
        if power and not (c.isalnum() or c in "-+.{}/"):
            power = False
        w = _CMR10.get(c, _WIDE)
        width += w * (_SUPERSCRIPT if power else 1.0)
    return width


@dataclass(frozen=True)
class Cell:
    """A cell as LaTeX source and its estimated width (pt, at 10 pt)."""

    source: str
    width: float


def number_format(values: Sequence[float], digits: int = 4) -> Callable[[float], Cell]:
    """Return how a column of ``values`` is written: one format for all of them.

    Integers as they are; fixed decimals when the magnitudes lie between 0.001 and 100,000
    within four decades (``digits`` significant digits of the smallest, more where two
    values would read alike, up to five of the largest); else ``digits`` significant digits
    times a power of ten.
    """
    finite = sorted({float(v) for v in values if math.isfinite(v)})
    sizes = [abs(v) for v in finite if v != 0]
    if finite and all(v.is_integer() and abs(v) < 1e7 for v in finite):
        return lambda v: _plain_cell(f"{v:.0f}", v)
    if sizes and min(sizes) >= 1e-3 and max(sizes) < 1e5 and max(sizes) / min(sizes) < 1e4:
        base = digits - 1 - math.floor(math.log10(min(sizes)))
        cap = max(base, 4 - math.floor(math.log10(max(sizes))))  # five digits of the largest
        gaps = [b - a for a, b in zip(finite, finite[1:])]
        need = -math.floor(math.log10(min(gaps))) if gaps else base
        decimals = max(0, min(max(base, need), cap))
        return lambda v: _plain_cell(f"{v:.{decimals}f}", v)
    return lambda v: _scientific(v, digits)


def _plain_cell(text: str, value: float) -> Cell:
    if not math.isfinite(value):
        return _special(value)
    source = f"${text}$" if text.startswith("-") else text
    return Cell(source, text_width(text))


def _special(value: float) -> Cell:
    if math.isnan(value):
        return Cell("--", text_width("--"))
    return Cell(r"$\infty$" if value > 0 else r"$-\infty$", 10.0)


def _scientific(value: float, digits: int = 4) -> Cell:
    if not math.isfinite(value):
        return _special(value)
    if value == 0:
        return Cell("0", text_width("0"))
    mantissa, exponent = f"{value:.{digits - 1}e}".split("e")
    power = int(exponent)
    if power == 0:
        return _plain_cell(mantissa, value)
    return Cell(rf"${mantissa}\times10^{{{power}}}$", text_width(mantissa) + _times_ten(power))


def _times_ten(power: int) -> float:
    r"""Estimate the width (pt) of ``\times10^{power}`` in math mode.

    The sign has a binary operator's space (4 mu) each side; the power is set at 7 pt (cmr7's
    digits, cmsy7's minus, not a hyphen) and followed by ``\scriptspace``.
    """
    power_width = len(str(abs(power))) * _DIGIT7 + (_MINUS7 if power < 0 else 0.0) + _SCRIPTSPACE
    return _TIMES + 2 * _MEDMUSKIP + text_width("10") + power_width


def text_cell(value: object) -> Cell:
    """Write a text cell (or a number in a column of text): escaped, units typeset."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return Cell("--", text_width("--"))
    if isinstance(value, bool):
        return Cell("yes" if value else "no", text_width("yes"))
    if isinstance(value, numbers.Real):  # a number among text: four significant digits
        mantissa, _, power = f"{float(value):.4g}".partition("e")
        width = text_width(mantissa) + (_times_ten(int(power)) if power else 0.0)
        return Cell(latex_number(float(value)), width)
    text = str(value)
    return Cell(latex_text(text), text_width(text))


def split_head(name: str) -> tuple[str, str]:
    """``("Outage position error", "(m, 30 s)")``: a head's name and its units, if any."""
    found = _HEAD_UNITS.match(name.strip())
    if found and found["name"]:
        return found["name"], found["units"]
    return name, ""


def head_lines(name: str, room: float) -> list[str]:
    """Break a head's name into at most two lines, each within ``room`` pt where it can."""
    words = name.split()
    if text_width(name) <= room or len(words) < 2:
        return [name]
    best = min(range(1, len(words)), key=lambda k: max(text_width(" ".join(words[:k])),
                                                        text_width(" ".join(words[k:]))))
    return [" ".join(words[:best]), " ".join(words[best:])]


@dataclass(frozen=True)
class Column:
    """A column laid out: its alignment, head lines, units and cells."""

    align: str
    head: list[str]
    units: str
    cells: list[Cell]

    @property
    def width(self) -> float:
        """The column's width (pt at 10 pt), its separation included."""
        widths = [c.width for c in self.cells] + [text_width(h) for h in self.head]
        return MARGIN * max([*widths, text_width(self.units)]) + COLUMN_SEP


def columns_of(frame: pd.DataFrame, digits: int = 4) -> list[Column]:
    """Lay out each column of ``frame``: numbers right-aligned in one format, text left."""
    out = []
    for name in frame.columns:
        values = list(frame[name])
        numeric = all(isinstance(v, numbers.Real) and not isinstance(v, bool)
                      for v in values if v is not None) and any(v is not None for v in values)
        if numeric:
            fmt = number_format([float(v) for v in values if v is not None], digits)
            cells = [fmt(float(v)) if v is not None else _special(math.nan) for v in values]
        else:
            cells = [text_cell(v) for v in values]
        title, units = split_head(str(name))
        room = max([c.width for c in cells] + [text_width(units), 40.0])
        out.append(Column("r" if numeric else "l", head_lines(title, room), units, cells))
    return out


@dataclass(frozen=True)
class Layout:
    """How a table is set: its size, page, whether it breaks across pages, its parts."""

    size: str = ""
    landscape: bool = False
    long: bool = False
    parts: tuple[tuple[int, ...], ...] = ()
    resize: bool = False


def choose_layout(columns: Sequence[Column], n_rows: int) -> Layout:
    r"""Choose the first way that fits the page.

    As it is; on a landscape page; split into parts on landscape pages, each repeating the
    leading text columns; smaller (``\small``, ``\footnotesize``) on landscape pages; scaled
    down to the page's width.  A table of more rows than its page holds is a ``longtable``.
    """
    widths = [c.width for c in columns]
    every = (tuple(range(len(columns))),)

    def long(landscape: bool) -> bool:
        return n_rows * ROW_HEIGHT + FRAME_HEIGHT > (TEXT_WIDTH if landscape else TEXT_HEIGHT)

    if sum(widths) <= TEXT_WIDTH:
        return Layout(long=long(False), parts=every)
    if sum(widths) <= TEXT_HEIGHT:
        return Layout(landscape=True, long=long(True), parts=every)
    parts = _split(columns, TEXT_HEIGHT)
    if parts:
        return Layout(landscape=True, long=long(True), parts=parts)
    for size, scale in SIZES[1:]:
        if scale * sum(widths) <= TEXT_HEIGHT:
            return Layout(size=size, landscape=True, long=long(True), parts=every)
    if long(True):  # a longtable cannot be scaled: the smallest size, in parts if it can
        return Layout(size=SIZES[-1][0], landscape=True, long=True,
                      parts=_split(columns, TEXT_HEIGHT / SIZES[-1][1]) or every)
    return Layout(landscape=True, parts=every, resize=True)


def _split(columns: Sequence[Column], room: float) -> tuple[tuple[int, ...], ...]:
    """Put the columns in parts within ``room`` pt, each led by the table's leading text columns.

    The leading text columns repeated are as many (up to three) as take a third of the room at
    most.  None (an empty tuple) when the first column is not text or is wider than that, or
    a column does not fit beside them.
    """
    keys: list[int] = []
    for i, c in enumerate(columns[:3]):
        if c.align != "l" or sum(columns[k].width for k in keys) + c.width > room / 3:
            break
        keys.append(i)
    if not keys:
        return ()
    key_width = sum(columns[i].width for i in keys)
    parts, part, width = [], list(keys), key_width
    for i in range(len(keys), len(columns)):
        if width + columns[i].width > room and len(part) > len(keys):
            parts.append(tuple(part))
            part, width = list(keys), key_width
        if width + columns[i].width > room:
            return ()
        part.append(i)
        width += columns[i].width
    parts.append(tuple(part))
    return tuple(parts)


def _head_cell(column: Column) -> str:
    lines = [latex_text(line) for line in column.head]
    if len(lines) == 1:
        return lines[0]
    return f"\\shortstack[{column.align}]{{" + " \\\\ ".join(lines) + "}"


def _heads(columns: Sequence[Column]) -> list[str]:
    """Return the head rows between the top and middle rules: the names, then the units."""
    rows = [" & ".join(_head_cell(c) for c in columns) + r" \\"]
    if any(c.units for c in columns):
        rows.append(" & ".join(latex_text(c.units) for c in columns) + r" \\")
    return ["\\toprule", *rows, "\\midrule"]


def _float(layout: Layout, spec: str, heads: list[str], body: list[str], caption: str,
           label: str) -> list[str]:
    """Return a ``table`` float: size, caption, label, the tabular (scaled down if it must)."""
    tabular = [f"\\begin{{tabular}}{{{spec}}}", *heads, *body, "\\bottomrule", "\\end{tabular}"]
    if layout.resize:  # the box's braces on the tabular's own lines: no stray space in it
        tabular = ["\\resizebox{\\linewidth}{!}{" + tabular[0], *tabular[1:-1],
                   tabular[-1] + "}"]
    return ["\\begin{table}[htbp]", "\\centering", *([layout.size] if layout.size else []),
            f"\\caption{{{caption}}}", f"\\label{{{label}}}", *tabular, "\\end{table}"]


def _long(layout: Layout, spec: str, heads: list[str], body: list[str], caption: str,
          label: str) -> list[str]:
    """Return a ``longtable``: its heads on every page, the bottom rule on the last."""
    table = [f"\\begin{{longtable}}{{{spec}}}", f"\\caption{{{caption}}}\\label{{{label}}}\\\\",
             *heads, "\\endfirsthead", *heads, "\\endhead", "\\bottomrule", "\\endlastfoot",
             *body, "\\end{longtable}"]
    return ["{" + layout.size, *table, "}"] if layout.size else table


def latex_table(frame: pd.DataFrame, caption: str, label: str, digits: int = 4) -> str:
    r"""Write ``frame`` as LaTeX that fits a page of a plain article (:func:`choose_layout`).

    Parameters
    ----------
    frame : DataFrame
        The table; its index is left out.  A column of numbers is right-aligned in one
        format (:func:`number_format`), any other left-aligned as text.
    caption : str
        Plain text; escaped here.
    label : str
        The ``\label`` (see :func:`fosmodel.typeset.latex.table_label`); a table split into
        parts labels the second ``<label>-2``, and so on.
    digits : int, default 4
        Significant digits of the numbers (more in a column where two would read alike).

    Returns
    -------
    str
        The LaTeX source, ending in a newline; its first line, a comment, names the packages
        it needs.
    """
    columns = columns_of(frame, digits)
    layout = choose_layout(columns, len(frame))
    packages = ["booktabs", *(["longtable"] if layout.long else []),
                *(["pdflscape"] if layout.landscape else []),
                *(["graphicx"] if layout.resize else [])]
    out = [f"% a fosmodel table: \\usepackage{{{','.join(packages)}}}"]
    for k, part in enumerate(layout.parts):
        chosen = [columns[i] for i in part]
        of = f" (part {k + 1} of {len(layout.parts)})" if len(layout.parts) > 1 else ""
        body = [" & ".join(c.cells[r].source for c in chosen) + r" \\" for r in range(len(frame))]
        write = _long if layout.long else _float
        block = write(layout, "".join(c.align for c in chosen), _heads(chosen), body,
                      latex_text(caption) + of, label if k == 0 else f"{label}-{k + 1}")
        out += ["\\begin{landscape}", *block, "\\end{landscape}"] if layout.landscape else block
    return "\n".join(out) + "\n"
