import gzip
import importlib.util

import numpy as np
import pandas as pd
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.io import loader, timebase, values
from fosmodel.io.loader import load_record, parse_scales


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
    with pytest.raises(InputError, match="no time column; give the sample rate with rate=HZ"):
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
    message = r"rate=200 Hz disagrees with the time column \(100 Hz\)"
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


# --- preamble lines before the header ---------------------------------------------------------


def test_preamble_gives_rate_and_metadata(tmp_path):
    p = _csv(tmp_path, "Fs,100\nLogging Type,1\n\nWaiting time,-1\nax,gx\n1,2\n3,4\n")
    rec = load_record(p)
    assert rec.rate == 100.0 and rec.names == ["ax", "gx"] and rec.n_samples == 2
    assert rec.metadata == {"Logging Type": "1", "Waiting time": "-1"}
    assert any("preamble on lines 1-4" in n and "100 Hz from line 1 (Fs,100)" in n
               and "Logging Type=1, Waiting time=-1" in n for n in rec.notes)
    assert load_record(p, rate=100.5).rate == 100.5  # within 1 %: the given rate is kept


def test_preamble_keeps_true_line_numbers(tmp_path):
    p = tmp_path / "r.csv.gz"
    with gzip.open(p, "wt") as fh:
        fh.write("Fs,100\nDevice,MPU-6050\nax,gx\n1,2\n3,x\n")
    with pytest.raises(InputError, match="column 'gx', line 5: 'x' is not a number"):
        load_record(p)


@pytest.mark.parametrize("key", ["fs", "RATE", "sample_rate", "Sampling rate (Hz)", "ODR"])
def test_preamble_rate_keys(tmp_path, key):
    assert load_record(_csv(tmp_path, f"{key},200\na\n1\n2\n")).rate == 200.0


@pytest.mark.parametrize(
    "text, rate, message",
    [
        ("Fs,100\na\n1\n", 200, r"rate=200 Hz disagrees with the preamble's Fs,100 \(line 1\)"),
        ("Fs,abc\na\n1\n", None, "line 1: the preamble sample rate Fs,abc is not a positive"),
        ("Fs,-5\na\n1\n", None, "line 1: the preamble sample rate Fs,-5 is not a positive"),
        ("Fs,50\ntime,a\n0,1\n0.01,2\n0.02,3\n", None,
         r"the preamble's Fs,50 \(line 1\) disagrees with the time column \(100 Hz\)"),
    ],
)
def test_preamble_rate_errors(tmp_path, text, rate, message):
    p = _csv(tmp_path, text)
    with pytest.raises(InputError, match=message) as err:
        load_record(p, rate=rate)
    assert str(p) in str(err.value)


def test_units_row_is_not_a_preamble(tmp_path):
    with pytest.raises(InputError, match="column 'gx', line 2: 'deg/s' is not a number"):
        load_record(_csv(tmp_path, "gx,ax,temp\ndeg/s,g,C\n1,2,3\n"))


# --- scales and raw integer counts -----------------------------------------------------------


def test_parse_scales():
    assert parse_scales(["gx=1/131", " ax = 0.5 ", "t=-2e-3"]) == {"gx": 1 / 131, "ax": 0.5,
                                                                  "t": -2e-3}
    with pytest.raises(InputError, match="column 'gx' is given twice"):
        parse_scales(["gx=1", "gx=2"])


@pytest.mark.parametrize("text", ["gx", "gx=", "=2", "gx=abc", "gx=1/0", "gx=0", "gx=inf",
                                  "gx=1/2/3"])
def test_parse_scales_rejects(text):
    with pytest.raises(InputError, match="expected NAME=FACTOR or NAME=A/B"):
        parse_scales([text])


def test_scale_turns_counts_into_units(tmp_path):
    p = _csv(tmp_path, "ax,gx,n\n16384,131,1\n-8192,262,2\n")
    rec = load_record(p, scale={"ax": 1 / 16384, "gx": 1 / 131})
    np.testing.assert_allclose(rec.column("ax"), [1.0, -0.5])
    np.testing.assert_allclose(rec.column("gx"), [1.0, 2.0])
    assert rec.column("ax").dtype == float
    assert any(n.startswith("scaled ax by 6.10352e-05, gx by 0.00763359") for n in rec.notes)
    hint = [n for n in rec.notes if "hold only integers" in n]
    assert len(hint) == 1 and hint[0].startswith("column(s) n hold only integers")
    unscaled = load_record(p)
    assert any(n.startswith("column(s) ax, gx, n hold only integers") for n in unscaled.notes)


