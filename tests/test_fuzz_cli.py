"""Malformed input through every command that reads a file: exit 2, one line, nothing written.

A seeded generator writes a few hundred broken files (each kind of damage a user's logger or
editor can do, in several variants at random places); each is fed to ``fit``, ``predict``
(as the record, and as the model), ``study``, ``close-loop`` and ``allan``, and bad options
(``--column``, ``--scale``, ``--rate``, ...) are fed on a valid record.  Every run must exit
with code 2 (never 1, never a traceback), print exactly one ``fosmodel: error: `` line naming
the file (besides any ``fosmodel: note: `` lines), raise no warning, and leave the output
directory byte for byte as it was: no new file or directory, pre-existing outputs unchanged.
Where the damage sits at a known place, the message must name that column and line.

Beyond damage: records where a result would mean nothing (constant, a few samples, noise-free),
files that are no regular file (a FIFO, a device through a symlink, a directory), compressed
files that expand far, complex numbers, and outputs that name the input however spelt.  On
those a command refuses in one line or succeeds; never a traceback, never another exit code,
never an output where it failed.
"""

import bz2
import gzip
import importlib.util
import io
import json
import lzma
import os
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import cli
from fosmodel.io.loader import load_record
from fosmodel.models.model import FOSModel

N_ROWS = 40
HEADER = "time,gx,temp"
NAMES = HEADER.split(",")


def _base_lines():
    """A valid 100 Hz record: header and N_ROWS rows of time, gyro and temperature."""
    rng = np.random.default_rng(7)
    gx = lfilter([1.0], [1.0, -0.8], rng.standard_normal(N_ROWS))
    return [HEADER] + [f"{k / 100:.2f},{g:.6f},{20 + k / 1000:.3f}" for k, g in enumerate(gx)]


BASE = _base_lines()


def _text(lines):
    return "".join(f"{line}\n" for line in lines).encode()


def _cells(lines, row, col, value):
    """``lines`` with the cell at file line ``row + 1``, column ``col`` replaced by ``value``."""
    cells = lines[row].split(",")
    cells[col] = value
    return [*lines[:row], ",".join(cells), *lines[row + 1:]]


def _data_row(rng):
    return int(rng.integers(1, len(BASE)))


# --- the kinds of damage: each returns (id, file name, bytes, expected text or None) ------------


def _empty_and_blank(rng):
    blanks = [bytes(rng.choice(list(b" \t\r\n"), int(rng.integers(1, 30))).astype(np.uint8))
              for _ in range(5)]
    return [("empty", "r.csv", b"", "the file is empty")] + [
        (f"blank-{i}", "r.csv", text, "the file is empty") for i, text in
        enumerate(blanks)]


def _header_only(rng):
    return [("header-only", "r.csv", _text([HEADER]), "header only"),
            ("header-only-preamble", "r.csv", _text(["Fs,100", "gx,temp"]), None),
            ("header-only-gz", "r.csv.gz", gzip.compress(_text([HEADER])), "header only")]


def _garbage(rng):
    suffixes = [".csv"] * 16 + [".csv.gz", ".csv.bz2", ".csv.xz"] * 2 + [".npy", ".parquet"] * 6
    return [(f"garbage-{i}{suffix}", f"r{suffix}", b"\xff" + rng.bytes(int(rng.integers(1, 300))),
             None) for i, suffix in enumerate(suffixes)]


def _non_utf8(rng):
    out = []
    for i in range(12):
        row = int(rng.integers(0, len(BASE)))
        data = bytearray(_text(BASE[:row]))
        line = BASE[row].encode()
        at = int(rng.integers(0, len(line) + 1))
        byte = [b"\xb0", b"\xe9", b"\xff", b"\x80"][i % 4]
        data += line[:at] + byte + line[at:] + b"\n" + _text(BASE[row + 1:])
        out.append((f"non-utf8-{i}", "r.csv", bytes(data), f"line {row + 1}: not UTF-8 text"))
    return out


def _delimiters(rng):
    out = []
    for sep, label in ((";", "semicolons"), ("\t", "tabs"), ("|", "bars")):
        lines = [line.replace(",", sep) for line in BASE]
        out += [(f"delimiter-{label}", "r.csv", _text(lines), f"separated by {label}"),
                (f"delimiter-{label}-gz", "r.csv.gz", gzip.compress(_text(lines)), label),
                (f"delimiter-{label}-decimal-comma", "r.csv",
                 _text([lines[0]] + [line.replace(".", ",") for line in lines[1:]]), label)]
    return out


