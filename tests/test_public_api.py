"""The public API: every package declares its names, and the studies, docs and benchmarks use
only those.

A package's public names are its ``__all__``, imported on first use (``fosmodel._lazy``):
the ``if TYPE_CHECKING:`` imports type checkers read, the table ``attach`` imports from and
``__all__`` must name the same things, each must resolve, and none may be the name of a
module of its package (importing that module would hide it).
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "fosmodel"
#: Every package of fosmodel, by dotted name.
PACKAGES = sorted(".".join(p.parent.relative_to(ROOT).parts) for p in PACKAGE.rglob("__init__.py"))
#: Modules at the top of the package that a user imports from (the others are private).
TOP_MODULES = ("fosmodel.demo",)
#: Packages whose names are imported on first use: not the command line's (it imports its
#: parser) nor the loop's effect catalogue (each kind registers itself as it is imported).
LAZY = [p for p in PACKAGES if p not in ("fosmodel.cli", "fosmodel.loop.effects")]


def _tree(package: str) -> ast.Module:
    return ast.parse((ROOT.joinpath(*package.split(".")) / "__init__.py").read_text())


def _type_checking_names(tree: ast.Module) -> dict[str, set[str]]:
    """The names the ``if TYPE_CHECKING:`` block imports, by relative module."""
    block = next(node for node in tree.body if isinstance(node, ast.If)
                 and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING")
    names: dict[str, set[str]] = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom) and node.level == 1, ast.unparse(node)
        names.setdefault(node.module or "", set()).update(a.name for a in node.names)
    return names


def _attached_names(tree: ast.Module) -> dict[str, set[str]]:
    """The table the package gives ``attach``."""
    call = next(node for node in ast.walk(tree) if isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name) and node.func.id == "attach")
    return {module: set(names) for module, names in ast.literal_eval(call.args[1]).items()}


@pytest.mark.parametrize("package", PACKAGES)
def test_every_package_declares_its_public_names(package):
    module = importlib.import_module(package)
    assert module.__all__ and len(set(module.__all__)) == len(module.__all__)
    missing = [name for name in module.__all__ if not hasattr(module, name)]
    assert not missing, f"{package}.__all__ names what it does not hold: {missing}"


@pytest.mark.parametrize("package", LAZY)
def test_type_checkers_the_lazy_table_and_all_name_the_same_things(package):
    tree = _tree(package)
    typed, attached = _type_checking_names(tree), _attached_names(tree)
    assert typed == attached
    module = importlib.import_module(package)
    public = set(module.__all__) - {"__version__"}
    assert public == {name for names in attached.values() for name in names}
    assert dir(module) == sorted(module.__all__)


@pytest.mark.parametrize("package", LAZY)
def test_no_public_name_is_hidden_by_a_module_of_its_package(package):
    folder = ROOT.joinpath(*package.split("."))
    modules = {p.stem for p in folder.glob("*.py")} | {p.name for p in folder.iterdir()
                                                       if (p / "__init__.py").is_file()}
    assert not set(importlib.import_module(package).__all__) & modules


def test_a_package_s_names_are_imported_when_first_used():
    heavy = ("sklearn", "statsmodels", "matplotlib", "pandas", "scipy")
    code = (f"import sys, {', '.join(LAZY)}\n"
            f"print(sorted(m for m in sys.modules if m.split('.')[0] in {heavy!r}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"
    code = ("import sys; from fosmodel.io import SplitSpec\n"
            "print(sorted(m for m in sys.modules if m.startswith('fosmodel.io.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "['fosmodel.io.split']"


def test_an_unknown_name_is_an_attribute_error():
    import fosmodel.io

    with pytest.raises(AttributeError, match="module 'fosmodel.io' has no attribute 'load'"):
        fosmodel.io.load  # noqa: B018


# What the studies, the docs pages, the README and the benchmarks import

#: ``from fosmodel... import a, b`` (one line or parenthesised) and ``import fosmodel...``,
#: in a script or a page, after the prompts of a console example are taken off.
FROM_IMPORT = re.compile(r"^[ \t]*from[ \t]+(fosmodel[\w.]*)[ \t]+import[ \t]+(\([^)]*\)|.*)$",
                         re.MULTILINE)
PLAIN_IMPORT = re.compile(r"^[ \t]*import[ \t]+(fosmodel[\w.]*)", re.MULTILINE)
PROMPT = re.compile(r"^([ \t]*)(>>>|\.\.\.) ?", re.MULTILINE)
CLIENTS = sorted([*ROOT.glob("studies/*.py"), *ROOT.glob("benchmarks/*.py"),
                  *ROOT.glob("docs/*.py"), *ROOT.glob("docs/pages/*.md"), ROOT / "README.md"])
#: Benchmarks that time the kernel's parts apart must reach inside it; each says why.
INSIDE_THE_KERNEL = {
    "benchmarks/bench_fos_speed.py": "times the correlations, Gram columns and search apart",
    "benchmarks/bench_sysidentpy.py": "clears the pair plan to time a first fit, one BLAS thread",
}


def _imports(text: str) -> list[tuple[str, str]]:
    """Every ``(module, name)`` imported from fosmodel, ``(module, "")`` for ``import module``."""
    text = PROMPT.sub(r"\1", text)
    found = [(m, "") for m in PLAIN_IMPORT.findall(text)]
    for module, names in FROM_IMPORT.findall(text):
        for name in names.split("#")[0].strip("()").replace("\n", " ").split(","):
            if name.split():
                found.append((module, name.split()[0]))
    return found


def _public(module: str, name: str) -> bool:
    if module not in PACKAGES and module not in TOP_MODULES:
        return False
    if not name:  # ``import fosmodel.io``: a package
        return module in PACKAGES
    return name in importlib.import_module(module).__all__


def test_the_client_scanner_reads_every_form_of_import():
    text = ("from fosmodel import FOSModel, fos  # a comment\n"
            ">>> from fosmodel.core import (\n...     Term,\n...     layout,\n... )\n"
            "    import fosmodel.models.model  # noqa\n"
            "from fosmodel.io.loader import load_record as load\n")
    assert _imports(text) == [
        ("fosmodel.models.model", ""), ("fosmodel", "FOSModel"), ("fosmodel", "fos"),
        ("fosmodel.core", "Term"), ("fosmodel.core", "layout"),
        ("fosmodel.io.loader", "load_record")]
    assert [_public(m, n) for m, n in _imports(text)] == [False, True, True, True, True, False]


@pytest.mark.parametrize("path", CLIENTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_studies_docs_and_benchmarks_use_only_public_names(path):
    if path.relative_to(ROOT).as_posix() in INSIDE_THE_KERNEL:
        pytest.skip(INSIDE_THE_KERNEL[path.relative_to(ROOT).as_posix()])
    wrong = [f"{module}: {name}" if name else module
             for module, name in _imports(path.read_text()) if not _public(module, name)]
    assert not wrong, (f"{path.relative_to(ROOT)} imports names no package declares public "
                       f"(import them from the package, or add them to its __all__): {wrong}")


def test_the_api_page_lists_every_public_name_as_the_packages_give_it():
    spec = importlib.util.spec_from_file_location("api_page", ROOT / "docs" / "api_page.py")
    api_page = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(api_page)
    current = api_page.PAGE.read_text(encoding="utf-8")
    assert set(api_page.PACKAGES) == set(PACKAGES)
    assert current == api_page.page_text(current), "run: python docs/api_page.py"


# The developers' guide and the README describe the layers as the code has them

GUIDE = (ROOT / "DEVELOPERS.md").read_text(encoding="utf-8")


def _diagram() -> dict[str, list[str]]:
    """Each layer of the guide's diagram and the public names it shows."""
    block = GUIDE.split("```text\n", 1)[1].split("```", 1)[0]
    rows = (re.match(r"(\w+) {2,}(\w.*)$", line) for line in block.splitlines())
    return {row[1]: [name.strip() for name in row[2].split(",")] for row in rows if row}


