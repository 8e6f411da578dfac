"""--start/--stop: the stretch of a record analysed, cut before any analysis."""

import json

import numpy as np
import pytest

from fosmodel import cli
from fosmodel.cli.arguments import offset
from fosmodel.core.exceptions import InputError
from fosmodel.io.loader import load_record


@pytest.fixture
def record(tmp_path):
    path = tmp_path / "r.csv"
    gx = np.random.default_rng(0).normal(0, 0.02, 60_000)  # 600 s at 100 Hz
    path.write_text("Fs,100\ngx_dps\n" + "".join(f"{v:.5f}\n" for v in gx))
    return path


def test_offsets_read_units_and_zero():
    assert (offset("0"), offset("90"), offset("10min"), offset("1.5h")) == (0.0, 90.0, 600.0,
                                                                             5400.0)


def test_between_cuts_every_column_and_says_so(record):
    rec = load_record(record)
    part = rec.between(60.0, 300.0)
    assert part.n_samples == 24_000
    np.testing.assert_array_equal(part.column("gx_dps"), rec.column("gx_dps")[6000:30000])
    assert part.notes[-1] == ("start=60 s and stop=300 s: kept that stretch of the record's "
                              "600 s (24000 of 60000 samples)")
    assert rec.between(start=540.0).n_samples == 6000
    with pytest.raises(InputError, match=r"r.csv: stop=601 s is beyond the record, which "
                                         r"lasts 600 s$"):
        rec.between(stop=601.0)
    with pytest.raises(InputError, match=r"start=300 s is not before stop=300 s$"):
        rec.between(300.0, 300.0)


def test_allan_analyses_the_stretch_and_says_it(record, tmp_path, capsys):
    out, js = tmp_path / "o", tmp_path / "o.json"
    assert cli.main(["allan", str(record), "--column", "gx_dps", "--start", "1min",
                     "--stop", "300", "--out", str(out), "--json", str(js)]) == 0
    err = capsys.readouterr().err
    assert ("fosmodel: note: --start 60 s and --stop 300 s: kept that stretch of the record's "
            "600 s (24000 of 60000 samples)") in err.splitlines()
    data = json.loads(js.read_text())
    assert data["allan"]["n_samples"] == 24_000
    assert data["source"].endswith("r.csv from 60 s to 300 s")
    assert r"gx\_dps of r.csv from 60 s to 300 s" in (out / "allan.tex").read_text()


@pytest.mark.parametrize("command", [["allan", "--column", "gx_dps"],
                                     ["imu", "--columns", "gx_dps"],
                                     ["close-loop", "--column", "gx_dps"]])
@pytest.mark.parametrize(("window", "told"), [
    (["--stop", "20min"], "r.csv: --stop 1200 s is beyond the record, which lasts 600 s"),
    (["--start", "5min", "--stop", "2min"], "r.csv: --start 300 s is not before --stop 120 s"),
    (["--start", "700"], "r.csv: --start 700 s is beyond the record, which lasts 600 s"),
])
def test_a_stretch_outside_the_record_is_refused_with_nothing_written(
        record, tmp_path, capsys, command, window, told):
    out, js = tmp_path / "out", tmp_path / "out.json"
    argv = [command[0], str(record), *command[1:], *window, "--out", str(out), "--json", str(js)]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == f"fosmodel: error: {record.parent}/{told}"
    assert not out.exists() and not js.exists()