def _ragged(rng):
    out = []
    for i in range(16):
        row = 1 if i < 3 else _data_row(rng)
        longer = i % 2 == 0
        line = BASE[row] + ",1.5" if longer else BASE[row].rsplit(",", 1)[0]
        lines = [*BASE[:row], line, *BASE[row + 1:]]
        expected = f"line {row + 1}" if longer else f"column 'temp', line {row + 1}: an empty"
        out.append((f"ragged-{i}", "r.csv", _text(lines), expected))
    return out


def _bad_cells(rng, tokens, kind, count):
    out = []
    for i in range(count):
        row, col = _data_row(rng), int(rng.integers(0, 2))  # time or gx: read by every command
        token = tokens[i % len(tokens)]
        out.append((f"{kind}-{i}", "r.csv", _text(_cells(BASE, row, col, token)),
                    f"column '{NAMES[col]}', line {row + 1}"))
    return out


def _non_numeric(rng):
    tokens = ["abc", "1.2.3", "--", "1e", "0x1F", '"1,5"', "12:00:01", "true", "1_000x", "#"]
    return _bad_cells(rng, tokens, "non-numeric", 30)


def _not_finite(rng):
    tokens = ["nan", "NaN", "inf", "-inf", "", "NULL", "N/A", "1e309", "-Infinity"]
    return _bad_cells(rng, tokens, "not-finite", 27)


def _huge(rng):
    tokens = ["1e308", "-1.7976931348623157e308", "1e31", "-5e200", "4.2e+100"]
    return [(name, filename, data, f"{expected}: ") for name, filename, data, expected in
            _bad_cells(rng, tokens, "huge", 15)]


def _times(lines):
    return [float(line.split(",")[0]) for line in lines[1:]]


def _with_times(times):
    return [HEADER] + [f"{t!r}," + line.split(",", 1)[1] for t, line in zip(times, BASE[1:])]


def _time_column(rng):
    out = []
    for i in range(6):
        t, k = _times(BASE), int(rng.integers(2, N_ROWS - 2))  # k: the sample that breaks
        t[k] = t[k - 1]
        out.append((f"time-repeats-{i}", "r.csv", _text(_with_times(t)),
                    f"'time', line {k + 2}: time repeats"))
        t = _times(BASE)
        t[k], t[k + 1] = t[k + 1], t[k]
        out.append((f"time-backwards-{i}", "r.csv", _text(_with_times(t)),
                    f"'time', line {k + 3}: time goes backwards"))
        t = _times(BASE)
        jump = float(rng.uniform(0.05, 5.0))
        t[k:] = [v + jump for v in t[k:]]
        out.append((f"time-gap-{i}", "r.csv", _text(_with_times(t)),
                    f"'time', line {k + 2}: a gap of"))
    out += [("time-one-row", "r.csv", _text(BASE[:2]), "a single sample cannot give a rate"),
            ("time-only", "r.csv", _text([line.split(",")[0] for line in BASE]),
             "only a time column"),
            ("time-at-0.4-hz", "r.csv", _text(_with_times([v * 250 for v in _times(BASE)])),
             "gives a sample rate of 0.4 Hz, outside the 1 Hz to 100 kHz an IMU samples at"),
            ("time-at-a-picosecond", "r.csv", _text(_with_times([v * 1e-10 for v in
                                                                 _times(BASE)])),
             "gives a sample rate of 1e+12 Hz, outside 1e-06 to 1e+09 Hz")]
    return out


def _duplicate_names(rng):
    headers = ["time,gx,gx", "time,gx,time", "gx,gx,temp", "time,temp,temp", "time, gx,gx"]
    return [(f"duplicate-names-{i}", "r.csv", _text([h, *BASE[1:]]), "appears 2 times")
            for i, h in enumerate(headers)]