def test_scale_of_an_unknown_column(tmp_path):
    p = _csv(tmp_path, "gx,gy\n1,2\n")
    with pytest.raises(InputError, match=r"scale= names no column 'g_x' \(did you mean 'gx'\?\); "
                                         "columns: gx, gy"):
        load_record(p, scale={"g_x": 0.5})


def test_no_integer_hint_for_float_columns(tmp_path):
    rec = load_record(_csv(tmp_path, "a\n0.5\n1.25\n"))
    assert rec.notes == []


# --- host receive time that arrives in bursts -------------------------------------------------


def test_bursty_time_is_refused_without_uniform(bursty_csv):
    p, effective = bursty_csv()
    message = (rf"{p}: column 't_s' \(lines 2-401\) looks like a host's bursty receive time "
               rf"\(median interval 0.001 s, mean 0.00991 s\); effective rate {effective:.6g} Hz")
    with pytest.raises(InputError, match=message) as err:
        load_record(p)
    assert "pass uniform=True" in str(err.value) and "or rate=HZ" in str(err.value)


def test_bursty_time_with_uniform_or_rate(bursty_csv):
    p, effective = bursty_csv()
    rec = load_record(p, uniform=True)
    assert rec.rate == pytest.approx(effective) and rec.n_samples == 400
    np.testing.assert_allclose(rec.time, np.arange(400) / effective)
    assert any("bursty receive time" in n and f"uniformly spaced at {effective:.6g} Hz" in n
               for n in rec.notes)
    assert load_record(p, rate=100).rate == 100.0
    with pytest.raises(InputError, match="rate=200 Hz disagrees with the effective rate of the "
                                         "bursty time column"):
        load_record(p, rate=200)


def test_regular_time_checks_still_hold(tmp_path):
    rng = np.random.default_rng(4)
    t = np.arange(1000) / 100 + rng.uniform(-1e-3, 1e-3, 1000)  # jittered but regular
    pd.DataFrame({"time": t, "a": rng.normal(size=1000)}).to_csv(tmp_path / "j.csv", index=False)
    rec = load_record(tmp_path / "j.csv")
    assert rec.rate == pytest.approx(100, rel=1e-3) and rec.notes == []
    np.testing.assert_array_equal(rec.time, t)
    t[600:] += 20.0  # one long gap: most intervals are far below the mean, but it is no burst
    pd.DataFrame({"time": t, "a": rng.normal(size=1000)}).to_csv(tmp_path / "g.csv", index=False)
    with pytest.raises(InputError, match=r"column 'time', line 602: a gap of 20.0\d* s"):
        load_record(tmp_path / "g.csv")
    rec = load_record(tmp_path / "g.csv", uniform=True)
    assert any("(1 gap(s) in it ignored)" in n for n in rec.notes)
    np.testing.assert_allclose(rec.time, np.arange(1000) / rec.rate)


def test_uniform_without_time_is_noted(tmp_path):
    rec = load_record(_csv(tmp_path, "a\n0.5\n1.5\n"), rate=10, uniform=True)
    assert rec.notes == ["uniform=True has no effect: the record has no time column"]


# --- outliers --------------------------------------------------------------------------------


def _bounds(x):
    center = np.median(x)
    sigma = 1.4826 * np.median(np.abs(x - center))
    return center - 10 * sigma, center + 10 * sigma


def test_outliers_are_reported_and_kept(spiky_csv):
    p, a, b = spiky_csv(with_time=False)
    rec = load_record(p, outliers="keep")
    assert set(rec.outliers) == {"a", "b"}
    np.testing.assert_array_equal(rec.outliers["a"], [100, 700])
    np.testing.assert_array_equal(rec.outliers["b"], [700])
    np.testing.assert_array_equal(rec.column("a"), a)
    note = next(n for n in rec.notes if n.startswith("column 'a'"))
    assert "2 outlier(s) (|x - median| > 10 x 1.4826 MAD" in note
    assert "at sample(s) 100, 700 (line(s) 102, 702); kept" in note


