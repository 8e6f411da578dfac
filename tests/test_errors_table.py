"""The documentation's table of errors, row by row: each problem, built here, gives its row.

The table (docs/pages/cli.md, ``## Errors``) has one row per input problem: the problem,
the message after ``fosmodel: error: `` (``...`` where it names a file or goes on), and the
exit code.  ``BUILDERS`` maps each problem, spelt as in the table, to a function that writes
the input and returns the command line (``FILE_BUILDERS`` those whose input is a record file of
conftest's fixtures); a row without a builder, or a builder without a row,
fails, so that the table and the code cannot drift apart.
"""

import errno
import gzip
import itertools
import json
import os
from pathlib import Path

import numpy as np
import pytest

from fosmodel import cli

PAGE = Path(__file__).resolve().parents[1] / "docs" / "pages" / "cli.md"


def _table():
    """(problem, message, exit code) of each row of the page's ``## Errors`` table."""
    text = PAGE.read_text(encoding="utf-8")
    lines = text.split("\n## Errors\n", 1)[1].split("\n## ", 1)[0].splitlines()
    table = itertools.dropwhile(lambda line: not line.startswith("|"), lines)
    rows = list(itertools.takewhile(lambda line: line.startswith("|"), table))[2:]
    return [tuple(cell.strip() for cell in row.strip("|").split("|")) for row in rows]


ROWS = _table()


def _record(n=40, rate=100.0):
    """CSV text of a small valid record: time, gx and temp_c."""
    rng = np.random.default_rng(1)
    rows = [f"{k / rate!r},{g:.6f},{20 + k / 1000:.3f}" for k, g in
            enumerate(rng.standard_normal(n))]
    return "\n".join(["time,gx,temp_c", *rows]) + "\n"


def _write(tmp, text, name="rec.csv"):
    path = tmp / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    return str(path)


def _fit(tmp, text, *extra, name="rec.csv"):
    return ["fit", _write(tmp, text, name), "--column", "gx", *extra,
            "--out", str(tmp / "model.json")]


def _model(tmp, edit=None):
    """A model file fit on a valid record, optionally edited as a dict by ``edit``."""
    path = tmp / "model.json"
    assert cli.main(_fit(tmp, _record(200), "--max-lag", "2", name="train.csv")) == 0
    if edit:
        path.write_text(json.dumps(edit(json.loads(path.read_text()))))
    return str(path)


def _predict(tmp, record, model):
    return ["predict", _write(tmp, record), "--model", model, "--out", str(tmp / "pred.csv")]


def _gappy(tmp):
    t = np.r_[np.arange(0, 1, 0.01), np.arange(1.5, 3, 0.01)]
    return _write(tmp, "time,gx\n" + "".join(f"{v:.2f},{np.sin(3 * v):.6f}\n" for v in t))


def _truncated_gzip(tmp):
    return _fit(tmp, gzip.compress(_record().encode())[:-10], name="rec.csv.gz")


def _three_d_npy(tmp):
    np.save(tmp / "rec.npy", np.zeros((4, 3, 2)))
    return ["fit", str(tmp / "rec.npy"), "--column", "c0", "--out", str(tmp / "model.json")]


def _cut(path):
    """``path`` cut to its first 20 kB, as a copy that stopped."""
    path.write_bytes(path.read_bytes()[:20_000])
    return path


def _bag_fit(tmp, path, *extra):
    return ["fit", str(path), "--column", "gx", *extra, "--out", str(tmp / "m.json")]


def _bomb(tmp):
    """A record of one repeated line: a 70 kB file that expands to 70 MB."""
    data = gzip.compress(b"gx\n" + b"0\n" * 35_000_000, 9)
    return _fit(tmp, data, "--rate", "100", name="rec.csv.gz")


def _still_time(tmp):
    rows = "".join("0.0,1\n" for _ in range(500_001))
    return _fit(tmp, gzip.compress(("time,gx\n" + rows).encode(), 9), name="rec.csv.gz")


def _device(tmp):
    (tmp / "rec.csv").symlink_to("/dev/zero")
    return ["fit", str(tmp / "rec.csv"), "--column", "gx", "--out", str(tmp / "m.json")]


