"""``fosmodel imu``: the six-axis workflow from the command line."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from fosmodel.cli import main
from fosmodel.noise.axes import resolve_axes
from fosmodel.workflows.imu import ImuConfig, run_imu

FAST = ["--orders", "1-2", "--methods", "fos,burg", "--jobs", "1"]


@pytest.fixture(scope="module")
def imu_csv(tmp_path_factory):
    """Six axes of the static_imu scenario (300 s at 100 Hz) and a die temperature."""
    from data_synth import make_scenario

    rec = make_scenario("static_imu", duration=300.0, seed=5)
    frame = pd.DataFrame({"time": np.arange(30_000) / 100.0, **rec.columns})
    frame["temp_c"] = 30 + 0.001 * np.arange(30_000) / 100.0
    path = tmp_path_factory.mktemp("imu") / "imu.csv"
    frame.to_csv(path, index=False)
    return path, rec


def _run(args, capsys):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.slow
def test_two_axes_end_to_end_equal_the_library(imu_csv, tmp_path, capsys, figure_log):
    path, rec = imu_csv
    figures = figure_log()
    out, js = tmp_path / "report", tmp_path / "imu.json"
    code, stdout, err = _run(["imu", path, "--columns", "gx_dps,ax_mps2", "--split", "60s,60s",
                              *FAST, "--inflate", "2", "--out", out, "--json", js], capsys)
    assert code == 0, err
    *table, written = stdout.splitlines()  # the last line names the output directory
    assert all(len(line) <= 100 for line in table)
    assert written == f"six-axis report of 2 axes written to {out.resolve()}/ and {js}"
    assert "fosmodel: gx_dps: gyro in deg/s (from the name)" in err
    assert "4/4 tasks done" in err
    page = (out / "report.md").read_text()
    assert "auxiliary channels of the loop: temp_c" in page
    axes = resolve_axes(["gx_dps", "ax_mps2"])
    alone = run_imu({a.column: rec.columns[a.column] for a in axes}, axes, 100.0,
                    aux={"temp_c": pd.read_csv(path)["temp_c"].to_numpy()},
                    config=ImuConfig(orders=(1, 2), methods=("fos", "burg"), train_s=60.0,
                                     evaluate_s=60.0, n_jobs=1))
    data = json.loads(js.read_text())
    assert data["aux"] == ["temp_c"]
    assert data["noise"]["exports"]["inflate"] == 2.0
    assert "inflated 2x" in (out / "noise" / "px4_ekf2.params").read_text()
    pd.testing.assert_frame_equal(pd.DataFrame(data["study"]), alone.study_table(),
                                  check_dtype=False)
    pd.testing.assert_frame_equal(pd.DataFrame(data["loop"]), alone.loop_table(),
                                  check_dtype=False)
    for column in ("gx_dps", "ax_mps2"):
        assert (out / "models" / f"{column}.json").is_file()
        assert (out / "study" / column / "report.md").is_file()
    # every figure of the report reads (tests/test_figures.py), the loop's left out
    checked = figures()
    assert len(checked) == len(list(out.rglob("*.png")))
    assert {p: problems for p, problems in checked.items()
            if problems and "/loop/" not in f"/{p}"} == {}


@pytest.mark.slow
def test_a_ros2_bag_is_read_with_its_units(imu_bag, tmp_path, capsys):
    bag, _ = imu_bag("day", "mcap", imu={"/imu0": 12_000}, rate=50.0)  # 240 s
    out = tmp_path / "bag-report"
    code, stdout, err = _run(["imu", bag, "--columns", "gx,ay", "--split", "60s,60s", *FAST,
                              "--out", out], capsys)
    assert code == 0, err
    for column, sensor, units in (("gx", "gyro", "rad/s"), ("ay", "accel", "m/s^2")):
        assert f"fosmodel: {column}: {sensor} in {units} (units from the file)" in err
    table = pd.read_csv(out / "noise.csv")
    assert list(table["Column"]) == ["gx", "ay"]


def test_refusals_take_one_line_and_write_nothing(imu_csv, tmp_path, capsys):
    path, _ = imu_csv
    out = tmp_path / "never"
    code, _, err = _run(["imu", path, *FAST, "--split", "180s,180s", "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert err.strip().splitlines()[-1] == (
        "fosmodel: error: the record has 30000 samples (300 s at 100 Hz), too short for these "
        "settings, which need at least 420 s: the study needs 420 s (the split 180 s / 180 s "
        "leaves 0 samples to predict, 6000 are needed (a 30 s outage horizon and two 30 s bias "
        "windows)); the loop needs 420 s (on the study's segments, which the record does not "
        "hold); shorten --split (the loop's: --loop-split) or --horizon, or give a longer "
        "record")
    other = tmp_path / "other.csv"
    pd.DataFrame({"time": np.arange(100) / 10, "foo": np.ones(100), "bar": np.zeros(100)}
                 ).to_csv(other, index=False)
    code, _, err = _run(["imu", other, "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert err.strip().splitlines()[-1] == (
        f"fosmodel: error: {other}: no column tells a gyro or an accelerometer by its name "
        "(columns: foo, bar); name the axes and give their units")
    with pytest.raises(SystemExit) as stop:
        main(["imu", str(path), "--segments", "--out", str(out)])
    assert stop.value.code == 2 and not out.exists()
    assert "the six-axis workflow needs a contiguous record" in capsys.readouterr().err


def test_the_help_lists_the_options_with_their_defaults(capsys):
    with pytest.raises(SystemExit):
        main(["imu", "--help"])
    text = " ".join(capsys.readouterr().out.split())  # as one line, however argparse wraps
    for option, default in (("--orders", "1-10"), ("--protocol", "fair"),
                            ("--split", "50%,20%"), ("--jobs", "2")):
        assert option in text and f"(default: {default})" in text, option
    assert "--loop-split" in text and "(default: the study's, so that both score on one " \
        "prediction segment)" in text


@pytest.mark.slow
def test_a_readable_header_goes_through_every_step(readable_csv, tmp_path, capsys):
    """``Gyro X (deg/s),...,Accel X (g)``: units from the names, a loop that names the other
    axes as companions and takes none as an input (Accel X follows Accel Y, which a model
    must not use: in use it measures the motion), reports in folders named after the
    columns, models that apply again."""
    from fosmodel.io.model_file import read_model
    from fosmodel.io.output import path_name

    out = tmp_path / "report"
    axes = ["Accel X (g)", "Accel Y (g)", "Gyro Z (deg/s)"]  # a slash, brackets, spaces
    code, _, err = _run(["imu", readable_csv, "--columns", ",".join(axes), "--rate", "100",
                         "--split", "60s,60s", "--orders", "1", "--degrees", "1", "--methods",
                         "fos,burg", "--jobs", "2", "--out", out], capsys)
    assert code == 0, err
    frame = pd.read_csv(readable_csv)
    assert "fosmodel: Accel X (g): accel in g (from the name)" in err
    assert "fosmodel: Gyro Z (deg/s): gyro in deg/s (from the name)" in err
    assert list(pd.read_csv(out / "study.csv")["axis"]) == axes
    loop = (out / "loop" / "Accel_X_g_" / "report.md").read_text()
    assert "companions: Accel Y (g), Gyro Z (deg/s)" in loop
    assert read_model(out / "models" / "Accel_X_g_.json").input_columns() == []
    for column in axes:
        assert (out / "study" / path_name(column) / "report.md").is_file()
        model = read_model(out / "models" / f"{path_name(column)}.json")
        channels = {name: frame[name].to_numpy() for name in model.input_columns()}
        pred = model.predict(frame[column].to_numpy(), channels)
        assert np.isfinite(pred[model.lag_window_:]).all()


@pytest.fixture(scope="module")
def long_csv(tmp_path_factory):
    """A gyro axis of 2.4 h at 2 Hz: long enough that 3 min is a small part of it."""
    from data_synth import make_scenario

    rec = make_scenario("static_imu", duration=8640.0, rate=2.0, seed=7)
    path = tmp_path_factory.mktemp("long") / "long.csv"
    pd.DataFrame({"time": np.arange(17_280) / 2.0, "gx_dps": rec.columns["gx_dps"]}
                 ).to_csv(path, index=False)
    return path


def test_the_default_split_is_in_proportion_to_the_record(long_csv, tmp_path, capsys):
    """A 2.4 h record is fitted on its first 1.2 h, not on 3 min of warm-up."""
    code, out, _ = _run(["imu", long_csv, "--orders", "1", "--degrees", "1", "--methods",
                         "fos,burg", "--jobs", "1", "--json", tmp_path / "o.json",
                         "--out", tmp_path / "o"], capsys)
    assert code == 0
    split = ("Split (the study's and the loop's): fitting 0-4320 s (50 %), evaluation "
             "4320-6048 s (20 %), prediction 6048-8640 s (30 %).")
    assert split in (tmp_path / "o" / "report.md").read_text()
    assert " ".join(out.split()).startswith(split)  # wrapped for the console
    loop = json.loads((tmp_path / "o.json").read_text())["loops"]["gx_dps"]
    assert loop["segments_s"] == {"train": [0.0, 4320.0], "evaluate": [4320.0, 6048.0],
                                  "predict": [6048.0, 8640.0]}


def test_a_short_record_takes_the_proportional_split_too(imu_csv, tmp_path, capsys):
    """300 s: 150 s fitted, 60 s to choose on, 90 s predicted (the 30 s outages fit)."""
    path, _ = imu_csv
    code, out, _ = _run(["imu", path, "--columns", "gx_dps", "--orders", "1", "--degrees", "1",
                         "--methods", "fos,burg", "--jobs", "1", "--out", tmp_path / "o"],
                        capsys)
    assert code == 0
    assert " ".join(out.split()).startswith(
        "Split (the study's and the loop's): fitting 0-150 s (50 %), evaluation 150-210 s "
        "(20 %), prediction 210-300 s (30 %).")


def test_the_loop_takes_a_split_of_its_own_when_asked(imu_csv):
    from fosmodel.cli.parser import build_parser

    args = build_parser().parse_args(["imu", "x.csv", "--out", "o", "--loop-split", "60s,30s"])
    config = ImuConfig().on_record(30_000, 100.0, args.split, args.loop_split)
    assert (config.train_s, config.evaluate_s) == (150.0, 60.0)
    assert config.loop_split == (0.2, 0.1)


def test_allan_s_shortest_tau_is_a_duration_as_imu_s():
    from fosmodel.cli.parser import build_parser

    for command in (["allan", "--column", "gx"], ["imu"]):
        base = [*command, "x.csv", "--out", "o", "--min-tau"]
        assert build_parser().parse_args([*base, "0.5s"]).min_tau == 0.5
        assert build_parser().parse_args([*base, "2"]).min_tau == 2.0
