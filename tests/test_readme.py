"""The README's examples run: its Python blocks, and its command-line block through the CLI."""

import re
import shlex
from pathlib import Path

import pytest

from fosmodel.cli import main

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()


def _blocks(language):
    return re.findall(rf"```{language}\n(.*?)```", README, flags=re.S)


@pytest.mark.parametrize("code", _blocks("python"))
def test_python_blocks_run(code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})


def test_first_two_commands_install_demo_and_test():
    first, second = _blocks("bash")[0].strip().splitlines()[:2]
    assert first.startswith("pip install") and first.endswith("fosmodel demo")
    assert second.startswith("pip install") and "pytest" in second


def test_command_line_block_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    block = next(b for b in _blocks("bash") if "fosmodel fit" in b)
    for line in block.strip().splitlines():
        args = shlex.split(line, comments=True)
        assert args[0] == "fosmodel"
        assert main(args[1:]) == 0, line
    assert (tmp_path / "pred.csv").exists() and (tmp_path / "rec.truth.json").exists()