def _report_over_input(tmp):
    """A study written into the record's own directory, where its table would take the
    record's name."""
    path = _write(tmp, _record(12000), "study.csv")
    return ["study", path, "--column", "gx", "--sensor", "gyro", "--units", "deg/s",
            "--orders", "1", "--degrees", "1", "--methods", "burg", "--protocol", "fair",
            "--split", "30s,20s", "--no-levels", "--out", str(tmp)]


def _spiky_driver(tmp):
    """A gyro record whose die temperature, a driver of its model, has 40 spikes."""
    n = 6000
    rng = np.random.default_rng(2)
    rows = [f"{k / 100!r},{g:.6f},{25 + k / 1e4 + (40 if k % 150 == 0 else 0):.4f}"
            for k, g in enumerate(0.05 * rng.standard_normal(n))]
    path = _write(tmp, "\n".join(["time,gx,temp_c", *rows]) + "\n")
    return ["close-loop", path, "--column", "gx", "--out", str(tmp / "report")]


def _model_edit(tmp, edit):
    """``predict`` with a model file whose fitted state ``edit`` changes (in place)."""
    def edited(data):
        edit(data["fitted"])
        return data
    return _predict(tmp, _record(), _model(tmp, edited))


def _twice(fitted):
    """Repeat the terms, and each list of the fitted state that has one entry per term."""
    for key in ("terms", "coef", "coef_se", "q", "mse_path"):
        fitted[key] = fitted[key] * 2


def _large_model(tmp):
    with open(tmp / "m.json", "wb") as fh:  # sparse: its size says it all
        fh.truncate(17 * 2**20)
    return _predict(tmp, _record(), str(tmp / "m.json"))


def _device_model(tmp):
    (tmp / "m.json").symlink_to("/dev/zero")
    return _predict(tmp, _record(), str(tmp / "m.json"))


def _folder_in_the_report(tmp):
    (tmp / "report" / "allan.md").mkdir(parents=True)
    return _report("allan", tmp, _write(tmp, _record(3000)))


def _report(command, tmp, path, *extra):
    """``study``, ``close-loop`` or ``allan`` on ``path``, with a report directory."""
    study = ["--sensor", "gyro", "--units", "deg/s"] if command == "study" else []
    return [command, path, "--column", "gx", *study, *extra, "--out", str(tmp / "report")]


def _units(tmp, *units):
    """``study`` of column gx with the ``units`` options."""
    return ["study", _write(tmp, _record()), "--column", "gx", *units, "--out",
            str(tmp / "report")]


def _turned(tmp):
    """A minute of gx at rest with a turn at 30 deg/s for 2 s from 20 s on."""
    t = np.arange(6000) / 100.0
    gx = 0.05 * np.random.default_rng(2).standard_normal(len(t)) + 30.0 * ((t >= 20) & (t < 22))
    return _write(tmp, "time,gx\n" + "".join(f"{v:.2f},{g:.5f}\n" for v, g in zip(t, gx)))


def _gravity_in_g(tmp):
    """Ten seconds of an accelerometer triad at rest, in g."""
    rng = np.random.default_rng(3)
    rows = [f"{k / 100:.2f},{a:.5f},{b:.5f},{1 + c:.5f}" for k, (a, b, c) in
            enumerate(2e-3 * rng.standard_normal((1000, 3)))]
    return _write(tmp, "\n".join(["time,ax,ay,az", *rows]) + "\n")