def test_outliers_that_carry_the_mean_square_refuse_the_record_by_default(spiky_csv):
    p, _, _ = spiky_csv(with_time=False)
    with pytest.raises(InputError, match=(
            f"^{p}: column 'a': 2 outlier\\(s\\) \\(\\|x - median\\| > 10 x 1.4826 MAD\\) at "
            r"sample\(s\) 100, 700 \(line\(s\) 102, 702\) carry 86 % of its mean square about "
            "its median: .* outliers='keep' \\(if they are the sensor's\\), or "
            "outliers='clip' or 'drop'$")):
        load_record(p)


@pytest.mark.parametrize("mode", ["refuse", "keep", "drop"])
def test_a_single_spike_of_a_thousand_sigma(tmp_path, mode):
    x = np.random.default_rng(8).normal(size=20_000)
    x[12_345] = 1e3
    p = _write(tmp_path, {"time": np.arange(x.size) / 100, "gx": x})
    if mode == "refuse":  # 1e6 against a mean square of 2e4: 98 % of it
        with pytest.raises(InputError, match=r"column 'gx': 1 outlier\(s\) .* carry 98 %"):
            load_record(p)
        return
    rec = load_record(p, outliers=mode)
    assert rec.outliers["gx"].tolist() == [12_345]
    kept = rec.column("gx")
    if mode == "keep":
        np.testing.assert_array_equal(kept, x)
    else:
        np.testing.assert_array_equal(kept, np.delete(x, 12_345))


def test_a_run_of_outliers_is_an_event_not_a_spike(tmp_path):
    # the sensor turned for half a second: 50 samples in a row far from rest carry most of
    # the mean square, but they are the record's motion, which the static checks name
    x = np.random.default_rng(10).normal(size=20_000)
    x[5_000:5_050] += 200.0
    x[9_000:9_004] += 300.0  # and a glitch of four samples: a run, not a spike either
    p = _write(tmp_path, {"time": np.arange(x.size) / 100, "gx": x})
    rec = load_record(p)
    assert rec.outliers["gx"].size == 54
    x[12_000] = 1e3  # a spike on top: 1e6 of the column's 3.3e6, 30 %
    with pytest.raises(InputError, match=r"column 'gx': 1 outlier\(s\) .* at sample\(s\) "
                                         r"12000 .* carry 30 %"):
        load_record(_write(tmp_path, {"time": np.arange(x.size) / 100, "gx": x}))


def test_a_few_outliers_under_the_share_are_kept_with_a_note(tmp_path):
    x = np.random.default_rng(9).normal(size=100_000)
    x[500] = 12.0  # 144 against a mean square of 1e5: 0.14 %
    rec = load_record(_write(tmp_path, {"gx": x}), rate=100)
    np.testing.assert_array_equal(rec.column("gx"), x)
    assert rec.outliers["gx"].tolist() == [500]
    assert any("kept: they carry 0.14 % of its mean square about its median, under the 1 %"
               in n for n in rec.notes)


def test_outliers_clipped_to_the_bound(spiky_csv):
    p, a, _ = spiky_csv(with_time=False)
    rec = load_record(p, outliers="clip")
    low, high = _bounds(a)
    expected = a.copy()
    expected[100], expected[700] = high, low
    np.testing.assert_allclose(rec.column("a"), expected)
    assert any("clipped to [" in n for n in rec.notes)


def test_outliers_dropped_keep_the_time_gap(spiky_csv):
    p, a, b = spiky_csv(with_time=True)
    rec = load_record(p, outliers="drop")
    keep = np.setdiff1d(np.arange(1000), [100, 700])
    assert rec.n_samples == 998 and rec.rate == pytest.approx(100)
    np.testing.assert_array_equal(rec.column("a"), a[keep])
    np.testing.assert_array_equal(rec.column("b"), b[keep])
    np.testing.assert_allclose(rec.time, keep / 100)
    np.testing.assert_array_equal(rec.outliers["a"], [100, 700])  # positions in the file
    assert any(n.startswith("dropped 2 row(s)") and "no longer uniformly spaced" in n
               for n in rec.notes)


