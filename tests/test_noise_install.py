"""The core install stays lean: allantools is held to releases that do not pull test tools."""

from __future__ import annotations

import re
from importlib.metadata import requires, version
from pathlib import Path

PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"
#: What a core install must not bring: allantools 2024.4 and 2024.6 list both.
TEST_TOOLS = {"pytest", "numpydoc"}


def _name(requirement: str) -> str:
    return re.split(r"[\s<>=!~;\[]", requirement, maxsplit=1)[0].lower()


def test_the_core_requirement_on_allantools_excludes_the_releases_that_pull_pytest():
    block = re.search(r"^dependencies = \[(.*?)^\]", PYPROJECT.read_text(), re.S | re.M)[1]
    core = re.findall(r'^\s*"([^"]+)",', block, re.M)
    (allantools,) = [r for r in core if _name(r) == "allantools"]
    assert allantools.replace(" ", "") == "allantools>=2019.9,<2024.4"
    assert not TEST_TOOLS & {_name(r) for r in core}


def test_the_installed_allantools_requires_no_test_tools():
    needs = {_name(r) for r in requires("allantools") or []}
    assert not TEST_TOOLS & needs, (version("allantools"), needs)
