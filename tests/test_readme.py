"""The documentation's examples run: the Python and command-line blocks of the README and of
every page in docs/pages."""

import doctest
import re
import shlex
from pathlib import Path

import pytest

from fosmodel.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs" / "pages").glob("*.md"))]


def _blocks(language, pages=PAGES):
    return [(page.relative_to(ROOT).as_posix(), block) for page in pages for block in
            re.findall(rf"```{language}\n(.*?)```", page.read_text(), flags=re.S)]


def _commands():
    """Every command-line block but the install commands (README and the docs' home)."""
    return [(page, block) for page, block in _blocks("bash")
            if not block.lstrip().startswith("pip install")]


@pytest.mark.parametrize(("page", "code"), _blocks("python"))
@pytest.mark.slow
def test_python_blocks_run(page, code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    exec(compile(code, page, "exec"), {})


def _sessions():
    """The interactive (pycon) blocks of each page as one session (later blocks use earlier)."""
    by_page: dict[str, list[str]] = {}
    for page, block in _blocks("pycon"):
        by_page.setdefault(page, []).append(block)
    return [(page, "\n".join(blocks)) for page, blocks in by_page.items()]


@pytest.mark.parametrize(("page", "session"), _sessions(), ids=lambda value: value[:40])
def test_interactive_blocks_print_what_they_show(page, session, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    test = doctest.DocTestParser().get_doctest(session, {}, page, page, 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    runner.run(test)
    assert runner.summarize(verbose=False).failed == 0


def test_first_two_commands_install_demo_and_test():
    first, second = _blocks("bash", PAGES[:1])[0][1].strip().splitlines()[:2]
    assert first.startswith("pip install") and first.endswith("fosmodel demo")
    assert second.startswith("pip install") and "pytest" in second


def test_the_readme_is_short_and_its_links_resolve():
    text = PAGES[0].read_text()
    assert len(text.splitlines()) <= 200
    for link in re.findall(r"\]\(([^)#]+)\)", text):
        assert (ROOT / link).is_file(), link


@pytest.mark.parametrize(("page", "block"), _commands())
@pytest.mark.slow
def test_command_line_blocks_run(page, block, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for line in block.strip().splitlines():
        args = shlex.split(line, comments=True)
        assert args[0] == "fosmodel", f"{page}: {line}"
        assert main(args[1:]) == 0, f"{page}: {line}"