def _compressed(rng):
    out = []
    for suffix, compress in ((".gz", gzip.compress), (".bz2", bz2.compress),
                             (".xz", lzma.compress)):
        packed = compress(_text(BASE))
        for i in range(4):
            cut = int(rng.integers(1, len(packed) - 1))
            out.append((f"truncated{suffix}-{i}", f"r.csv{suffix}", packed[:cut], None))
        out.append((f"not{suffix}", f"r.csv{suffix}", _text(BASE), None))
    return out


def _npy_bytes(array, allow_pickle=False):
    buffer = io.BytesIO()
    np.save(buffer, array, allow_pickle=allow_pickle)
    return buffer.getvalue()


def _npz_bytes():
    buffer = io.BytesIO()
    np.savez(buffer, gx=np.arange(5.0))
    return buffer.getvalue()


def _gx(values, dtype):
    """A structured array with the one field ``gx`` the commands read."""
    return np.array([(v,) for v in values], dtype=[("gx", dtype)])


def _npy(rng):
    valid = _npy_bytes(np.arange(200.0).reshape(100, 2))
    field = np.zeros(4, dtype=[("time", float), ("gx", float, (3,))])
    arrays = {
        "object": (_npy_bytes(np.array([1, "a", None], dtype=object), allow_pickle=True),
                   "not a readable .npy"),
        "3d": (_npy_bytes(np.zeros((4, 3, 2))), "must be 1-D or 2-D"),
        "0d": (_npy_bytes(np.array(5.0)), "must be 1-D or 2-D"),
        "structured-2d": (_npy_bytes(np.zeros((2, 2), dtype=[("time", float), ("gx", float)])),
                          "must be 1-D with one number per field"),
        "structured-0d": (_npy_bytes(np.zeros((), dtype=[("time", float), ("gx", float)])),
                          "must be 1-D with one number per field"),
        "subarray-field": (_npy_bytes(field), "must be 1-D with one number per field"),
        "complex": (_npy_bytes(_gx([1 + 2j, 3j, 4.0], complex)), "holds complex numbers"),
        "dates": (_npy_bytes(_gx(["2020-01-01", "2020-01-02"], "datetime64[D]")),
                  "holds dates"),
        "strings": (_npy_bytes(_gx(["a", "b"], "U1")), "'a' is not a number"),
        "npz": (_npz_bytes(), "an .npz archive"),
        "empty-rows": (_npy_bytes(_gx([], float)), "header only"),
        "no-columns": (_npy_bytes(np.zeros((5, 0))), "no columns"),
        "nan": (_npy_bytes(_gx([1.0, np.nan], float)), "column 'gx', row 1"),
    }
    out = [(f"npy-{name}", "r.npy", data, expected) for name, (data, expected) in arrays.items()]
    for i in range(5):
        out.append((f"npy-truncated-{i}", "r.npy", valid[:int(rng.integers(1, len(valid) - 1))],
                    "not a readable .npy"))
    return out


def _parquet(rng):
    if importlib.util.find_spec("pyarrow") is None:  # the garbage cases still run
        return []
    buffer = io.BytesIO()
    pd.DataFrame({"time": np.arange(50) / 100, "gx": np.ones(50)}).to_parquet(buffer)
    valid = buffer.getvalue()
    out = [(f"parquet-truncated-{i}", "r.parquet", valid[:int(rng.integers(1, len(valid) - 1))],
            "not a readable Parquet") for i in range(5)]
    buffer = io.BytesIO()
    pd.DataFrame({"time": pd.date_range("2024-01-01", periods=50, freq="10ms"),
                  "gx": np.ones(50)}).to_parquet(buffer)
    return out + [("parquet-csv-text", "r.parquet", _text(BASE), "not a readable Parquet"),
                  ("parquet-dates", "r.parquet", buffer.getvalue(), "'time' holds dates")]


def _model_text():
    """The model ``fosmodel fit --max-lag 2`` writes for the base record."""
    frame = pd.read_csv(io.BytesIO(_text(BASE)))
    model = FOSModel(max_lag=2).fit(pd.Series(frame["gx"].to_numpy(), name="gx"))
    return json.dumps(model.to_dict({"column": "gx", "rate_hz": 100.0}), indent=2).encode()


MODEL = _model_text()