def test_dropping_without_time_is_refused(tmp_path, spiky_csv):
    p, _, _ = spiky_csv(with_time=False)
    with pytest.raises(InputError, match=f"{p}: outliers='drop' would remove 2 sample"
                                         r"\(s\) from a record without a time column, which "
                                         "breaks the uniform sample spacing.*"
                                         r"use outliers='clip' \(or 'keep'\)$"):
        load_record(p, outliers="drop")
    clean = load_record(_csv(tmp_path, "a\n0.5\n1.5\n0.7\n"), outliers="drop")
    assert clean.notes == ["outliers='drop': no outliers found (|x - median| > 10 x 1.4826 MAD)"]
    with pytest.raises(InputError, match="outliers must be one of refuse, keep, clip, drop"):
        load_record(p, outliers="remove")


def test_outliers_of_a_column_on_few_levels(tmp_path):
    temp = np.full(200, 25.0)
    temp[::3], temp[1::7] = 25.1, 24.9  # MAD 0: the resolution 0.1 C is the scale
    rec = load_record(_write(tmp_path, {"temp": temp, "const": np.ones(200)}))
    assert rec.outliers == {}
    temp[50] = 27.0
    rec = load_record(_write(tmp_path, {"temp": temp, "const": np.ones(200)}), outliers="keep")
    assert set(rec.outliers) == {"temp"} and rec.outliers["temp"].tolist() == [50]


def test_no_outliers_in_clean_gaussian_noise(tmp_path):
    rng = np.random.default_rng(6)
    rec = load_record(_write(tmp_path, {"a": rng.normal(size=200_000)}))
    assert rec.outliers == {} and rec.notes == []


def _write(tmp_path, columns):
    path = tmp_path / "w.csv"
    pd.DataFrame(columns).to_csv(path, index=False)
    return path


# --- the loader options on the command line ---------------------------------------------------


def _gappy(tmp_path):
    t = np.r_[np.arange(0, 1, 0.01), np.arange(1.5, 3, 0.01)]
    x = np.sin(3 * t)
    path = tmp_path / "gappy.csv"
    pd.DataFrame({"time": t, "x": x}).to_csv(path, index=False)
    return path, t, x


def test_gaps_are_refused_with_both_ways_out(tmp_path):
    p, _, _ = _gappy(tmp_path)
    with pytest.raises(InputError, match="line 102: a gap of 0.51 s.*pass gaps='fill' to "
                                         "interpolate across them or gaps='segments' to fit on "
                                         "the pieces"):
        load_record(p)


def test_gaps_filled_by_interpolation(tmp_path):
    p, t, x = _gappy(tmp_path)
    rec = load_record(p, gaps="fill")
    assert rec.n_samples == 300 and rec.rate == pytest.approx(100) and rec.segments is None
    np.testing.assert_allclose(rec.time, np.arange(300) * 0.01, atol=1e-12)
    np.testing.assert_allclose(rec.column("x"), np.interp(rec.time, t, x))
    assert "1 gap(s), first at line 102; filled by linear interpolation (50 samples added" in (
        rec.notes[0])


def test_gaps_kept_as_segments(tmp_path):
    p, t, x = _gappy(tmp_path)
    rec = load_record(p, gaps="segments")
    assert rec.n_samples == 250 and rec.segments == [slice(0, 100), slice(100, 250)]
    np.testing.assert_array_equal(rec.column("x"), x)
    with pytest.raises(InputError, match="needs a contiguous record, this one has 2 segments"):
        rec.require_contiguous("the study")
    load_record(p, gaps="fill").require_contiguous("the study")  # fine


def _wide(tmp_path, n=1000):
    rng = np.random.default_rng(5)
    frame = pd.DataFrame({"time": np.arange(n) / 100.0,
                          **{f"c{i}": rng.standard_normal(n) for i in range(6)}})
    frame.to_csv(tmp_path / "w.csv", index=False)
    np.save(tmp_path / "w.npy", frame.to_numpy()[:, 1:])
    frame.to_parquet(tmp_path / "w.parquet")
    return frame


