"""Replace one generated section of the README (between ``<!-- NAME:begin/end -->`` markers)."""

from __future__ import annotations

from pathlib import Path

from fosmodel.io.output import write_text

README = Path(__file__).resolve().parents[1] / "README.md"


def replace_section(name: str, text: str, readme: Path = README) -> None:
    """Put ``text`` between the section's markers (which must exist once each)."""
    content = readme.read_text(encoding="utf-8")
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    if content.count(begin) != 1 or content.count(end) != 1:
        raise SystemExit(f"{readme}: expected one {begin} and one {end}")
    head, rest = content.split(begin)
    _, tail = rest.split(end)
    write_text(readme, f"{head}{begin}\n{text.strip()}\n{end}{tail}")
