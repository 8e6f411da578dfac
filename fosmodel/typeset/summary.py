"""Plain-text result summaries in the manner of statsmodels' ``summary()``."""

from __future__ import annotations

import html
from dataclasses import dataclass, field

import pandas as pd

from .latex import latex_table, latex_text, table_label
from .markdown import markdown_table

_WIDTH = 78


@dataclass
class Summary:
    """A titled block of key/value facts, a table, and notes.

    ``str(summary)`` renders it as fixed-width text; :meth:`to_frame` gives the
    table, :meth:`as_markdown` a Markdown rendering for reports, :meth:`as_html` the
    rendering a notebook shows (``_repr_html_``) and :meth:`as_latex` a LaTeX one (special
    characters escaped) for a paper.
    """

    title: str
    info: list[tuple[str, str]]
    table: pd.DataFrame
    notes: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        """Return the summary as fixed-width text, statsmodels-style."""
        rule = "=" * _WIDTH
        lines = [self.title.center(_WIDTH), rule]
        half = (len(self.info) + 1) // 2
        left, right = self.info[:half], self.info[half:]
        for i, (k, v) in enumerate(left):
            text = f"{k + ':':<22}{v:>16}"
            if i < len(right):
                k2, v2 = right[i]
                text += f"   {k2 + ':':<20}{v2:>17}"
            lines.append(text)
        lines.append(rule)
        lines.extend(self.table.to_string(index=False, float_format=_fmt, na_rep="").splitlines())
        lines.append(rule)
        lines.extend(f"[{i + 1}] {note}" for i, note in enumerate(self.notes))
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """Return a copy of the table."""
        return self.table.copy()

    def as_markdown(self) -> str:
        """Return the title, the facts, the table and the notes as Markdown."""
        head = "\n".join(f"- **{k}**: {v}" for k, v in self.info)
        notes = "\n".join(f"{i + 1}. {n}" for i, n in enumerate(self.notes))
        body = f"### {self.title}\n\n{head}\n\n{markdown_table(self.table)}"
        return body + (f"\n\n{notes}" if notes else "")


    def as_html(self) -> str:
        """Return the title, the facts, the table and the notes as HTML."""
        facts = "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>"
                        for k, v in self.info)
        notes = "".join(f"<li>{html.escape(n)}</li>" for n in self.notes)
        return (f"<h4>{html.escape(self.title)}</h4><table>{facts}</table>"
                + self.table.to_html(index=False, na_rep="", float_format=_fmt)
                + (f"<ol>{notes}</ol>" if notes else ""))

    def _repr_html_(self) -> str:
        return self.as_html()

    def as_latex(self) -> str:
        """Return the facts and the table as two LaTeX tables, the notes as an ``enumerate``.

        The tables come from :func:`~fosmodel.typeset.latex.latex_table` (booktabs rules, a
        caption, the labels ``tab:fosmodel-<title>-facts`` and ``tab:fosmodel-<title>``);
        every special character is escaped, units are typeset.
        """
        facts = pd.DataFrame(self.info, columns=["Fact", "Value"])
        notes = "\n".join(f"\\item {latex_text(n)}" for n in self.notes)
        return "\n".join([
            latex_table(facts, f"{self.title}: the fit", table_label(self.title, "facts")),
            latex_table(self.table, self.title, table_label(self.title), digits=6),
            *(["\\begin{enumerate}", notes, "\\end{enumerate}", ""] if notes else [])])


def _fmt(v: float) -> str:
    return f"{v:.6g}"