@pytest.mark.parametrize("name", ["w.csv", "w.npy", "w.parquet"])
def test_columns_read_in_blocks_equal_the_whole_read(tmp_path, monkeypatch, name):
    frame = _wide(tmp_path)
    whole = load_record(tmp_path / name, rate=None if name != "w.npy" else 100.0)
    monkeypatch.setattr(loader, "CHUNK_ROWS", 64)  # 16 blocks, the last one short
    part = load_record(tmp_path / name, columns=["c4", "c1"],
                       rate=None if name != "w.npy" else 100.0)
    assert part.names == ["c1", "c4"]  # file order, only those asked for
    for c in part.names:
        np.testing.assert_array_equal(part.column(c), whole.column(c))
        np.testing.assert_array_equal(part.column(c), frame[c].to_numpy())
    assert part.rate == pytest.approx(100.0)


def test_a_bad_cell_in_a_later_block_names_its_line(tmp_path, monkeypatch):
    _wide(tmp_path)
    lines = (tmp_path / "w.csv").read_text().splitlines()
    cells = lines[700].split(",")
    cells[3] = "oops"  # column c2, file line 701
    lines[700] = ",".join(cells)
    cells = lines[900].split(",")
    cells[4] = ""  # column c3, file line 901
    lines[900] = ",".join(cells)
    (tmp_path / "w.csv").write_text("\n".join(lines) + "\n")
    monkeypatch.setattr(loader, "CHUNK_ROWS", 64)
    with pytest.raises(InputError, match=r"column 'c2', line 701: 'oops' is not a number"):
        load_record(tmp_path / "w.csv", columns=["c2"])
    with pytest.raises(InputError, match=r"column 'c3', line 901: an empty cell or NaN \(1 such"):
        load_record(tmp_path / "w.csv", columns=["c3"])
    # the damaged columns are not read when not asked for
    assert load_record(tmp_path / "w.csv", columns=["c0"]).names == ["c0"]


@pytest.mark.parametrize("name", ["w.csv", "w.npy", "w.parquet"])
def test_a_column_the_file_lacks_is_named_with_the_file_columns(tmp_path, name):
    _wide(tmp_path)
    with pytest.raises(InputError, match=r"no column 'c9'.*columns: c0, c1, c2, c3, c4, c5$"):
        load_record(tmp_path / name, columns=["c9"], rate=100.0 if name == "w.npy" else None)


def test_npy_is_memory_mapped(tmp_path, monkeypatch):
    _wide(tmp_path)
    modes = []
    real_load = np.load
    monkeypatch.setattr(np, "load", lambda *a, **k: modes.append(k.get("mmap_mode"))
                        or real_load(*a, **k))
    load_record(tmp_path / "w.npy", columns=["c0"], rate=100.0)
    assert modes and set(modes) == {"r"}


@pytest.mark.parametrize("text", ["time,gx\n0,1,2\n0.01,2\n", "time,gx\n0,1\n0.01,2,3\n0.02,3\n"])
def test_a_row_with_extra_fields_is_refused_when_reading_some_columns(tmp_path, text):
    path = tmp_path / "rec.csv"
    path.write_text(text)
    with pytest.raises(InputError, match="more fields|Expected 2 fields"):
        loader.load_record(path, columns=["gx"], rate=100)


def test_a_short_row_is_refused_when_reading_some_columns(tmp_path):
    path = tmp_path / "rec.csv"
    path.write_text("time,gx,temp\n0,1,20\n0.01,21\n0.02,3,20\n")  # gx or temp missing on line 3
    with pytest.raises(InputError, match=r"column 'temp', line 3: an empty cell or a row shorter"):
        loader.load_record(path, columns=["gx"])


@pytest.mark.parametrize("name", ["w.npy", "w.parquet"])
def test_a_record_over_the_memory_budget_is_refused_at_its_first_block(tmp_path, monkeypatch,
                                                                        name):
    _wide(tmp_path)
    monkeypatch.setattr(loader, "CHUNK_ROWS", 100)
    monkeypatch.setenv("FOSMODEL_MAX_MEMORY", "20000")
    converted = []
    real = values._numeric
    monkeypatch.setattr(values, "_numeric", lambda *a: converted.append(a[2]) or real(*a))
    width = 6 if name == "w.npy" else 7
    with pytest.raises(InputError, match=rf"^{tmp_path / name}: too large to read: 1,000 rows of "
                       rf"{width} column\(s\) take 0.0 GiB as float64, more than the 0.0 GiB "
                       r"this machine has free; read fewer columns \(columns=\) or a shorter "
                       r"stretch$"):
        load_record(tmp_path / name, rate=100.0 if name == "w.npy" else None)
    assert len(converted) == width  # the first block's columns, no more