def _model_json(rng, model):
    """Model files damaged in every part, and files of another kind or a newer format."""
    out = []
    for i in range(6):
        out.append((f"model-truncated-{i}", "m.json", model[:int(rng.integers(1, len(model)))],
                    "not a model file"))
    data = json.loads(model)
    edits = {
        "newer": ("format_version", 99, "is newer than this fosmodel"),
        "other-kind": ("format", "fosmodel.StudyResult", "not a fosmodel FOSModel file"),
        "params-list": ("params", [1], "corrupted model file"),
        "fitted-missing": ("fitted", None, "corrupted model file"),
        "meta-list": ("meta", [1], "corrupted model file"),
        "meta-column-number": ("meta", {"column": 5}, "corrupted model file"),
    }
    for name, (key, value, expected) in edits.items():
        out.append((f"model-{name}", "m.json", json.dumps({**data, key: value}).encode(), expected))
    fitted = {
        "terms-numbers": ("terms", [1, 2]), "offsets-list": ("offsets", [0.0]),
        "coef-nan": ("coef", [float("nan")] * len(data["fitted"]["coef"])),
        "intercept-inf": ("intercept", float("inf")), "n-samples-huge": ("n_samples", 1e400),
        "coef-count": ("coef", [1.0] * (len(data["fitted"]["coef"]) + 1)),
    }
    for name, (key, value) in fitted.items():
        broken = {**data, "fitted": {**data["fitted"], key: value}}
        out.append((f"model-{name}", "m.json", json.dumps(broken).encode(), "corrupted model file"))
    return out + [
        ("model-list", "m.json", b"[1, 2]", "not a fosmodel FOSModel file"),
        ("model-deep", "m.json", b"[" * 100_000 + b"]" * 100_000, "not a model file"),
        ("model-long-number", "m.json", b'{"format": ' + b"9" * 5000 + b"}", "not a model file"),
        ("model-latin1", "m.json", model.replace(b'"meta"', b'"m\xe9ta"'), "not UTF-8"),
    ]


def _expanding(rng):
    """Small compressed files of one repeated line that expand far beyond the limit."""
    out = []
    for i, (suffix, compress) in enumerate(((".csv.gz", gzip.compress),
                                            (".csv.bz2", bz2.compress))):
        line = f"{rng.integers(1, 9)}\n".encode()
        data = compress(b"gx\n" + line * 35_000_000)
        out.append((f"expanding-{i}", f"r{suffix}", data, "times its size"))
    return out


def _complex_npy(rng):
    rows = np.zeros(50, dtype=[("time", "f8"), ("gx", "c16"), ("temp", "f8")])
    rows["time"], rows["temp"] = np.arange(50) / 100, 20.0
    rows["gx"] = rng.standard_normal(50) + 1j * rng.standard_normal(50)
    buf = io.BytesIO()
    np.save(buf, rows)
    return [("complex-npy", "r.npy", buf.getvalue(), "complex numbers")]


KINDS = [_empty_and_blank, _header_only, _garbage, _non_utf8, _delimiters, _ragged, _non_numeric,
         _not_finite, _huge, _time_column, _duplicate_names, _compressed, _npy, _parquet,
         _expanding, _complex_npy]


# --- running the commands ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    """A valid record, a model fit on it, and an output directory with earlier results."""
    root = tmp_path_factory.mktemp("fuzz")
    (root / "good.csv").write_bytes(_text(BASE))
    (root / "model.json").write_bytes(MODEL)
    out = root / "out"
    out.mkdir()
    for name in ("model.json", "pred.csv", "study.json", "loop.json", "allan.json"):
        (out / name).write_text(f"earlier {name}\n")
    (out / "allan").mkdir()
    (out / "allan" / "report.md").write_text("earlier report\n")
    return root


def _commands(record, model, out):
    """The argument lists of every command reading ``record`` (and ``model``)."""
    r, m = str(record), str(model)
    return {
        "fit": ["fit", r, "--column", "gx", "--max-lag", "2", "--out", f"{out}/model.json"],
        "fit-new": ["fit", r, "--column", "gx", "--out", f"{out}/new-model.json"],
        "predict": ["predict", r, "--model", m, "--out", f"{out}/pred.csv"],
        "study": ["study", r, "--column", "gx", "--sensor", "gyro", "--units", "deg/s",
                  "--out", f"{out}/study", "--json", f"{out}/study.json"],
        "close-loop": ["close-loop", r, "--column", "gx", "--out", f"{out}/loop",
                       "--json", f"{out}/new-loop.json"],
        "allan": ["allan", r, "--column", "gx", "--out", f"{out}/allan",
                  "--json", f"{out}/allan.json"],
    }


