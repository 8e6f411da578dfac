"""Ctrl-C has one behaviour whatever its moment: the exit code agrees with what is on disk.

Until the command returns, its outputs are taken back (code 130, ``fosmodel: interrupted``);
once they are committed, the command finishes and exits 0.  Each case is a real SIGINT sent
by the process to itself at that moment, in a child process.
"""

import json
import subprocess
import sys
import textwrap

import numpy as np
import pandas as pd
import pytest

#: Installs Python's own Ctrl-C handler (a shell running the tests in the background
#: ignores SIGINT, and an ignored signal stays so through exec), then wraps ``TARGET`` so
#: that the process sends itself SIGINT at the moment under test, and runs the command.
CHILD = textwrap.dedent("""
    import importlib, os, signal, sys, time
    signal.signal(signal.SIGINT, signal.default_int_handler)
    module, name, when = sys.argv[1], sys.argv[2], sys.argv[3]
    target = importlib.import_module(module)
    original = getattr(target, name)

    def ctrl_c():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.5)  # the handler runs here, if it raises

    def wrapped(*args, **kwargs):
        if when == "before":
            ctrl_c()
        out = original(*args, **kwargs)
        if when == "after":
            ctrl_c()
        return out

    setattr(target, name, wrapped)
    from fosmodel import cli
    sys.exit(cli.main(sys.argv[4:]))
""")


@pytest.fixture
def record(tmp_path):
    n = 3000
    gx = 0.1 * np.random.default_rng(0).standard_normal(n)
    pd.DataFrame({"time": np.arange(n) / 100.0, "gx": gx}).to_csv(tmp_path / "rec.csv",
                                                                   index=False)
    old = tmp_path / "m.json"
    old.write_text('{"an": "older output"}\n')
    return tmp_path


def _run(folder, module, name, when):
    argv = ["fit", str(folder / "rec.csv"), "--column", "gx", "--max-lag", "2",
            "--out", str(folder / "m.json")]
    return subprocess.run([sys.executable, "-c", CHILD, module, name, when, *argv],
                          capture_output=True, text=True, timeout=300, cwd=folder)


def _left(folder):
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("module, name, when", [
    ("fosmodel.io.journal", "_remove", "before"),  # removing the replaced file's copy
    ("fosmodel.cli.exit_codes", "_run", "after"),  # the command has returned its code
])
def test_ctrl_c_after_the_outputs_are_committed_finishes_with_0(record, module, name, when):
    done = _run(record, module, name, when)
    assert done.returncode == 0, done.stderr
    assert "interrupted" not in done.stderr
    assert "model written to" in done.stdout
    assert json.loads((record / "m.json").read_text())["format"]
    assert _left(record) == ["m.json", "rec.csv"]  # no copy of the old file, no temporary


@pytest.mark.parametrize("module, name, when", [
    ("fosmodel.io.model_file", "write_model", "after"),  # written, the command not returned
    ("fosmodel.io.journal", "replace", "before"),  # about to put the model in place
])
def test_ctrl_c_before_the_command_returns_takes_every_output_back(record, module, name, when):
    done = _run(record, module, name, when)
    assert done.returncode == 130, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "fosmodel: interrupted"
    assert (record / "m.json").read_text() == '{"an": "older output"}\n'
    assert _left(record) == ["m.json", "rec.csv"]