def test_a_csv_over_the_memory_budget_is_refused_as_it_grows(tmp_path, monkeypatch):
    _wide(tmp_path)
    monkeypatch.setattr(loader, "CHUNK_ROWS", 100)
    monkeypatch.setenv("FOSMODEL_MAX_MEMORY", str(300 * 8 * 7))
    with pytest.raises(InputError, match=r"too large to read: 400 rows of 7 column\(s\) already "
                       "take"):
        load_record(tmp_path / "w.csv")


def test_parquet_with_a_null_or_text_column_goes_through_pandas(tmp_path):
    frame = pd.DataFrame({"time": [0.0, 0.01, 0.02], "gx": [1.0, None, 3.0]})
    frame.to_parquet(tmp_path / "null.parquet")
    with pytest.raises(InputError, match=r"column 'gx', row 1: an empty cell or NaN"):
        load_record(tmp_path / "null.parquet")
    frame = pd.DataFrame({"time": [0.0, 0.01, 0.02], "gx": ["1", "2.5", "x"]})
    frame.to_parquet(tmp_path / "text.parquet")
    with pytest.raises(InputError, match=r"column 'gx', row 2: 'x' is not a number"):
        load_record(tmp_path / "text.parquet")


@pytest.mark.parametrize("name", ["t.npy", "t.parquet"])
def test_time_going_backwards_across_blocks_is_named(tmp_path, monkeypatch, name):
    time = np.arange(300) / 100.0
    time[128] = time[126]  # the first row of the third 64-row block goes back
    frame = pd.DataFrame({"time": time, "gx": np.ones(300)})
    frame.to_parquet(tmp_path / "t.parquet")
    np.save(tmp_path / "t.npy", frame.to_records(index=False))
    monkeypatch.setattr(loader, "CHUNK_ROWS", 64)
    with pytest.raises(InputError, match=r"column 'time', row 128: time goes backwards "
                       r"\(1.27 then 1.26\)"):
        load_record(tmp_path / name)


def test_structured_npy_equals_its_fields(tmp_path, monkeypatch):
    frame = _wide(tmp_path)
    np.save(tmp_path / "s.npy", frame.to_records(index=False))
    monkeypatch.setattr(loader, "CHUNK_ROWS", 64)
    record = load_record(tmp_path / "s.npy")
    np.testing.assert_array_equal(record.time, frame["time"].to_numpy())
    for c in record.names:
        np.testing.assert_array_equal(record.column(c), frame[c].to_numpy())


@pytest.mark.parametrize("seed", range(5))
def test_tenths_equal_numpy_histogram(seed):
    rng = np.random.default_rng(seed)
    time = np.sort(np.concatenate([rng.uniform(0, 7, 500), np.linspace(0, 7, 11)]))  # edges too
    np.testing.assert_array_equal(timebase._tenths(time), np.histogram(time, bins=10)[0])


@pytest.mark.parametrize("gaps, offered", [("refuse", " or gaps='segments' to fit on the pieces"),
                                           ("contiguous", "")])
def test_a_gap_is_refused_offering_what_the_caller_can_take(tmp_path, gaps, offered):
    path = tmp_path / "gap.csv"
    path.write_text("time,gx\n0,1\n0.01,2\n0.02,3\n0.5,4\n0.51,5\n")
    message = (f"{path}: column 'time', line 5: a gap of 0.48 s where the sample interval is "
               "0.01 s (1 gap(s) in the record); pass gaps='fill' to interpolate across them"
               f"{offered}")
    with pytest.raises(InputError) as err:
        load_record(path, gaps=gaps)
    assert str(err.value) == message


