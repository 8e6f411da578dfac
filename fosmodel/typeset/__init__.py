"""How text, tables and units are typeset: Markdown, LaTeX and matplotlib mathtext.

Markdown pipe tables, LaTeX tables for papers (escaped text, typeset units, numbers, booktabs
rules), the same units for matplotlib's labels, and the statsmodels-style summaries the fitted
models and the noise fit print.

A bottom layer beside :mod:`fosmodel.core`: it imports nothing else of fosmodel.  Its public
names are imported on first use (:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .latex import (
        latex_escape,
        latex_number,
        latex_text,
        mathtext_units,
        table_label,
    )
    from .markdown import markdown_table
    from .summary import Summary
    from .tables import latex_table
else:
    __getattr__, __dir__ = attach(__name__, {
        "latex": ("latex_escape", "latex_number", "latex_text", "mathtext_units", "table_label"),
        "markdown": ("markdown_table",),
        "summary": ("Summary",),
        "tables": ("latex_table",),
    })

__all__ = ["Summary", "latex_escape", "latex_number", "latex_table", "latex_text",
           "markdown_table", "mathtext_units", "table_label"]
