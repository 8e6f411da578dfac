"""Replace one generated section of the documentation (between ``<!-- NAME:begin/end -->``
markers), in whichever page holds it: the README or a page of ``docs/pages/``."""

from __future__ import annotations

from pathlib import Path

from fosmodel.io.output import write_text

README = Path(__file__).resolve().parents[1] / "README.md"
PAGES = README.parent / "docs" / "pages"


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


def page_path(path: Path) -> str:
    """A file or folder under ``studies/results`` as the pages link it (through their
    ``results`` link to that folder)."""
    return "results/" + path.relative_to(README.parent / "studies" / "results").as_posix()
