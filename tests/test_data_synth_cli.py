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


def test_a_scenario_of_sessions_writes_one_file_pair_per_session(tmp_path, capsys):
    assert main(["synth", "--list"]) == 0
    assert "3 x 86400 s at 1 Hz" in capsys.readouterr().out
    out = tmp_path / "day.csv"
    args = ["synth", "temperature_sessions", "--duration", "120", "--seed", "2",
            "--set", "lag_s=60", "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out.splitlines()
    assert len(printed) == 3 and "day_s3.truth.json" in printed[2]
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        f"day_s{k}{ext}" for k in (1, 2, 3) for ext in (".csv", ".truth.json")]
    truths = [json.loads((tmp_path / f"day_s{k}.truth.json").read_text()) for k in (1, 2, 3)]
    assert [t["session"]["label"] for t in truths] == ["s1", "s2", "s3"]
    assert truths[0]["shared"]["temperature_bias"]["gx_dps"]["lag_s"] == 60
    frame = pd.read_csv(tmp_path / "day_s2.csv")
    assert list(frame.columns) == ["time", "gx_dps", "gy_dps", "gz_dps", "ax_mps2", "ay_mps2",
                                   "az_mps2", "temp_c"] and len(frame) == 120
    assert frame["ax_mps2"].mean() > 9.0  # the second session has x up


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
                 ["clean", "--out", str(tmp_path / "missing" / "x.csv")],
                 ["temperature_sessions", "--duration", "10",
                  "--out", str(tmp_path / "missing" / "x.csv")],
                 ["temperature_sessions", "--set", 'orientations=["+z/+x"]',
                  "--out", str(tmp_path / "x.csv")]):
        assert main(["synth", *args]) == 2
        err = capsys.readouterr().err
        assert err.startswith("fosmodel: error: ") and err.count("\n") == 1
    assert not list(tmp_path.iterdir())