def test_the_guide_s_diagram_shows_every_layer_with_names_it_exports():
    diagram, package_of = _diagram(), {p.rpartition(".")[2]: p for p in PACKAGES}
    assert set(diagram) == set(package_of)
    wrong = [f"{layer}: {name}" for layer, names in diagram.items() for name in names
             if name not in importlib.import_module(package_of[layer]).__all__]
    assert not wrong, f"the diagram shows names the layer does not export: {wrong}"


def test_the_guide_s_module_table_lists_every_module_and_no_other():
    listed = set(re.findall(r"`(fosmodel/[\w/]+\.py)`", GUIDE))
    cli_row = next(line for line in GUIDE.splitlines() if line.startswith("| `fosmodel/cli/`"))
    modules = {p.relative_to(ROOT).as_posix() for p in PACKAGE.rglob("*.py")
               if p.name != "__init__.py" or p.parent == PACKAGE}
    missing = [m for m in modules if m not in listed
               and not (m.startswith("fosmodel/cli/") and f"`{Path(m).name}`" in cli_row)]
    assert not missing, f"DEVELOPERS.md's module table lacks {sorted(missing)}"
    assert not [m for m in listed if not (ROOT / m).is_file()], "the table lists moved modules"


def test_the_readme_s_layer_chain_names_every_layer_in_order():
    layout = (ROOT / "README.md").read_text(encoding="utf-8").split("## Layout", 1)[1]
    chain = layout.split("down this line", 1)[1].split("See `DEVELOPERS.md`", 1)[0]
    floors = [re.findall(r"`([\w./]+)`", re.sub(r"\([^()]*\)", "", floor))
              for floor in chain.split("->")]
    assert floors == [["core", "typeset"], ["models"], ["io"], ["noise"], ["filter"],
                      ["study", "loop"], ["workflows"], ["cli/", "demo.py"]]
