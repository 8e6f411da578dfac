"""``fosmodel synth``: the generator's command line (data_synth.cli, mounted by fosmodel.cli)."""

import json

import pandas as pd

from data_synth.scenarios import SCENARIOS
from fosmodel.cli import main


def test_list(capsys):
    assert main(["synth", "--list"]) == 0
    out = capsys.readouterr().out
    for name in SCENARIOS:
        assert name in out
    assert "102.4 Hz" in out


def test_writes_csv_and_truth_deterministically(tmp_path, capsys):
    args = ["synth", "undeclared_vibration", "--duration", "12", "--rate", "50", "--seed", "9"]
    assert main([*args, "--out", str(tmp_path / "a.csv")]) == 0
    assert main([*args, "--out", str(tmp_path / "b.csv")]) == 0
    assert "a.truth.json" in capsys.readouterr().out
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert (tmp_path / "a.truth.json").read_bytes() == (tmp_path / "b.truth.json").read_bytes()
    frame = pd.read_csv(tmp_path / "a.csv")
    assert list(frame.columns) == ["time", "gyro_x"] and len(frame) == 600
    truth = json.loads((tmp_path / "a.truth.json").read_text())
    assert (truth["seed"], truth["rate_hz"], truth["duration_s"]) == (9, 50.0, 12.0)


def test_set_overrides_and_no_time(tmp_path):
    out = tmp_path / "g.csv"
    code = main(["synth", "paper_gyro_y", "--duration", "2", "--set", "units=deg/h",
                 "--set", "gm_order=3", "--no-time", "--out", str(out)])
    assert code == 0
    truth = json.loads(out.with_suffix(".truth.json").read_text())
    assert truth["units"] == "deg/h"
    assert [s for s in truth["sources"] if s["name"] == "gm"][0]["params"]["order"] == 3
    assert out.read_text().splitlines()[0] == "gyro_y"


def test_synthetic_record_fits_end_to_end(tmp_path, capsys):
    rec = tmp_path / "clean.csv"
    assert main(["synth", "clean", "--duration", "60", "--out", str(rec)]) == 0
    assert main(["fit", str(rec), "--column", "gyro_x", "--max-lag", "4",
                 "--out", str(tmp_path / "m.json")]) == 0
    assert "y[n-1]" in capsys.readouterr().out


def test_input_errors_exit_2_with_one_line(tmp_path, capsys):
    for args in (["nope", "--out", str(tmp_path / "x.csv")], ["clean"],
                 ["clean", "--set", "oops", "--out", str(tmp_path / "x.csv")],
                 ["clean", "--out", str(tmp_path / "missing" / "x.csv")]):
        assert main(["synth", *args]) == 2
        err = capsys.readouterr().err
        assert err.startswith("fosmodel: error: ") and err.count("\n") == 1
    assert not list(tmp_path.iterdir())
