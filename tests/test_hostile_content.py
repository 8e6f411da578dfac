"""Content refused the same way by every command, before any fitting; other columns noted.

Zeros, a constant, denormal numbers and integers beyond float64's exact range are refused
in one line naming the column, exit code 2, nothing written, by fit, study, close-loop,
imu, allan and fleet alike.  Only the analysed column and the model's drivers are refused on
their content: another column (a boolean flag, another axis with knocks) is named in a note
and left out, and the command runs to its end.
"""

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import cli

UNITS = "gx=deg/s,gy=deg/s,gz=deg/s,ax=m/s^2,ay=m/s^2,az=m/s^2"


def _imu(n, seed=0):
    rng = np.random.default_rng(seed)
    frame = {"time": np.arange(n) / 100.0}
    for c in ("gx", "gy", "gz"):
        frame[c] = 0.05 * lfilter([1.0], [1.0, -0.5], rng.standard_normal(n))
    for c, mean in zip(("ax", "ay", "az"), (0.0, 0.0, 9.81)):
        frame[c] = mean + 0.02 * rng.standard_normal(n)
    return pd.DataFrame(frame)


def _commands(rec, out):
    return {
        "fit": ["fit", rec, "--column", "gx", "--out", f"{out}.json"],
        "allan": ["allan", rec, "--column", "gx", "--out", out],
        "study": ["study", rec, "--column", "gx", "--sensor", "gyro", "--units", "deg/s",
                  "--out", out],
        "close-loop": ["close-loop", rec, "--column", "gx", "--out", out],
        "imu": ["imu", rec, "--units", UNITS, "--out", out],
        "fleet": ["fleet", rec, "--units", UNITS, "--steps", "allan", "--out", out],
    }


CONTENT = {
    "zeros": (lambda n, rng: np.zeros(n),
              "column 'gx' holds only zeros: there is nothing to model (a sensor's readings "
              "are never exactly zero throughout)"),
    "constant": (lambda n, rng: np.full(n, 1.5),
                 "column 'gx' is constant (1.5): there is nothing to model"),
    "denormal": (lambda n, rng: 5e-311 * rng.standard_normal(n),
                 "column 'gx': its values are at most"),
    "huge integers": (lambda n, rng: np.uint64(2**64 - 1)
                      - rng.integers(0, 2**20, n).astype(np.uint64),
                      "column 'gx': integers up to 1.845e+19"),
}


