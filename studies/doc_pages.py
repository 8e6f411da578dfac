"""What the studies put into the documentation: their sections of the pages and the figures
the pages show.

:func:`replace_section` rewrites one generated section (between ``<!-- NAME:begin/end -->``
markers) in whichever page holds it, the README or a page of ``docs/pages/``;
:func:`show_figure` copies a figure into ``docs/pages/figures/`` (tracked, unlike the studies'
own results in ``studies/results/``) and gives the link a page uses."""

from __future__ import annotations

from pathlib import Path

from fosmodel.io import atomic_write, write_text

README = Path(__file__).resolve().parents[1] / "README.md"
PAGES = README.parent / "docs" / "pages"
FIGURES = PAGES / "figures"


def replace_section(name: str, text: str) -> Path:
    """Put ``text`` between the section's markers (one pair in all the pages); the page."""
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    pages = [p for p in (README, *sorted(PAGES.glob("*.md")))
             if begin in p.read_text(encoding="utf-8")]
    if len(pages) != 1:
        raise SystemExit(f"expected the section {name} in one page, found it in {len(pages)}")
    content = pages[0].read_text(encoding="utf-8")
    if content.count(begin) != 1 or content.count(end) != 1:
        raise SystemExit(f"{pages[0]}: expected one {begin} and one {end}")
    head, rest = content.split(begin)
    _, tail = rest.split(end)
    write_text(pages[0], f"{head}{begin}\n{text.strip()}\n{end}{tail}")
    return pages[0]


def show_figure(png: Path, name: str) -> str:
    """Copy the figure ``png`` to ``docs/pages/figures/name`` and return the pages' link to it."""
    FIGURES.mkdir(exist_ok=True)
    with atomic_write(FIGURES / name, "wb") as fh:
        fh.write(png.read_bytes())
    return f"figures/{name}"
