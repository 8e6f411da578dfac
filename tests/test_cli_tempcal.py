"""``fosmodel tempcal``: a thermal calibration from the command line, its files and refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fosmodel.cli import main

SHARED = Path(__file__).parents[2] / "shared" / "data"
LOGS, MPU = SHARED / "px4_ulog", SHARED / "mpu6050_sunsided"
needs = {name: pytest.mark.skipif(not path.is_dir(), reason=f"{path} is absent (only a checkout "
                                  "beside the project's shared/ folder has it)")
         for name, path in (("logs", LOGS), ("mpu", MPU))}


def _run(args, capsys):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    """Three thermal sweeps of one IMU with a 5 min lag, as CSV files."""
    from data_synth.thermal import thermal_sessions

    folder = tmp_path_factory.mktemp("sweeps")
    paths = []
    for k, rec in enumerate(thermal_sessions(4, lag_s=300.0)):
        paths.append(folder / f"s{k + 1}.csv")
        rec.to_frame().to_csv(paths[-1], index=False)
    return paths


@pytest.mark.slow
def test_three_sessions_end_to_end(sweeps, tmp_path, capsys, figure_log):
    figures = figure_log()
    out = tmp_path / "cal"
    code, stdout, err = _run(["tempcal", *sweeps, "--gyro-id", "2424842", "--accel-id",
                              "0x250052", "--out", out], capsys)
    assert code == 0, err
    assert stdout.splitlines()[-1] == (f"thermal calibration of 6 axes written to "
                                       f"{out.resolve()}/")
    assert {p.name for p in out.iterdir()} == {
        "report.md", "tempcal.json", "px4.params", "px4_console.txt", "ardupilot.parm",
        "summary.md", "summary.csv", "summary.tex", "bias_vs_temperature.png",
        "bias_vs_temperature.svg", "residual_vs_time.png", "residual_vs_time.svg"}
    data = json.loads((out / "tempcal.json").read_text())
    assert [a["column"] for a in data["axes"]] == ["gx_dps", "gy_dps", "gz_dps", "ax_mps2",
                                                    "ay_mps2", "az_mps2"]
    for axis in data["axes"]:
        held = axis["held_out"]
        assert axis["model"]["lag_s"] == pytest.approx(300, rel=0.05)
        assert held["rms"]["model"] <= 0.5 * held["rms"]["px4"], axis["column"]
    assert data["px4_parameters"]["TC_A0_ID"] == 0x250052
    assert "TC_G0_ID\t2424842\t6" in (out / "px4.params").read_text()
    assert "grows x" in (out / "report.md").read_text()
    assert all(problems == "" for problems in figures().values()), figures()
    assert "note" not in err  # both device ids given: nothing to say


def test_a_record_without_a_temperature_column_is_refused(tmp_path, capsys):
    path = tmp_path / "still.csv"
    pd.DataFrame({"time": np.arange(600.0), "gx": 0.0, "gy": 0.0, "gz": 0.0}).to_csv(path,
                                                                                   index=False)
    out = tmp_path / "cal"
    code, stdout, err = _run(["tempcal", path, "--out", out], capsys)
    assert code == 2 and stdout == "" and not out.exists()
    assert err == (f"fosmodel: error: {path}: no temperature column (columns: gx, gy, gz); a "
                   "thermal calibration needs one: name it with --temperature COLUMN\n")


def test_a_narrow_span_and_a_degree_it_cannot_support_are_refused(tmp_path, capsys):
    path = tmp_path / "warm.csv"
    t = np.arange(3600.0)
    for span, args, message in (
            (0.5, [], "temp_c spans only 0.5 C; a thermal calibration needs at least 5 C "
                      "(--min-span ...)"),
            (12.0, ["--degree", "3"], "temp_c spans 12 C, too narrow for --degree 3 (5 C per "
                                      "power); it supports --degree 2")):
        temp = 20 + span * t / t[-1]
        pd.DataFrame({"time": t, "gx": 0.01 * temp, "temp_c": temp}).to_csv(path, index=False)
        out = tmp_path / "cal"
        code, _, err = _run(["tempcal", path, "--units", "rad/s", *args, "--out", out], capsys)
        assert code == 2 and not out.exists()
        assert err == f"fosmodel: error: {path}: {message}\n"


@needs["mpu"]
def test_the_real_mpu6050_record_spans_half_a_degree_and_is_refused(tmp_path, capsys):
    path = MPU / "unmoved-with-x-pointing-forward-10min.csv.gz"
    out = tmp_path / "cal"
    code, _, err = _run(["tempcal", path, "--uniform", "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert err.splitlines()[-1] == (f"fosmodel: error: {path}: temp_c spans only 0.471 C; a "
                                    "thermal calibration needs at least 5 C (--min-span ...)")


@needs["logs"]
def test_a_ulog_gives_its_gyro_and_accelerometer_with_their_device_ids(tmp_path, capsys):
    from fosmodel.workflows.tempcal_records import tempcal_groups

    path = LOGS / "sample_log_small.ulg"
    groups = tempcal_groups([path])
    assert [(g.name, [a.column for a in g.axes], g.temperature, g.device_id)
            for g in groups] == [("gyro", ["gx", "gy", "gz"], "temperature", 2424842),
                                 ("accel", ["ax", "ay", "az"], "temperature", 2424842)]
    assert [g.name for g in tempcal_groups([path], instance=1)] == ["gyro", "accel"]
    assert tempcal_groups([path], instance=1)[0].device_id == 3670050
    out = tmp_path / "cal"
    code, _, err = _run(["tempcal", path, "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert err.splitlines()[-1] == (f"fosmodel: error: {path}: temperature spans only 0.335 C; "
                                    "a thermal calibration needs at least 5 C (--min-span ...)")