BUILDERS = {
    "missing file": lambda tmp: ["fit", str(tmp / "none.csv"), "--column", "gx", "--out",
                                 str(tmp / "m.json")],
    "empty file": lambda tmp: _fit(tmp, ""),
    "header only": lambda tmp: _fit(tmp, "time,gx\n"),
    "non-numeric cell": lambda tmp: _fit(tmp, "time,gx\n0,1\n0.01,abc\n"),
    "empty or NaN cell": lambda tmp: _fit(tmp, "time,gx\n0,1\n0.01,\n"),
    "column of booleans as a signal":
        lambda tmp: _fit(tmp, "time,gx\n0,True\n0.01,False\n0.02,True\n"),
    "infinite cell": lambda tmp: _fit(tmp, "time,gx\n0,1\n0.01,-inf\n"),
    "value too large to compute with": lambda tmp: _fit(tmp, "time,gx\n0,1\n0.01,1e308\n"),
    "time repeats": lambda tmp: _fit(tmp, "time,gx\n0,1\n0.01,2\n0.01,3\n"),
    "time goes backwards": lambda tmp: _fit(tmp, "time,gx\n0,1\n0.02,2\n0.01,3\n"),
    "gap in time without `--fill` or `--segments`":
        lambda tmp: _fit(tmp, "time,gx\n0,1\n0.01,2\n0.02,3\n0.5,4\n0.51,5\n"),
    "gap in time with `study`, `close-loop`, `allan`, `imu` or `fleet`":
        lambda tmp: _report("allan", tmp, _gappy(tmp)),
    "`--rate` disagreeing with the time column": lambda tmp: _fit(tmp, _record(), "--rate", "50"),
    "time column at a rate no IMU has": lambda tmp: _fit(tmp, "time,gx\n0.5,1\n2.5,2\n4.5,3\n"),
    "time column at no rate at all": lambda tmp: _fit(tmp, "time,gx\n0,1\n1e-12,2\n2e-12,3\n"),
    "preamble rate no IMU has": lambda tmp: _fit(tmp, "Fs,0.5\ngx\n1\n2\n3\n"),
    "one sample and no `--rate`": lambda tmp: _fit(tmp, "time,gx\n0,1\n"),
    "no time column and no `--rate`": lambda tmp: _report("allan", tmp, _write(tmp, "gx\n1\n2\n")),
    "missing or misspelt column": lambda tmp: _fit(tmp, _record(), "--column", "g_x"),
    "wrong delimiter": lambda tmp: _fit(tmp, "time;gx\n0;1\n0.01;2\n"),
    "column name given twice": lambda tmp: _fit(tmp, "time,gx,gx\n0,1,2\n0.01,2,3\n"),
    "column without a name": lambda tmp: _fit(tmp, "time,,gx\n0,1,2\n0.01,2,3\n"),
    "row with more fields than the header": lambda tmp: _fit(tmp, "time,gx\n0,1,2\n0.01,2,3\n"),
    "file not in UTF-8": lambda tmp: _fit(tmp, "time,gx\n0,1\n0.01,2\xb0\n".encode("latin-1")),
    "damaged compressed file": _truncated_gzip,
    "damaged `.npy` or Parquet file": lambda tmp: _fit(tmp, b"not numpy", name="rec.npy"),
    "`.npy` array of 3 or more dimensions": _three_d_npy,
    "`--topic` for a file without topics": lambda tmp: _fit(tmp, _record(), "--topic", "/imu0"),
    "bad `--scale`": lambda tmp: _fit(tmp, _record(), "--scale", "gx=x"),
    "`--scale` of a missing column": lambda tmp: _fit(tmp, _record(), "--scale", "g_x=2"),
    "bad `--rate` or other option value": lambda tmp: _fit(tmp, _record(), "--rate", "-5"),
    "modelled column given as its own input": lambda tmp: _fit(tmp, _record(), "--exog", "gx:1"),
    "record too short for the lag window": lambda tmp: _fit(tmp, _record(), "--max-lag", "100"),
    "too few samples for the candidates": lambda tmp: _fit(tmp, _record(), "--degree", "2"),
    "constant record":
        lambda tmp: _fit(tmp, "time,gx\n" + "".join(f"{k / 100},1\n" for k in range(50))),
    "column of zeros":
        lambda tmp: _fit(tmp, "time,gx\n" + "".join(f"{k / 100},0\n" for k in range(50))),
    "denormal numbers": lambda tmp: _fit(tmp, "time,gx\n" + "".join(
        f"{k / 100},{(-1) ** k * 3e-310!r}\n" for k in range(50))),
    "integers beyond float64's exact range": lambda tmp: _fit(tmp, "time,gx\n" + "".join(
        f"{k / 100},{2**64 - 1 - 4096 * k}\n" for k in range(50))),
    "an output that is a device, FIFO or socket":
        lambda tmp: _fit(tmp, _record())[:-1] + ["/dev/null"],
    "outliers on a driver of the model (`close-loop`)": _spiky_driver,
    "a compressed file that expands far": _bomb,
    "a compressed line that does not end":
        lambda tmp: _fit(tmp, gzip.compress(b"gx\n1\n" + b"0" * 20 * 2**20, 9), "--rate",
                         "100", name="rec.csv.gz"),
    "a header longer than 1 MiB": lambda tmp: _fit(tmp, "g" * 2**20 + "x\n1\n2\n"),
    "time that does not advance over a block": _still_time,
    "a device, FIFO or socket as the record": _device,
    "an output naming a file the command reads":
        lambda tmp: _fit(tmp, _record())[:-1] + [str(tmp / "rec.csv")],
    "two outputs naming one file":
        lambda tmp: _report("close-loop", tmp, _write(tmp, _record(3000)), "--json",
                            str(tmp / "o.json"), "--model", str(tmp / "o.json")),
    "a report that would replace an input": _report_over_input,
    "record too short for the model's lag window (`predict`)":
        lambda tmp: _predict(tmp, _record(2), _model(tmp)),
    "record too short for the split": lambda tmp: _report("close-loop", tmp,
                                                          _write(tmp, _record(3000))),
    "`--segments` with `study`, `close-loop` or `allan`":
        lambda tmp: _report("allan", tmp, _gappy(tmp), "--segments"),
    "`--split` without units": lambda tmp: _report("study", tmp, _write(tmp, _record()),
                                                   "--split", "180,180"),
    "unknown units": lambda tmp: _units(tmp, "--units", "deg"),
    "units of another sensor than `--sensor`":
        lambda tmp: _units(tmp, "--units", "deg/s", "--sensor", "accel"),
    "a column whose units are neither given nor in its name": lambda tmp: _units(tmp),
    "units given for a column not studied": lambda tmp: _units(tmp, "--units", "gy=deg/s"),
    "model file missing": lambda tmp: _predict(tmp, _record(), str(tmp / "none.json")),
    "model file not JSON": lambda tmp: _predict(tmp, _record(), _write(tmp, "{", "m.json")),
    "model file damaged inside":
        lambda tmp: _predict(tmp, _record(), _model(tmp, lambda d: {**d, "fitted": {}})),
    "model file from a newer fosmodel":
        lambda tmp: _predict(tmp, _record(), _model(tmp, lambda d: {**d, "format_version": 99})),
    "model file of another kind":
        lambda tmp: _predict(tmp, _record(), _write(tmp, '{"rows": []}', "m.json")),
    "model file that is a FIFO, a device or a directory": _device_model,
    "model file over 16 MiB": _large_model,
    "model file nested too deep":
        lambda tmp: _predict(tmp, _record(), _write(tmp, "[" * 50 + "]" * 50, "m.json")),
    "model file with a term outside its candidate set":
        lambda tmp: _model_edit(tmp, lambda f: f.update(terms=["y[n-1000000000000]"])),
    "model file with a term twice": lambda tmp: _model_edit(tmp, _twice),
    "model file with a weight no fit gives":
        lambda tmp: _model_edit(tmp, lambda f: f.update(coef=[1e12] * len(f["coef"]))),
    "a folder where a file of the report goes": _folder_in_the_report,
    "output directory missing":
        lambda tmp: _fit(tmp, _record())[:-1] + [str(tmp / "none" / "m.json")],
    "output file is a directory": lambda tmp: _fit(tmp, _record())[:-1] + [str(tmp)],
    "report directory is a file":
        lambda tmp: _report("allan", tmp, _write(tmp, _record()))[:-1] + [str(tmp / "rec.csv")],
    "two records of one name in a fleet": lambda tmp: [
        "fleet", _write(tmp, _record()), _write(tmp, _record(), "rec.csv.gz"), "--out",
        str(tmp / "store")],
    "unknown step of a fleet": lambda tmp: ["fleet", _write(tmp, _record()), "--steps",
                                            "allan,fit", "--out", str(tmp / "store")],
    "a record that moves (`allan`, `imu`, `fleet`)":
        lambda tmp: _report("allan", tmp, _turned(tmp), "--units", "deg/s"),
    "units given against the units a column's name spells":
        lambda tmp: ["allan", _write(tmp, _record().replace("gx", "gx_dps")), "--columns",
                     "gx_dps", "--units", "gx_dps=rad/s", "--out", str(tmp / "report")],
    "accelerometers whose mean contradicts gravity in the units given":
        lambda tmp: ["allan", _gravity_in_g(tmp), "--columns", "ax,ay,az", "--units", "m/s^2",
                     "--out", str(tmp / "report")],
}

