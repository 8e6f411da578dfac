"""The Python API page: every public name of every package, with its one-line summary.

``python docs/api_page.py`` rewrites the section of ``docs/pages/api.md`` between its
``<!-- API:begin/end -->`` markers from the packages' ``__all__``: for a function or a class
the first sentence of its docstring, for a constant the ``#:`` comment above it in its module.
``tests/test_public_api.py`` checks that the page is what this script writes.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "pages" / "api.md"
BEGIN, END = "<!-- API:begin -->", "<!-- API:end -->"
#: The packages in the order of the layers, the package's face first.
PACKAGES = ("fosmodel", "fosmodel.core", "fosmodel.typeset", "fosmodel.models", "fosmodel.io",
            "fosmodel.noise", "fosmodel.filter", "fosmodel.study", "fosmodel.loop",
            "fosmodel.loop.effects",
            "fosmodel.workflows", "fosmodel.cli")


def _markdown(text: str) -> str:
    """RST roles and double backquotes as Markdown code; pipes escaped for a table cell."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"`\1`", text).replace("``", "`")
    return " ".join(text.split()).replace("|", "\\|")


def _homes(package: str) -> dict[str, str]:
    """Each public name of a lazily attached package and the module it comes from."""
    tree = ast.parse(Path(importlib.import_module(package).__file__).read_text())
    calls = [node for node in ast.walk(tree) if isinstance(node, ast.Call)
             and isinstance(node.func, ast.Name) and node.func.id == "attach"]
    if not calls:
        return {}
    table = ast.literal_eval(calls[0].args[1])
    return {name: f"{package}.{module}" for module, names in table.items() for name in names}


def _comment(module: str, name: str) -> str:
    """The ``#:`` lines above ``name = ...`` in ``module``."""
    lines = Path(importlib.import_module(module).__file__).read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if re.match(rf"{name}\b.*=", line))
    above = []
    while at and lines[at - 1].startswith("#:"):
        at -= 1
        above.insert(0, lines[at][2:].strip())
    if not above:
        raise SystemExit(f"{module}.{name}: a public constant needs a #: comment above it")
    return " ".join(above)


def summary(package: str, name: str) -> str:
    """The first sentence of what ``package.name`` is."""
    value = getattr(importlib.import_module(package), name)
    if inspect.isclass(value) or inspect.isroutine(value):
        doc = inspect.getdoc(value) or ""
        first = doc.split("\n\n")[0]
        if not first:
            raise SystemExit(f"{package}.{name} has no docstring")
        return _markdown(first)
    if name == "__version__":
        return "The installed version."
    return _markdown(_comment(_homes(package).get(name, package), name))


def _kind(value: object) -> str:
    if inspect.isclass(value):
        return "class"
    return "function" if inspect.isroutine(value) else "constant"


def section() -> str:
    """The generated part of the page: a table per package."""
    parts = []
    for package in PACKAGES:
        module = importlib.import_module(package)
        lead = _markdown((module.__doc__ or "").strip().split("\n\n")[0])
        rows = [f"| `{name}` | {_kind(getattr(module, name))} | {summary(package, name)} |"
                for name in sorted(module.__all__, key=lambda n: (n.startswith("_"), n.lower()))]
        parts.append("\n".join([f"## `{package}`", "", lead, "",
                                "| name | kind | what it is |", "|---|---|---|", *rows]))
    return "\n\n".join(parts)


def page_text(current: str) -> str:
    """``current`` with its generated section rewritten."""
    head, rest = current.split(BEGIN)
    _, tail = rest.split(END)
    return f"{head}{BEGIN}\n{section()}\n{END}{tail}"


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    PAGE.write_text(page_text(PAGE.read_text(encoding="utf-8")), encoding="utf-8")
    print(f"wrote {PAGE.relative_to(ROOT)}")
