r"""LaTeX for papers: escaped text with typeset units, numbers, and booktabs tables.

Every LaTeX table fosmodel writes goes through :func:`latex_table` (reports through
:func:`fosmodel.io.output.write_tables`, fit summaries through
:meth:`fosmodel.typeset.summary.Summary.as_latex`): a ``table`` float with a caption and a
stable label (:func:`table_label`), booktabs rules (``\toprule``, ``\midrule``,
``\bottomrule``), text with LaTeX's special characters escaped and units typeset
(:func:`latex_text`: ``m/s^2`` as ``m/s$^{2}$``, ``deg/sqrt(h)`` as
``deg/$\sqrt{\mathrm{h}}$``) and numbers to four significant digits with powers of ten in
math mode (:func:`latex_number`: ``1e-05`` as ``$1\times10^{-5}$``).  The tables need the
``booktabs`` package.  :func:`mathtext_units` types the same units for matplotlib's labels, so
a unit reads one way in the figures and the tables.
"""

from __future__ import annotations

import math
import numbers
import re

import pandas as pd

_LATEX_SPECIAL = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#",
                  "_": r"\_", "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}",
                  "^": r"\textasciicircum{}"}
# a power (``^2``, ``^-1``, ``^0.5``, ``^{1/2}``) or the square root of a unit (``sqrt(Hz)``)
_UNIT_MARKUP = re.compile(r"\^(?:\{(?P<braced>[-+]?[\w./]+)\}|(?P<power>[-+]?\d+(?:\.\d+)?))"
                          r"|sqrt\((?P<root>[A-Za-z]+)\)")


def latex_escape(text: str) -> str:
    r"""Escape LaTeX's special characters in ``text``.

    ``_`` becomes ``\_``, ``^`` becomes ``\textasciicircum{}``, ...
    """
    return "".join(_LATEX_SPECIAL.get(c, c) for c in text)


def _pieces(text: str) -> list[tuple[bool, str]]:
    """``text`` cut into plain pieces and math pieces (``(True, "^{2}")``)."""
    pieces, at = [], 0
    for m in _UNIT_MARKUP.finditer(text):
        pieces.append((False, text[at:m.start()]))
        if m["root"]:
            pieces.append((True, rf"\sqrt{{\mathrm{{{m['root']}}}}}"))
        else:
            pieces.append((True, f"^{{{m['braced'] or m['power']}}}"))
        at = m.end()
    pieces.append((False, text[at:]))
    return [(math_, piece) for math_, piece in pieces if piece]


def latex_text(text: str) -> str:
    r"""Write ``text`` for LaTeX's text mode: units' powers and square roots in math mode.

    Every other special character is escaped.

    Examples
    --------
    >>> latex_text("MSE (m/s^2)^2")
    'MSE (m/s$^{2}$)$^{2}$'
    >>> latex_text("N (deg/s/sqrt(Hz)) of gx_dps, 5 %")
    'N (deg/s/$\\sqrt{\\mathrm{Hz}}$) of gx\\_dps, 5 \\%'
    """
    return "".join(f"${piece}$" if math_ else latex_escape(piece) for math_, piece in _pieces(text))


def mathtext_units(text: str) -> str:
    """Write ``text`` for a matplotlib label, its units typeset as by :func:`latex_text`.

    ``m/s^2`` becomes ``m/s$^{2}$``; a dollar sign stays a dollar sign.
    """
    return "".join(f"${piece}$" if math_ else piece.replace("$", r"\$")
                   for math_, piece in _pieces(text))


def latex_number(value: float, digits: int = 4) -> str:
    r"""Write a number to ``digits`` significant digits for LaTeX.

    A power of ten and a minus sign go in math mode (``$1.5\times10^{-5}$``, ``$-0.25$``),
    NaN is ``--``, infinity ``$\infty$``.
    """
    if math.isnan(value):
        return "--"
    if math.isinf(value):
        return r"$\infty$" if value > 0 else r"$-\infty$"
    mantissa, _, exponent = f"{value:.{digits}g}".partition("e")
    if exponent:
        return rf"${mantissa}\times10^{{{int(exponent)}}}$"
    return f"${mantissa}$" if mantissa.startswith("-") else mantissa


def latex_cell(value: object, digits: int = 4) -> str:
    """Write one table cell: a number by :func:`latex_number`, None as ``--``.

    Anything else is text, by :func:`latex_text`.
    """
    if value is None:
        return "--"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, numbers.Integral):
        return latex_number(float(value), digits=max(digits, len(str(abs(int(value))))))
    if isinstance(value, numbers.Real):
        return latex_number(float(value), digits)
    return latex_text(str(value))


def table_label(*parts: str) -> str:
    """Return ``tab:fosmodel-<parts>``, a LaTeX label of the parts' letters and digits.

    The rest are hyphens, so the label is the same for every run of the same report.
    """
    slug = re.sub(r"[^a-z0-9]+", "-", "-".join(parts).lower()).strip("-")
    return f"tab:fosmodel-{slug}" if slug else "tab:fosmodel"


def latex_table(frame: pd.DataFrame, caption: str, label: str, digits: int = 4) -> str:
    r"""Write ``frame`` as a LaTeX ``table`` float with booktabs rules, a caption and a label.

    Parameters
    ----------
    frame : DataFrame
        The table; its index is left out.  Numeric columns are right-aligned, others left.
    caption : str
        Plain text; escaped here.
    label : str
        The ``\label`` (see :func:`table_label`).
    digits : int, default 4
        Significant digits of the numbers.

    Returns
    -------
    str
        The LaTeX source, ending in a newline; it needs ``\usepackage{booktabs}``.
    """
    spec = "".join("r" if pd.api.types.is_numeric_dtype(dtype) and
                   not pd.api.types.is_bool_dtype(dtype) else "l" for dtype in frame.dtypes)
    body = frame.set_axis([latex_text(str(c)) for c in frame.columns], axis=1)
    return body.to_latex(index=False, escape=False, column_format=spec, position="htbp",
                         caption=latex_text(caption), label=label, na_rep="--",
                         formatters=[lambda v: latex_cell(v, digits)] * frame.shape[1])