# Problems whose input is one of conftest's record files: (the fixture that writes it, a
# builder of the command line from the directory and that fixture's writer, given at call time)
FILE_BUILDERS = {
    "bursty host time without `--uniform`":
        ("bursty_csv", lambda tmp, write: ["fit", str(write()[0]), "--column", "gx", "--out",
                                           str(tmp / "m.json")]),
    "outliers carrying over 1 % of a column's mean square":
        ("spiky_csv", lambda tmp, write: ["fit", str(write(with_time=False)[0]), "--column", "a",
                                          "--out", str(tmp / "m.json")]),
    "outliers dropped without a time column":
        ("spiky_csv", lambda tmp, write: ["fit", str(write(with_time=False)[0]), "--column", "a",
                                          "--outliers", "drop", "--out", str(tmp / "m.json")]),
    "several IMU topics without `--topic`":
        ("imu_bag", lambda tmp, write: _bag_fit(tmp, write("two", imu={"/imu0": 400,
                                                                      "/imu1": 400})[0])),
    "`--topic` the log lacks":
        ("imu_bag", lambda tmp, write: _bag_fit(tmp, write("imu.bag", "ros1")[0], "--topic",
                                                "/imu2")),
    "`--topic` of another message type":
        ("imu_bag", lambda tmp, write: _bag_fit(tmp, write("imu", "mcap", temperature={
            "/temp": 5})[0], "--topic", "/temp")),
    "damaged ROS bag or ULog file":
        ("imu_bag", lambda tmp, write: _bag_fit(tmp, _cut(write("imu.bag", "ros1")[0]))),
}