def test_header_names_are_read_without_the_spaces_around_them(tmp_path):
    """``time, gx ,temp`` was refused: "no column 'gx' (did you mean 'gx '?)"."""
    p = _csv(tmp_path, "time, gx ,temp\n0, 1.5 ,20\n0.01,2.5,20.1\n0.02,3.5,20.2\n")
    rec = load_record(p, columns=["gx"])
    assert rec.names == ["gx"] and rec.column("gx").tolist() == [1.5, 2.5, 3.5]
    assert load_record(p).names == ["gx", "temp"]
    with pytest.raises(InputError, match=r"column name 'gx' appears 2 times in the header "
                                         r"\(columns 2, 3\)"):
        load_record(_csv(tmp_path, "time,gx, gx \n0,1,2\n0.01,2,3\n", "twice.csv"))


def test_booleans_are_no_signal(tmp_path):
    """A column of True/False was modelled as a signal of ones and zeros."""
    t = np.arange(50) / 100
    flags = np.arange(50) % 3 == 0
    pd.DataFrame({"time": t, "gx": np.sin(t), "ok": flags}).to_csv(tmp_path / "r.csv",
                                                                    index=False)
    (tmp_path / "gaps.csv").write_text("time,gx,ok\n0,1,True\n0.01,2,\n0.02,3,false\n")
    s = np.zeros(50, dtype=[("time", float), ("gx", float), ("ok", bool)])
    s["time"], s["gx"], s["ok"] = t, np.sin(t), flags
    np.save(tmp_path / "r.npy", s)
    np.save(tmp_path / "plain.npy", flags)
    files = {"r.csv": "(True/False)", "gaps.csv": "(True/False)", "r.npy": "(True/False)",
             "plain.npy": "(True/False)"}
    if importlib.util.find_spec("pyarrow") is not None:
        pd.DataFrame({"time": t, "gx": np.sin(t), "ok": flags}).to_parquet(tmp_path / "r.parquet")
        files["r.parquet"] = "(True/False)"
    for name in files:
        column = "c0" if name == "plain.npy" else "ok"
        with pytest.raises(InputError, match=rf"{name}: column '{column}' holds booleans "
                                             r"\(True/False\), not a sensor's readings"):
            load_record(tmp_path / name, columns=[column], rate=100)
    assert load_record(tmp_path / "r.csv", columns=["gx"]).names == ["gx"]  # left unread


