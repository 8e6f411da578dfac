"""Text inputs read alike with or without a UTF-8 byte-order mark; integer times differenced
as integers."""

import json

import numpy as np
import pandas as pd
import pytest

from fosmodel import FOSModel, cli
from fosmodel.io.loader import load_record

BOM = b"\xef\xbb\xbf"


def _record(tmp_path, n=3000):
    gx = 0.1 * np.random.default_rng(0).standard_normal(n)
    path = tmp_path / "rec.csv"
    pd.DataFrame({"time": np.arange(n) / 100.0, "gx": gx}).to_csv(path, index=False)
    return path


def test_a_model_file_with_a_byte_order_mark_is_read_as_without(tmp_path, capsys):
    rec = _record(tmp_path)
    plain = tmp_path / "m.json"
    assert cli.main(["fit", str(rec), "--column", "gx", "--max-lag", "2",
                     "--out", str(plain)]) == 0
    marked = tmp_path / "bom.json"
    marked.write_bytes(BOM + plain.read_bytes())
    assert FOSModel.load(marked).to_dict() == FOSModel.load(plain).to_dict()
    for model, out in ((plain, "a.csv"), (marked, "b.csv")):
        assert cli.main(["predict", str(rec), "--model", str(model),
                         "--out", str(tmp_path / out)]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_a_record_with_a_byte_order_mark_is_read_as_without(tmp_path):
    rec = _record(tmp_path)
    marked = tmp_path / "bom.csv"
    marked.write_bytes(BOM + rec.read_bytes())
    a, b = load_record(rec), load_record(marked)
    assert a.names == b.names == ["gx"] and a.rate == b.rate
    np.testing.assert_array_equal(a.column("gx"), b.column("gx"))


def test_a_model_file_with_a_byte_order_mark_but_bad_json_still_says_so(tmp_path, capsys):
    path = tmp_path / "m.json"
    path.write_bytes(BOM + b"{not json")
    rec = _record(tmp_path)
    assert cli.main(["predict", str(rec), "--model", str(path), "--out",
                     str(tmp_path / "p.csv")]) == 2
    assert capsys.readouterr().err.strip() == (
        f"fosmodel: error: {path}: not a model file (invalid JSON at line 1)")


def _times(n=30_000):
    return 1_733_000_000_000 + 10 * np.arange(n, dtype=np.int64)  # epoch milliseconds


@pytest.mark.parametrize("kind", ["csv", "parquet", "npy"])
def test_int64_milliseconds_give_exactly_100_hz(tmp_path, kind):
    t = _times()
    gx = np.random.default_rng(1).standard_normal(len(t))
    path = tmp_path / f"rec.{kind}"
    if kind == "csv":
        pd.DataFrame({"time_ms": t, "gx": gx}).to_csv(path, index=False)
    elif kind == "parquet":
        pytest.importorskip("pyarrow")
        pd.DataFrame({"time_ms": t, "gx": gx}).to_parquet(path)
    else:
        np.save(path, np.rec.fromarrays([t, gx], names="time_ms,gx"))
    rec = load_record(path)
    assert rec.rate == 100.0
    assert rec.time[0] == 1_733_000_000.0
    # the times themselves are as near as float64 holds seconds since the epoch (2.4e-7 s)
    assert np.max(np.abs(np.diff(rec.time) - 0.01)) <= np.spacing(rec.time[-1])


def test_int64_nanoseconds_of_an_epoch_give_exactly_the_rate(tmp_path):
    # beyond 2^53: as floats their differences would be off by hundreds of nanoseconds
    t = 1_733_000_000_000_000_000 + 2_500_000 * np.arange(20_000, dtype=np.int64)
    gx = np.random.default_rng(2).standard_normal(len(t))
    path = tmp_path / "rec.csv"
    pd.DataFrame({"timestamp": t, "gx": gx}).to_csv(path, index=False)
    assert load_record(path).rate == 400.0


def test_the_rate_of_an_integer_time_reaches_the_outputs(tmp_path, capsys):
    t = _times(3000)
    gx = 0.1 * np.random.default_rng(3).standard_normal(len(t))
    path = tmp_path / "rec.csv"
    pd.DataFrame({"time_ms": t, "gx": gx}).to_csv(path, index=False)
    out = tmp_path / "m.json"
    assert cli.main(["fit", str(path), "--column", "gx", "--max-lag", "2",
                     "--out", str(out)]) == 0
    assert json.loads(out.read_text())["meta"]["rate_hz"] == 100.0