def _read_only(tmp, monkeypatch):
    """A folder the process may not write: its mode, and where that does not bind (root), as
    the system would answer."""
    folder = tmp / "locked"
    folder.mkdir(mode=0o555)
    real = os.access
    monkeypatch.setattr("fosmodel.io.output.os.access",
                        lambda path, mode: real(path, mode) and Path(path) != folder)
    return _fit(tmp, _record())[:-1] + [str(folder / "m.json")]


def _full_disk(tmp, monkeypatch):
    """The disk fills as the model is written (simulated: its fsync is refused)."""
    def fsync(fd):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr("fosmodel.io.output.os.fsync", fsync)
    return _fit(tmp, _record())


# Problems the system raises, simulated where a test cannot make them (the monkeypatch fixture)
PATCHED_BUILDERS = {
    "output folder not writable": _read_only,
    "disk full while writing an output": _full_disk,
}


def _build(problem, tmp, request):
    """The command line of ``problem``'s row, its input written into ``tmp``."""
    if problem in FILE_BUILDERS:
        fixture, build = FILE_BUILDERS[problem]
        return build(tmp, request.getfixturevalue(fixture))
    if problem in PATCHED_BUILDERS:
        return PATCHED_BUILDERS[problem](tmp, request.getfixturevalue("monkeypatch"))
    return BUILDERS[problem](tmp)


def _snapshot(directory):
    return {str(p.relative_to(directory)): p.read_bytes() if p.is_file() else None
            for p in sorted(directory.rglob("*"))}


def _run(argv):
    try:
        return cli.main(argv)
    except SystemExit as exc:  # argparse: a usage error
        return exc.code


def test_the_readme_has_the_errors_table():
    assert len(ROWS) >= 30 and all(len(row) == 3 for row in ROWS)


def test_every_builder_has_a_row():
    assert sorted({*BUILDERS, *FILE_BUILDERS, *PATCHED_BUILDERS} - {row[0] for row in ROWS}) == []


@pytest.mark.parametrize("problem, shown, code", ROWS, ids=[row[0] for row in ROWS])
def test_each_row_of_the_errors_table(problem, shown, code, tmp_path, capsys, request):
    assert problem in {*BUILDERS, *FILE_BUILDERS, *PATCHED_BUILDERS}, (
        f"no test builds the documentation's error row {problem!r}")
    argv = _build(problem, tmp_path, request)
    capsys.readouterr()  # what building printed
    before = _snapshot(tmp_path)
    assert _run(argv) == int(code)
    lines = [line for line in capsys.readouterr().err.splitlines()
             if not line.startswith("fosmodel: note: ")]
    assert len(lines) == 1 and lines[0].startswith("fosmodel: error: "), lines
    at = 0
    for part in filter(None, shown.strip("`").split("...")):  # in order, around the "..."
        assert part in lines[0][at:], (part, lines[0])
        at = lines[0].index(part, at) + len(part)
    assert _snapshot(tmp_path) == before  # nothing written