@pytest.mark.parametrize("content", sorted(CONTENT))
@pytest.mark.parametrize("command", ["fit", "allan", "study", "close-loop", "imu", "fleet"])
def test_content_is_refused_alike_before_any_fitting(tmp_path, capsys, content, command):
    make, said = CONTENT[content]
    frame = _imu(3000)
    frame["gx"] = make(3000, np.random.default_rng(1))
    rec = tmp_path / "rec.csv"
    frame.to_csv(rec, index=False)
    assert cli.main(_commands(str(rec), str(tmp_path / "out"))[command]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("fosmodel: error: "), err
    assert said in err[-1], err[-1]
    assert "internal error" not in err[-1] and "too short" not in err[-1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv"]


def test_the_denormal_message_in_full(tmp_path, capsys):
    frame = _imu(3000)
    frame["gx"] = 5e-311 * np.sign(np.random.default_rng(2).standard_normal(3000))
    rec = tmp_path / "rec.csv"
    frame.to_csv(rec, index=False)
    assert cli.main(["fit", str(rec), "--column", "gx", "--out", str(tmp_path / "m.json")]) == 2
    assert capsys.readouterr().err.strip() == (
        f"fosmodel: error: {rec}: column 'gx': its values are at most 5e-311 in magnitude, too "
        "small to compute with (their squares fall below float64's smallest normal number); "
        "check its units or pass --scale gx=FACTOR")


def test_content_of_a_column_not_analysed_refuses_nothing(tmp_path, capsys):
    frame = _imu(3000)
    frame["gy"] = 0.0  # another axis, not analysed
    rec = tmp_path / "rec.csv"
    frame.to_csv(rec, index=False)
    assert cli.main(["fit", str(rec), "--column", "gx", "--max-lag", "2",
                     "--out", str(tmp_path / "m.json")]) == 0


@pytest.fixture
def flagged(tmp_path):
    pytest.importorskip("pyarrow")
    frame = _imu(60_000)
    frame["flag"] = np.random.default_rng(3).random(len(frame)) > 0.5
    path = tmp_path / "rec.parquet"
    frame.to_parquet(path)
    return path


FLAG_NOTE = ("column 'flag' holds booleans (True/False), not a sensor's readings; read the "
             "signal's columns only")


def test_a_boolean_flag_column_is_noted_by_close_loop(flagged, capsys):
    out = flagged.parent / "report"
    assert cli.main(["close-loop", str(flagged), "--column", "gx", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert ("fosmodel: note: column 'flag' left out of the loop's cross-axis table and fast "
            f"inputs (it is not analysed): {FLAG_NOTE}") in err
    assert (out / "report.md").is_file() or any(out.iterdir())


def test_a_boolean_flag_column_is_left_out_by_fleet(flagged, capsys):
    out = flagged.parent / "store"
    assert cli.main(["fleet", str(flagged), "--columns", "gx:gyro:deg/s", "--steps", "allan",
                     "--out", str(out)]) == 0


@pytest.mark.slow
def test_a_boolean_flag_column_is_noted_by_imu(flagged, capsys):
    out = flagged.parent / "report"
    assert cli.main(["imu", str(flagged), "--units", UNITS, "--out", str(out)]) == 0
    assert ("fosmodel: note: column 'flag' left out of the analysis (it is not analysed): "
            f"{FLAG_NOTE}") in capsys.readouterr().err


def _knocked(tmp_path, column, rows, size, name="rec.csv"):
    frame = _imu(60_000)
    frame.loc[rows, column] += size
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return path, frame


@pytest.mark.parametrize("column, rows, size", [
    ("az", slice(None, None, 1500), 50.0),  # knocks on an accelerometer of a gyro's record
    ("gz", slice(20_000, 20_002), 30.0),  # a short knock on a companion gyro
])
def test_knocks_on_a_column_not_analysed_are_a_note_and_the_loop_runs(tmp_path, capsys,
                                                                       column, rows, size):
    path, _ = _knocked(tmp_path, column, rows, size)
    out = tmp_path / "report"
    assert cli.main(["close-loop", str(path), "--column", "gx", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    notes = [line for line in err.splitlines() if "left out" in line]
    assert len(notes) == 1, err
    assert notes[0].startswith(f"fosmodel: note: column {column!r} left out of the loop's "
                               f"cross-axis table and fast inputs (it is not analysed): "
                               f"column {column!r}: ")
    assert out.is_dir()


def test_knocks_on_the_analysed_column_still_refuse(tmp_path, capsys):
    path, _ = _knocked(tmp_path, "gx", slice(None, None, 1500), 50.0)
    assert cli.main(["close-loop", str(path), "--column", "gx", "--out",
                     str(tmp_path / "report")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"fosmodel: error: {path}: column 'gx': 40 "
                                               "outlier(s)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv"]


def test_spikes_on_a_driver_get_the_targets_policy_and_say_so(tmp_path, capsys):
    frame = _imu(60_000)
    frame["temp_c"] = 25 + np.arange(len(frame)) / 1e4
    frame.loc[::1500, "temp_c"] += 40.0
    path = tmp_path / "rec.csv"
    frame.to_csv(path, index=False)
    assert cli.main(["close-loop", str(path), "--column", "gx", "--out",
                     str(tmp_path / "report")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"fosmodel: error: {path}: column 'temp_c': 40 outlier(s)")
    assert err[0].endswith("('temp_c' is a driver the model may use: the modelled column's "
                           "policy applies to it)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv"]
