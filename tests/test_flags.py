"""The library names its options in its own terms; the command line says them as flags.

A message or note of the library names an option as the keyword argument a caller passes
(``rate=HZ``, ``gaps='fill'``); ``fosmodel.cli.flags.with_flags`` rewrites it as the flag
for the errors, notes and warnings the command line prints.  The command line's exact
messages are held by ``test_errors_table.py`` and ``test_cli.py``.
"""

import ast
import re
from pathlib import Path

import pytest

from fosmodel import cli
from fosmodel.cli.flags import with_flags
from fosmodel.io import load_record

ROOT = Path(__file__).resolve().parents[1]
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")
#: The command line's folder: its messages are the ones that say flags.
COMMAND_LINE = ("cli",)
EXEMPT = COMMAND_LINE


def _messages(path):
    """The string literals of a module but its docstrings, with their line numbers."""
    tree = ast.parse(path.read_text())
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                                       ast.AsyncFunctionDef))
                  and node.body and isinstance(node.body[0], ast.Expr)
                  and isinstance(node.body[0].value, ast.Constant)}
    return [(node.lineno, node.value) for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and id(node) not in docstrings]


def test_no_command_line_flag_in_the_library_s_messages():
    found = [f"{path.relative_to(ROOT)}:{line}: {text!r}"
             for path in sorted((ROOT / "fosmodel").rglob("*.py"))
             if path.relative_to(ROOT / "fosmodel").parts[0] not in EXEMPT
             for line, text in _messages(path) if FLAG.search(text)]
    assert not found, "\n".join(found)


def test_the_scan_sees_flags_in_f_strings_but_not_in_docstrings(tmp_path):
    path = tmp_path / "m.py"
    path.write_text('"""See ``--rate``."""\ndef f(n):\n    """--scale."""\n'
                    '    return f"pass --fill to {n}"\n')
    assert [text for _, text in _messages(path) if FLAG.search(text)] == ["pass --fill to "]


@pytest.mark.parametrize("library, command_line", [
    ("rec.csv: no time column; give the sample rate with rate=HZ",
     "rec.csv: no time column; give the sample rate with --rate HZ"),
    ("rec.csv: a single sample cannot give a rate; pass rate=",
     "rec.csv: a single sample cannot give a rate; pass --rate"),
    ("rec.csv: rate=50 Hz disagrees with the time column (100 Hz)",
     "rec.csv: --rate 50 Hz disagrees with the time column (100 Hz)"),
    ("pass uniform=True to take the samples as uniformly spaced at that rate, or rate=HZ",
     "pass --uniform to take the samples as uniformly spaced at that rate, or --rate HZ"),
    ("pass gaps='fill' to interpolate across them or gaps='segments' to fit on the pieces",
     "pass --fill to interpolate across them or --segments to fit on the pieces"),
    ("check its units or pass scale={'gx': FACTOR}", "check its units or pass --scale gx=FACTOR"),
    ("(scale={'time': 0.001} turns milliseconds into seconds)",
     "(--scale time=0.001 turns milliseconds into seconds)"),
    ('scale={"it\'s": 2.0}: the factor', "--scale it's=2.0: the factor"),
    ("scale='gx=x': expected NAME=FACTOR", "--scale 'gx=x': expected NAME=FACTOR"),
    ("rec.csv: scale= names no column 'g_x'", "rec.csv: --scale names no column 'g_x'"),
    ("column 'gx' is given twice in scale=", "column 'gx' is given twice in --scale"),
    ("outliers='clip': no outliers found", "--outliers clip: no outliers found"),
    ("kept (outliers='clip' or 'drop' handles them)",
     "kept (--outliers clip or drop handles them)"),
    ("outliers='drop' would remove 2 sample(s); use outliers='clip' (or 'keep')",
     "--outliers drop would remove 2 sample(s); use --outliers clip (or keep)"),
    ("column 'gx_dps' is named twice in columns=", "column 'gx_dps' is named twice in --columns"),
    ("2 IMU topics, choose one with topic=: /a, /b",
     "2 IMU topics, choose one with --topic: /a, /b"),
    ("leave out temperature_topic=", "leave out --temperature-topic"),
    ("shorten train_s= and evaluate_s= (the loop's: loop_split=) or horizon_s=, or give",
     "shorten --split (the loop's: --loop-split) or --horizon, or give"),
])
def test_each_option_the_library_names_becomes_its_flag(library, command_line):
    assert with_flags(library) == command_line


@pytest.mark.parametrize("text", [
    "/data/rate=100/imu.csv: no such file",  # a path that spells a keyword
    "column 'rate=2' is constant",           # so does a name
    "sensor_rate=5 Hz",                      # and the end of a longer word
])
def test_what_only_looks_like_an_option_is_left_alone(text):
    assert with_flags(text) == text


def test_the_command_line_prints_the_library_s_notes_with_flags(tmp_path, capsys):
    path = tmp_path / "r.csv"
    path.write_text("gx\n" + "".join(f"{(k * 7919) % 13 / 10}\n" for k in range(200)))
    assert load_record(path, rate=100.0, uniform=True).notes == [
        "uniform=True has no effect: the record has no time column"]
    code = cli.main(["fit", str(path), "--column", "gx", "--rate", "100", "--uniform",
                     "--max-lag", "2", "--out", str(tmp_path / "m.json")])
    err = capsys.readouterr().err
    assert code == 0
    assert "fosmodel: note: --uniform has no effect: the record has no time column\n" in err