def _snapshot(directory):
    return {str(p.relative_to(directory)): p.read_bytes() if p.is_file() else None
            for p in sorted(directory.rglob("*"))}


def _run_fails_cleanly(argv, work, capsys):
    """Run the CLI; assert exit 2, one error line, no warning, output untouched; return it."""
    before = _snapshot(work / "out")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            code = cli.main(argv)
        except SystemExit as exc:  # argparse: a usage error
            code = exc.code
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if not line.startswith("fosmodel: note: ")]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("fosmodel: error: "), err
    assert not caught, [str(w.message) for w in caught]
    assert _snapshot(work / "out") == before
    return lines[0]


def _cases():
    rng = np.random.default_rng(2024)
    return [case for kind in KINDS for case in kind(rng)]


CASES = _cases()


def test_the_base_record_and_model_are_valid(work, capsys):
    assert load_record(work / "good.csv").n_samples == N_ROWS
    assert cli.main(["fit", str(work / "good.csv"), "--column", "gx", "--max-lag", "2",
                     "--out", str(work / "refit.json")]) == 0
    assert json.loads((work / "refit.json").read_text())["fitted"] == json.loads(MODEL)["fitted"]
    assert cli.main(["predict", str(work / "good.csv"), "--model", str(work / "model.json"),
                     "--out", str(work / "pred.csv")]) == 0


def test_there_are_a_few_hundred_cases():
    assert len(CASES) + len(MODEL_CASES) + len(OPTION_CASES) >= 200
    assert len({case[0] for case in CASES}) == len(CASES)


def _write_case(case: tuple, work: Path) -> tuple[Path, str | None]:
    """Write a damaged file ``(id, filename, bytes, expected text)``; its path and the text."""
    name, filename, data, expected = case
    path = work / "in" / name / filename
    path.parent.mkdir(parents=True)
    path.write_bytes(data)
    return path, expected


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_every_command_refuses_a_malformed_record(case, work, capsys):
    path, expected = _write_case(case, work)
    for command, argv in _commands(path, work / "model.json", work / "out").items():
        line = _run_fails_cleanly(argv, work, capsys)
        assert str(path) in line, (command, line)
        assert expected is None or expected in line, (command, line)
    as_model = ["predict", str(work / "good.csv"), "--model", str(path), "--out",
                str(work / "out" / "pred.csv")]
    assert str(path) in _run_fails_cleanly(as_model, work, capsys)




MODEL_CASES = _model_json(np.random.default_rng(11), MODEL)


@pytest.mark.parametrize("case", MODEL_CASES, ids=[case[0] for case in MODEL_CASES])
def test_predict_refuses_a_damaged_model_file(case, work, capsys):
    path, expected = _write_case(case, work)
    line = _run_fails_cleanly(["predict", str(work / "good.csv"), "--model", str(path),
                               "--out", str(work / "out" / "pred.csv")], work, capsys)
    assert str(path) in line and expected in line, line
    for argv in _commands(path, work / "model.json", work / "out").values():
        assert str(path) in _run_fails_cleanly(argv, work, capsys)


# --- bad options on a valid record: (id, commands, extra arguments, expected text) -------------

