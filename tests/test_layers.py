"""The layers contract: fosmodel's folders are layers, and imports run one way, down.

    {core, typeset} -> models -> io -> noise -> filter -> {study, loop} -> workflows -> cli, demo

A module may import its own folder and the folders below it (``core`` and
``typeset`` are the ground floor side by side, and never import each other;
``study`` and ``loop`` are side by side and never import each other;
``workflows`` puts them together over a whole record); ``data_synth`` is a
client of the layers up to ``filter`` that only the application (``cli``,
``demo``) uses.  Every import counts, also one inside a function.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RANK = {"_version": 0, "core": 0, "typeset": 0, "models": 1, "io": 2, "noise": 3, "filter": 4,
        "study": 5, "loop": 5, "data_synth": 5.5, "workflows": 5.7, "cli": 6, "demo": 6,
        "__init__": 6}
#: Layers on one floor that never import each other.
SIDE_BY_SIDE = ({"core", "typeset"}, {"study", "loop"})


def _name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """The fosmodel and data_synth modules ``path`` imports (as dotted names)."""
    package = _name(path) if path.name == "__init__.py" else _name(path).rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*up, base] if base else up)
            modules = {f"{base}.{a.name}" for a in node.names}
            found.update(modules)
            if any(_module_path(m) is None for m in modules):  # a name of base, not a module
                found.add(base)
    return {m for m in found if m.split(".")[0] in ("fosmodel", "data_synth")
            and _module_path(m) is not None}


def _module_path(name: str) -> Path | None:
    path = ROOT.joinpath(*name.split("."))
    for candidate in (path.with_suffix(".py"), path / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _layer(name: str) -> str:
    parts = name.split(".")
    if parts[0] == "data_synth":
        return "data_synth"
    return parts[1] if len(parts) > 1 else "__init__"


GRAPH = {_name(p): _imports(p) for top in ("fosmodel", "data_synth")
         for p in sorted((ROOT / top).rglob("*.py"))}


@pytest.mark.parametrize("module", sorted(GRAPH))
def test_imports_run_down_the_layers(module):
    here = _layer(module)
    wrong = []
    for target in GRAPH[module]:
        there = _layer(target)
        if there == "__init__" and target == "fosmodel" and here != "__init__":
            wrong.append(f"{target} (the package's face: import the module itself)")
        elif RANK[there] > RANK[here] or {here, there} in SIDE_BY_SIDE:
            wrong.append(target)
    assert not wrong, f"{module} ({here}) imports upwards or sideways: {sorted(wrong)}"


def test_no_import_cycle():
    modules = {m: {t for t in deps if t in GRAPH and t != m} for m, deps in GRAPH.items()}
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(modules[node]):
            if state.get(nxt) == 1:
                cycle = path[path.index(nxt):] + [nxt] if nxt in path else [node, nxt]
                raise AssertionError("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                visit(nxt, [*path, nxt])
        state[node] = 2

    for start in sorted(modules):
        if start not in state:
            visit(start, [start])


def test_every_module_of_the_package_is_in_a_layer():
    assert {_layer(m) for m in GRAPH} <= set(RANK)
