import gzip

import numpy as np
import pandas as pd
import pytest

from fosmodel.exceptions import InputError
from fosmodel.loader import load_record


def _csv(tmp_path, text, name="rec.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_csv_with_time_gives_rate(tmp_path):
    t = np.arange(500) / 200.0
    pd.DataFrame({"time": t, "gyro_y": np.sin(t), "temp_c": 20 + t}).to_csv(
        tmp_path / "r.csv", index=False)
    rec = load_record(tmp_path / "r.csv")
    assert rec.rate == pytest.approx(200.0)
    assert rec.names == ["gyro_y", "temp_c"] and rec.n_samples == 500
    np.testing.assert_allclose(rec.time, t)
    assert load_record(tmp_path / "r.csv", rate=200.0).rate == 200.0


def test_csv_without_time_needs_rate(tmp_path):
    p = _csv(tmp_path, "a,b\n1,2\n3,4\n")
    rec = load_record(p)
    assert rec.rate is None
    with pytest.raises(InputError, match="no time column; give the sample rate with --rate"):
        rec.require_rate()
    assert load_record(p, rate=100).rate == 100.0


def test_gzip_csv(tmp_path):
    p = tmp_path / "r.csv.gz"
    with gzip.open(p, "wt") as fh:
        fh.write("x\n1\n2\n3\n")
    np.testing.assert_array_equal(load_record(p).column("x"), [1, 2, 3])


def test_npy_plain_and_structured(tmp_path):
    np.save(tmp_path / "a.npy", np.arange(6.0).reshape(3, 2))
    assert load_record(tmp_path / "a.npy").names == ["c0", "c1"]
    np.save(tmp_path / "b.npy", np.arange(4.0))
    assert load_record(tmp_path / "b.npy").names == ["c0"]
    s = np.zeros(4, dtype=[("time", float), ("gx", float)])
    s["time"] = np.arange(4) / 10
    np.save(tmp_path / "c.npy", s)
    rec = load_record(tmp_path / "c.npy")
    assert rec.names == ["gx"] and rec.rate == pytest.approx(10.0)


def test_parquet(tmp_path):
    pytest.importorskip("pyarrow")
    pd.DataFrame({"gx": [1.0, 2.0, 3.0]}).to_parquet(tmp_path / "r.parquet")
    assert load_record(tmp_path / "r.parquet", rate=5).column("gx").tolist() == [1, 2, 3]


@pytest.mark.parametrize(
    "text, message",
    [
        ("", "the file is empty"),
        ("a,b\n", "header only, no data rows"),
        ("a,b\n1,2\n3,x\n", "column 'b', line 3: 'x' is not a number"),
        ("a,b\n1,2\n3,\n", "column 'b', line 3: an empty cell or NaN"),
        ("a,b\n1,2\n3,inf\n", "column 'b', line 3: an infinite value"),
        ("a;b\n1;2\n", "separated by semicolons"),
        ("a\tb\n1\t2\n", "separated by tabs"),
        ("time,a\n0,1\n0.01,2\n0.01,3\n", "line 4: time repeats"),
        ("time,a\n0,1\n0.02,2\n0.01,3\n", "line 4: time goes backwards"),
        ("time,a\n0,1\n0.01,2\n0.02,3\n0.5,4\n0.51,5\n", "line 5: a gap of 0.48 s"),
        ("time\n0\n0.1\n", "only a time column"),
        ("a,,c\n1,2,3\n", "column 2 has no name"),
    ],
)
def test_bad_csv_is_named_precisely(tmp_path, text, message):
    p = _csv(tmp_path, text)
    with pytest.raises(InputError, match=message.replace("(", r"\(")) as err:
        load_record(p)
    assert str(p) in str(err.value)


def test_rate_disagreeing_with_time(tmp_path):
    p = _csv(tmp_path, "time,a\n0,1\n0.01,2\n0.02,3\n")
    message = r"--rate 200 Hz disagrees with the time column \(100 Hz\)"
    with pytest.raises(InputError, match=message):
        load_record(p, rate=200)


def test_missing_file_and_bad_rate(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_record(tmp_path / "nope.csv")
    with pytest.raises(InputError, match="positive number"):
        load_record(_csv(tmp_path, "a\n1\n"), rate=-1)


def test_missing_column_suggests_closest(tmp_path):
    rec = load_record(_csv(tmp_path, "gyro_y,temp_c\n1,2\n"))
    with pytest.raises(InputError, match="no column 'gyro_Y' \\(did you mean 'gyro_y'\\?\\)"):
        rec.column("gyro_Y")


def test_damaged_binary_files(tmp_path):
    (tmp_path / "x.npy").write_bytes(b"not numpy at all")
    with pytest.raises(InputError, match="not a readable .npy"):
        load_record(tmp_path / "x.npy")
    pytest.importorskip("pyarrow")
    (tmp_path / "x.parquet").write_bytes(b"PAR1 damaged")
    with pytest.raises(InputError, match="not a readable Parquet"):
        load_record(tmp_path / "x.parquet")