ALL = ("fit", "fit-new", "predict", "study", "close-loop", "allan")
READERS = ("fit", "study", "close-loop", "allan")  # the commands with a required --column
OPTION_CASES = [
    ("column-misspelt", ALL, ["--column", "g_x"], "no column 'g_x' (did you mean 'gx'?)"),
    ("column-time", READERS, ["--column", "time"], "no column 'time'"),
    ("column-empty", READERS, ["--column", ""], "no column"),
    ("exog-missing", ("fit",), ["--exog", "tmp:2"], "no column 'tmp' (did you mean 'temp'?)"),
    ("exog-itself", ("fit",), ["--exog", "gx:1"], "cannot be its own input"),
    ("aux-missing", ("close-loop",), ["--aux", "tmp"], "no channel 'tmp'"),
    ("aux-itself", ("close-loop",), ["--aux", "temp,gx"], "cannot explain its own residual"),
    ("scale-not-a-number", ALL, ["--scale", "gx=x"], "--scale 'gx=x': expected NAME=FACTOR"),
    ("scale-zero", ALL, ["--scale", "gx=0"], "--scale 'gx=0'"),
    ("scale-no-factor", ALL, ["--scale", "gx"], "--scale 'gx'"),
    ("scale-no-name", ALL, ["--scale", "=2"], "--scale '=2'"),
    ("scale-divide-by-zero", ALL, ["--scale", "gx=1/0"], "--scale 'gx=1/0'"),
    ("scale-infinite", ALL, ["--scale", "gx=inf"], "--scale 'gx=inf'"),
    ("scale-unknown-column", ALL, ["--scale", "gz=2"], "--scale names no column 'gz'"),
    ("scale-twice", ALL, ["--scale", "gx=2", "--scale", "gx=3"], "'gx' is given twice"),
    ("scale-overflow", ALL, ["--scale", "gx=1e300"], "(scaled by 1e+300) is too large"),
    ("scale-time-backwards", ALL, ["--scale", "time=-1"], "time goes backwards"),
    ("scale-time-absurd-rate", ALL, ["--scale", "time=1e-12"], "gives a sample rate of 1e+14"),
    ("rate-not-a-number", ALL, ["--rate", "x"], "argument --rate: expected a number"),
    ("rate-negative", ALL, ["--rate", "-1"], "argument --rate"),
    ("rate-zero", ALL, ["--rate", "0"], "expected a positive number, got '0'"),
    ("rate-nan", ALL, ["--rate", "nan"], "expected a positive number, got 'nan'"),
    ("rate-infinite", ALL, ["--rate", "inf"], "expected a positive number, got 'inf'"),
    ("rate-absurd", ALL, ["--rate", "1e308"], "the sample rate must be a positive number of Hz"),
    ("rate-subnormal", ALL, ["--rate", "5e-324"], "the sample rate must be a positive number"),
    ("rate-disagrees", ALL, ["--rate", "50"], "--rate 50 Hz disagrees with the time column"),
    ("fill-and-segments", ALL, ["--fill", "--segments"], "not allowed with argument"),
    ("outliers-unknown", ALL, ["--outliers", "remove"], "argument --outliers: invalid choice"),
    ("out-is-a-directory", ("fit", "predict"), ["--out", "{root}/out"], "it is a directory"),
    ("out-directory-missing", ("fit", "predict"), ["--out", "{root}/none/m.json"],
     "directory {root}/none does not exist"),
    ("report-out-is-a-file", ("study", "close-loop", "allan"), ["--out", "{root}/good.csv"],
     "it is a file, not a directory"),
    ("json-directory-missing", ("study", "close-loop", "allan"),
     ["--json", "{root}/none/r.json"], "directory {root}/none does not exist"),
    ("study-split-not-finite", ("study",), ["--split", "nan,180"], "argument --split"),
    ("study-split-infinite", ("study",), ["--split", "infs,180s"], "argument --split"),
    ("split-without-units", ("study", "close-loop"), ["--split", "180,180"],
     "argument --split: expected TRAIN,EVALUATE with units: durations like 180s,180s (s, min or "
     "h) or percents of the record like 50%,20%, got '180,180'"),
    ("split-percents-over-100", ("study", "close-loop"), ["--split", "60%,40%"],
     "argument --split: the split '60%,40%' takes 100% of the record for training and "
     "evaluation and leaves nothing to predict"),
    ("segments-where-contiguous", ("study", "close-loop", "allan"), ["--segments"],
     "argument --segments: the"),
    ("units-unknown", ("study", "close-loop", "allan"), ["--units", "dps"],
     "argument --units: unknown units 'dps'"),
    ("units-of-a-stray-column", ("study", "close-loop", "allan"), ["--units", "gz=deg/s"],
     "units are given for column 'gz', which is not among the columns: gx"),
    ("model-missing", ("predict",), ["--model", "{root}/none.json"], "cannot read model"),
    ("model-is-a-directory", ("predict",), ["--model", "{root}/out"], "cannot read model"),
]