@pytest.mark.parametrize("name, per_second, origin", [
    ("time", 1000, 0), ("time", 1000, 1_704_067_200_000), ("timestamp", 10**6, 5_000_000),
    ("time", 10**9, 1_704_067_200 * 10**9), ("time_ms", 1000, 0), ("t_us", 10**6, 0),
    ("timestamp_ns", 10**9, 0),
])
def test_integer_timestamps_are_read_in_their_unit(tmp_path, name, per_second, origin):
    """Integer milliseconds (a common logger format) were read as seconds: 0.1 Hz, fitted."""
    stamps = origin + (per_second // 100) * np.arange(300, dtype=np.int64)  # 100 Hz
    gx = np.sin(np.arange(300) / 7)
    pd.DataFrame({name: stamps, "gx": gx}).to_csv(tmp_path / "r.csv", index=False)
    rec = load_record(tmp_path / "r.csv")
    assert rec.rate == pytest.approx(100.0, rel=1e-5)
    np.testing.assert_allclose(rec.time - rec.time[0], np.arange(300) / 100, atol=1e-6)
    unit = {1000: "milliseconds", 10**6: "microseconds", 10**9: "nanoseconds"}[per_second]
    assert any(note.startswith(f"column {name!r} read in {unit} (") for note in rec.notes)
    scaled = load_record(tmp_path / "r.csv", scale={name: 1 / per_second})  # the user's word
    assert scaled.rate == pytest.approx(100.0, rel=1e-5)
    assert not any("read in" in note for note in scaled.notes)


def test_a_rate_no_imu_has_is_refused_unless_given(tmp_path):
    p = _csv(tmp_path, "time,gx\n" + "".join(f"{2.5 * k},{k % 3}\n" for k in range(20)))
    with pytest.raises(InputError, match=r"column 'time' gives a sample rate of 0.4 Hz, outside "
                                         r"the 1 Hz to 100 kHz an IMU samples at; if that is the "
                                         r"record's rate, confirm it with rate=0.4"):
        load_record(p)
    assert load_record(p, rate=0.4).rate == 0.4
    q = _csv(tmp_path, "Fs,200000\ngx\n1\n2\n3\n", "fast.csv")
    with pytest.raises(InputError, match=r"the preamble's Fs,200000 \(line 1\) gives a sample "
                                         r"rate of 200000 Hz, outside"):
        load_record(q)
    assert load_record(q, rate=2e5).rate == 2e5
    assert load_record(_csv(tmp_path, "gx\n1\n2\n", "none.csv"), rate=0.01).rate == 0.01


def test_a_second_time_column_is_left_unread(tmp_path):
    p = _csv(tmp_path, "time,timestamp_ns,gx\n0,5,1\n0.01,10000005,2\n0.02,20000005,3\n")
    rec = load_record(p)
    assert rec.names == ["gx"] and rec.rate == pytest.approx(100)
    assert "column 'timestamp_ns' is another time column: the time is 'time'" in rec.notes[0]


def test_a_warm_up_is_a_slow_excursion_not_outliers(tmp_path):
    # a die temperature warming 15 C over the first half hour, on 0.01 C steps otherwise still:
    # its long runs beyond the bounds are noted as a slow excursion, not counted as outliers
    t = np.arange(360_000) / 100.0
    temp = np.round(40.0 - 15.0 * np.exp(-t / 600.0)
                    + np.random.default_rng(4).normal(0, 0.02, t.size), 2)
    rec = load_record(_write(tmp_path, {"time": t, "temp_c": temp}))
    assert rec.outliers["temp_c"].size == 0  # the warm-up is the signal: none refused or counted
    notes = [n for n in rec.notes if n.startswith("column 'temp_c'")]
    assert len(notes) == 1
    slow = int(notes[0].split()[2])
    assert slow > 1000
    assert notes[0] == (
        f"column 'temp_c': {slow} sample(s) outside [{_bounds(temp)[0]:.6g}, "
        f"{_bounds(temp)[1]:.6g}] where the median of the 101 samples about them is far out too, a "
        "slow excursion (a warm-up, a drift): not counted as outliers, kept")


def test_units_are_read_from_the_column_names(tmp_path):
    path = tmp_path / "named.csv"
    path.write_text("time,gx_rads,gy_dps,ax_mps2,ay_g,temp_c,gz,vbat\n"
                    + "".join(f"{i / 100},0.{i % 7},1.{i % 5},9.{i % 3},1.{i % 4},25.{i % 9},"
                              f"0.{i % 6},12.{i % 2}\n" for i in range(200)))
    rec = load_record(path)
    assert rec.units == {"gx_rads": "rad/s", "gy_dps": "deg/s", "ax_mps2": "m/s^2",
                         "ay_g": "g", "temp_c": "degC"}
    scaled = load_record(path, scale={"gy_dps": 0.5})  # scaled: its units are no longer known
    assert "gy_dps" not in scaled.units and scaled.units["gx_rads"] == "rad/s"


def test_clip_bounds_the_spikes_and_leaves_a_slow_excursion_as_it_is(tmp_path):
    # the warm-up above with two one-sample glitches in its still part: outliers="clip" brings
    # the glitches to the bounds and leaves every sample of the warm-up as read
    t = np.arange(360_000) / 100.0
    temp = np.round(40.0 - 15.0 * np.exp(-t / 600.0)
                    + np.random.default_rng(4).normal(0, 0.02, t.size), 2)
    temp[[200_000, 300_000]] = [90.0, -10.0]
    rec = load_record(_write(tmp_path, {"time": t, "temp_c": temp}), outliers="clip")
    out = rec.outliers["temp_c"]
    assert sorted(out.tolist()) == [200_000, 300_000]
    clipped = rec.column("temp_c")
    low, high = _bounds(temp)
    assert clipped[200_000] == pytest.approx(high) and clipped[300_000] == pytest.approx(low)
    others = np.ones(t.size, dtype=bool)
    others[[200_000, 300_000]] = False
    np.testing.assert_array_equal(clipped[others], temp[others])  # the warm-up too
    assert clipped[0] < low  # the warm-up's start lies beyond the bounds, kept