@pytest.mark.parametrize("case", OPTION_CASES, ids=[case[0] for case in OPTION_CASES])
def test_every_command_refuses_a_bad_option(case, work, capsys):
    _, commands, extra, expected = case
    extra = [arg.format(root=work) for arg in extra]
    for command, argv in _commands(work / "good.csv", work / "model.json", work / "out").items():
        if command in commands:
            line = _run_fails_cleanly(argv + extra, work, capsys)
            assert expected.format(root=work) in line, (command, line)


# --- silently wrong numbers found while fuzzing -----------------------------------------------


def test_predict_on_segments_reports_the_mse_of_the_predicted_samples(tmp_path, capsys):
    """The MSE printed by predict skipped only the first lag window: with --segments the NaN
    predictions at the start of every later segment made it "MSE nan"."""
    t = np.r_[np.arange(0, 5, 0.01), np.arange(6, 11, 0.01)]
    y = lfilter([1.0], [1.0, -0.8], np.random.default_rng(3).standard_normal(len(t)))
    record = tmp_path / "gappy.csv"
    pd.DataFrame({"time": t, "gx": y}).to_csv(record, index=False)
    model, pred = tmp_path / "m.json", tmp_path / "p.csv"
    assert cli.main(["fit", str(record), "--column", "gx", "--max-lag", "3", "--segments",
                     "--out", str(model)]) == 0
    assert cli.main(["predict", str(record), "--model", str(model), "--segments",
                     "--out", str(pred)]) == 0
    resid = pd.read_csv(pred)["residual"].dropna()
    assert len(resid) == len(t) - 2 * 3
    assert f"{len(resid)} samples, MSE {np.mean(resid**2):.6g}" in capsys.readouterr().out


# --- records a result would mean nothing on, files that are not files, paths that alias ------


def _valid(lines_of_gx, rate=100):
    return _text(["time,gx,temp"] + [f"{k / rate:.2f},{g!r},{20 + k / 1000:.3f}"
                                     for k, g in enumerate(lines_of_gx)])


SILENT = {  # (file bytes, commands allowed to succeed on it: predict fits nothing)
    "constant": (_valid([1.0] * 4000), ("predict",)),
    "tiny": (_valid([0.1, -0.2, 0.3, 0.05]), ("predict",)),
    "noise-free": (_valid(list(lfilter([1.0], [1.0, -1.2, 0.5], np.r_[1.0, np.zeros(3999)]))),
                   ("fit", "fit-new", "predict", "study", "close-loop", "allan")),
}


@pytest.mark.parametrize("name", sorted(SILENT))
def test_every_command_on_a_record_where_a_result_would_mean_nothing(name, work, capsys):
    """Each command refuses in one line, or succeeds; never a traceback or another exit code,
    never an output where it failed."""
    data, may_succeed = SILENT[name]
    path, _ = _write_case((f"silent-{name}", "r.csv", data, None), work)
    for command, argv in _commands(path, work / "model.json", work / "out").items():
        before = _snapshot(work / "out")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = cli.main(argv)
        err = capsys.readouterr().err
        assert code in (0, 2) and "internal error" not in err, (command, err)
        if code == 2:
            assert _snapshot(work / "out") == before, command
            assert len([e for e in err.splitlines() if e.startswith("fosmodel: error: ")]) == 1
        else:
            assert command in may_succeed, (command, err)


def test_every_command_refuses_what_is_not_a_regular_file(work, capsys, tmp_path):
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    device = tmp_path / "zero.csv"
    device.symlink_to("/dev/zero")
    for path, text in ((fifo, "a FIFO, not a regular file"), (device, "a device"),
                       (work / "out", "a directory, not a record")):
        for command, argv in _commands(path, work / "model.json", work / "out").items():
            line = _run_fails_cleanly(argv, work, capsys)
            assert text in line, (command, line)


def test_no_command_writes_over_its_input_however_named(work, capsys, tmp_path):
    record = work / "out" / "pred.csv"  # an earlier output given back as the record
    record.write_bytes(_text(BASE))
    (tmp_path / "alias.csv").symlink_to(record)
    try:
        for alias in (record, tmp_path / "alias.csv", work / "out" / "allan" / ".." / "pred.csv"):
            argv = ["predict", str(alias), "--model", str(work / "model.json"), "--out",
                    str(record)]
            assert "never writes over a file it reads" in _run_fails_cleanly(argv, work, capsys)
    finally:
        record.write_text("earlier pred.csv\n")
