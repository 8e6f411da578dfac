import json
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel, cli


@pytest.fixture
def record(tmp_path):
    rng = np.random.default_rng(0)
    n = 3000
    temp = 20 + np.linspace(0, 5, n)
    gyro = lfilter([1.0], [1.0, -1.2, 0.5], rng.standard_normal(n)) + 0.4 * temp
    path = tmp_path / "rec.csv"
    pd.DataFrame({"time": np.arange(n) / 100.0, "gyro_y": gyro, "temp_c": temp}).to_csv(
        path, index=False)
    return path


def _run(args, capsys):
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_fit_then_predict(record, tmp_path, capsys):
    model = tmp_path / "model.json"
    code, out, err = _run(["fit", record, "--column", "gyro_y", "--max-lag", 4, "--degree", 2,
                           "--exog", "temp_c:1", "--out", model], capsys)
    assert code == 0, err
    assert "candidates: 28 (L=4, CP=2, temp_c:0-1)" in out
    assert "Fast Orthogonal Search model" in out and f"model written to {model}" in out
    saved = json.loads(model.read_text())
    assert saved["meta"]["column"] == "gyro_y" and saved["meta"]["rate_hz"] == pytest.approx(100)
    pred = tmp_path / "pred.csv"
    code, out, err = _run(["predict", record, "--model", model, "--out", pred], capsys)
    assert code == 0, err
    frame = pd.read_csv(pred)
    assert list(frame.columns) == ["time", "gyro_y", "prediction", "residual"]
    assert frame["prediction"].isna().sum() == 4
    mse = float(np.mean(frame["residual"].dropna() ** 2))
    assert f"MSE {mse:.6g}" in out
    assert mse == pytest.approx(saved["fitted"]["mse_path"][-1], rel=1e-6)


@pytest.mark.parametrize("stop", ["aic", "bic", "fpe", "mdl", "korenberg"])
def test_fit_stop_rules(record, tmp_path, capsys, stop):
    code, out, _ = _run(["fit", record, "--column", "gyro_y", "--stop", stop,
                         "--out", tmp_path / "m.json"], capsys)
    assert code == 0 and "Stop rule:" in out


@pytest.mark.parametrize(
    "args, message",
    [
        (["fit", "{dir}/missing.csv", "--column", "gyro_y"], "no such file"),
        (["fit", "{rec}", "--column", "gyro"], "no column 'gyro' (did you mean 'gyro_y'?)"),
        (["fit", "{rec}", "--column", "gyro_y", "--exog", "temp:1"], "no column 'temp'"),
        (["fit", "{rec}", "--column", "gyro_y", "--max-lag", "-2"], "max_lag must be an integer"),
        (["fit", "{rec}", "--column", "gyro_y", "--stop", "variance"], "needs a tolerance"),
        (["fit", "{rec}", "--column", "gyro_y", "--max-lag", "5000"], "record too short"),
        (["fit", "{rec}", "--column", "gyro_y", "--rate", "50"], "disagrees with the time column"),
        (["predict", "{rec}", "--model", "{rec}"], "not a model file"),
        (["predict", "{rec}", "--model", "{dir}/none.json"], "cannot read model"),
    ],
)
def test_bad_input_exit_2_one_line_and_no_output(record, tmp_path, capsys, args, message):
    out_file = tmp_path / "out.json"
    args = [a.format(rec=record, dir=tmp_path) for a in args] + ["--out", out_file]
    code, out, err = _run(args, capsys)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("fosmodel: error: ") and message in err
    assert not out_file.exists()


def test_output_directory_must_exist(record, tmp_path, capsys):
    code, _, err = _run(["fit", record, "--column", "gyro_y", "--out",
                         tmp_path / "no" / "m.json"], capsys)
    assert code == 2 and "does not exist" in err


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["fit", "x.csv", "--column", "a", "--exog", "temp", "--out", "m.json"])
    assert exc.value.code == 2
    assert "expected NAME:K" in capsys.readouterr().err


def test_internal_error_exit_1_with_hint(record, tmp_path, capsys, monkeypatch):
    def boom(*args, **kwargs):
        raise RuntimeError("unexpected")

    monkeypatch.setattr(cli.commands, "load_record", boom)
    code, _, err = _run(["fit", record, "--column", "gyro_y", "--out", tmp_path / "m.json"], capsys)
    assert code == 1 and "internal error: RuntimeError: unexpected" in err and "report" in err


def test_existing_output_survives_a_failed_run(record, tmp_path, capsys):
    model = tmp_path / "model.json"
    model.write_text("previous")
    code, _, _ = _run(["fit", record, "--column", "nope", "--out", model], capsys)
    assert code == 2 and model.read_text() == "previous"


@pytest.mark.slow
def test_demo_writes_outputs_and_says_where(tmp_path, capsys, figure_log):  # the main job
    figures = figure_log()
    code, out, err = _run(["demo", "--out", tmp_path / "demo"], capsys)
    assert code == 0, err
    assert f"outputs written to {(tmp_path / 'demo').resolve()}" in out
    assert "Table 1: accelerometer" in out and "Table 2: gyroscope" in out
    for sensor, units in (("accelerometer", "m/s^2"), ("gyroscope", "deg/h")):
        table = pd.read_csv(tmp_path / "demo" / sensor / "comparison.csv")
        assert set(table["Method"]) == {"Yule-Walker", "Covariance", "Burg", "Gauss-Markov",
                                        "FOS CP=1", "FOS CP=2"}
        assert list(table["Order L"].unique()) == [1, 10]
        assert np.all(table[f"MSE ({units})^2"] > 0)
        for name in ("report.md", "study.csv", "order_paper.png", "order_fair.svg"):
            assert (tmp_path / "demo" / sensor / name).exists()
    # the bundled real MPU-6050 record: study and residual loop, end to end
    assert "MPU-6050 record bundled with fosmodel (MIT licence): 44930 samples" in out
    assert "Residual loop on each axis of the MPU-6050 record" in out
    mpu = tmp_path / "demo" / "mpu6050"
    assert (mpu / "study_gx" / "comparison.csv").exists()
    assert (mpu / "study_ay" / "order_fair.png").exists()
    for axis in ("ax", "ay", "az", "gx", "gy", "gz"):
        assert (mpu / f"loop_{axis}" / "report.md").exists()
    # every figure reads (tests/test_figures.py says what is checked)
    checked = figures()
    assert len(checked) == len(list((tmp_path / "demo").rglob("*.png")))
    assert {path: problems for path, problems in checked.items() if problems} == {}


@pytest.mark.slow
def test_console_script_is_installed(record, tmp_path):
    script = shutil.which("fosmodel") or str(Path(sysconfig.get_path("scripts")) / "fosmodel")
    proc = subprocess.run([script, "fit", str(record), "--column", "nope",
                           "--out", str(tmp_path / "m.json")], capture_output=True, text=True)
    assert proc.returncode == 2 and "no column 'nope'" in proc.stderr


@pytest.fixture
def long_record(tmp_path):
    rng = np.random.default_rng(1)
    n = 9000
    accel = lfilter([1.0], [1.0, -0.9, 0.4], rng.standard_normal(n)) * 1e-3
    path = tmp_path / "accel.csv"
    pd.DataFrame({"time": np.arange(n) / 10.0, "accel_y": accel}).to_csv(path, index=False)
    return path


@pytest.mark.slow
def test_study_writes_report_and_json(long_record, tmp_path, capsys):
    out, js = tmp_path / "study", tmp_path / "rows.json"
    code, stdout, err = _run(["study", long_record, "--column", "accel_y", "--sensor", "accel",
                              "--units", "m/s^2", "--orders", "1-3", "--degrees", "1,2",
                              "--split", "300s,200s", "--starts", "5", "--out", out,
                              "--json", js], capsys)
    assert code == 0, err
    assert "Yule-Walker" in stdout and "FOS CP=2" in stdout and "written to" in stdout
    assert (out / "report.md").exists() and (out / "order_fair.svg").exists()
    data = json.loads(js.read_text())
    n_taus = len(data["level_taus_s"])
    # both protocols, then about the level (fair): FOS once, each baseline per time constant
    assert n_taus == 4 and len(data["rows"]) == 2 * (3 * 2 + 3 * 3 + 1) + 3 * 2 + n_taus * 10
    assert {"method", "order", "degree", "mse", "position_error_m", "outage_mse", "bias_rms",
            "outage_position_error_m", "runtime_s", "n_terms", "protocol",
            "level_tau_s"} <= set(data["rows"][0])
    assert "## About the local level (fair protocol)" in (out / "report.md").read_text()
    code, stdout, err = _run(["study", long_record, "--column", "accel_y", "--sensor", "accel",
                              "--units", "m/s^2", "--orders", "1", "--degrees", "1",
                              "--split", "300s,200s", "--starts", "5", "--no-levels",
                              "--out", tmp_path / "plain", "--json", js], capsys)
    assert code == 0, err
    assert not any(r["method"].endswith("+level") for r in json.loads(js.read_text())["rows"])


@pytest.mark.parametrize(
    "extra, message",
    [(["--split", "600s,300s"], "leaves 0 samples to predict"),
     (["--split", "10min,250s"], "leaves 500 samples to predict, 600 are needed (a 30 s "
                              "outage horizon and two 30 s bias windows)"),
     (["--methods", "fos,arima"], "unknown method 'arima'"),
     (["--units", "deg/s"], "fosmodel: error: column 'accel_y': deg/s is a unit of a gyro, "
                            "not of an accelerometer\n"),
     (["--column", "accel_x"], "no column 'accel_x' (did you mean 'accel_y'?)")],
)
def test_study_bad_input_exit_2(long_record, tmp_path, capsys, extra, message):
    args = ["study", long_record, "--column", "accel_y", "--sensor", "accel", "--units", "m/s^2",
            "--out", tmp_path / "out", "--json", tmp_path / "rows.json", *extra]
    code, _, err = _run(args, capsys)
    assert code == 2 and err.count("\n") == 1 and message in err
    assert not (tmp_path / "out").exists() and not (tmp_path / "rows.json").exists()


def test_study_empty_file_exit_2(tmp_path, capsys):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    code, _, err = _run(["study", empty, "--column", "a", "--sensor", "gyro", "--units", "deg/s",
                         "--out", tmp_path / "o"], capsys)
    assert code == 2 and "the file is empty" in err


@pytest.mark.slow
def test_close_loop_finds_an_undeclared_temperature_effect(tmp_path, capsys):
    rec = tmp_path / "rec.csv"
    assert cli.main(["synth", "undeclared_temperature", "--seed", "0", "--out", str(rec)]) == 0
    out, js, model = tmp_path / "loop", tmp_path / "loop.json", tmp_path / "final.json"
    code, stdout, err = _run(["close-loop", rec, "--column", "gyro_x", "--sensor", "gyro",
                              "--units", "deg/s", "--out", out, "--json", js, "--model", model],
                             capsys)
    assert code == 0, err
    assert "driver temp_c, slow part" in stdout and "written to" in stdout
    # a progress line for the starting model, each round and each effect tried
    assert "fosmodel: starting model: " in err and "fosmodel: round 1: " in err
    assert "fosmodel:   [1/" in err and "fosmodel: kept driver temp_c, slow part" in err
    data = json.loads(js.read_text())
    drivers = [e for e in data["effects"] if e["kind"] == "driver"]
    assert [e["channel"] for e in drivers] == ["temp_c"] and not data["worse_on_prediction"]
    assert data["after"]["outage_mse"]["30"] < data["before"]["outage_mse"]["30"]
    for name in ("report.md", "effects.csv", "ratios.csv", "diagnostics.md", "residual.png",
                 "residual.svg"):
        assert (out / name).exists()
    # the final model is a model file: predict rebuilds its compensation from the record
    saved = json.loads(model.read_text())
    assert saved["format"] == "fosmodel.FOSModel"
    assert all(name.startswith("pow(temp_c,") for name in saved["params"]["compensation"])
    pred = tmp_path / "pred.csv"
    code, stdout, err = _run(["predict", rec, "--model", model, "--out", pred], capsys)
    assert code == 0, err
    frame = pd.read_csv(pred)
    fitted = FOSModel.from_dict(saved)
    y, temp = frame["gyro_x"].to_numpy(), pd.read_csv(rec)["temp_c"].to_numpy()
    np.testing.assert_allclose(frame["prediction"], fitted.predict(y, {"temp_c": temp}),
                               rtol=1e-9, atol=1e-9)


# another gyro axis, and a magnetometer's axis: both measure the motion in use
@pytest.mark.parametrize("other", ["gy_dps", "mag_x"])
def test_close_loop_takes_a_companion_as_an_input_only_when_asked(other, tmp_path, capsys):
    rng = np.random.default_rng(3)
    n, rate = 30_000, 100.0
    gy = rng.standard_normal(n)
    gx = 0.05 * rng.standard_normal(n) + 0.02 * np.r_[0.0, gy[:-1]]
    rec = tmp_path / "imu.csv"
    pd.DataFrame({"time": np.arange(n) / rate, "gx_dps": gx, other: gy}).to_csv(rec,
                                                                               index=False)
    runs = {}
    for name, extra in (("default", []), ("asked", ["--aux", other])):
        js = tmp_path / f"{name}.json"
        code, stdout, err = _run(["close-loop", rec, "--column", "gx_dps", "--units", "deg/s",
                                  "--out", tmp_path / name, "--json", js, *extra], capsys)
        assert code == 0, err
        runs[name] = json.loads(js.read_text())
    default, asked = runs["default"], runs["asked"]
    assert default["effects"] == [] and default["roles"]["companions"] == [other]
    (noise,) = default["cross_axis"]
    assert noise["channel"] == other and noise["lag"] == 1 and noise["fired"]
    assert [(e["kind"], e["channel"]) for e in asked["effects"]] == [("companion", other)]
    report = (tmp_path / "asked" / "report.md").read_text()
    assert f"companion {other} as an input, as asked" in report
    assert "taken as an input as asked" in report


def test_fit_offers_levels(long_record, tmp_path, capsys):
    model = tmp_path / "m.json"
    code, out, err = _run(["fit", long_record, "--column", "accel_y", "--max-lag", 3,
                           "--levels", "auto", "--out", model], capsys)
    assert code == 0, err
    assert "levels offered (below the Allan floor): " in out and "Levels offered" in out
    saved = json.loads(model.read_text())
    assert saved["params"]["rate"] == 10.0 and saved["params"]["levels"]
    with pytest.raises(SystemExit) as exc:
        _run(["fit", long_record, "--column", "accel_y", "--levels", "5,0", "--out", model],
             capsys)
    assert exc.value.code == 2
    assert "expected 'auto' or time constants in seconds like 5,20" in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, message",
    [(["--sensor", "gyro"], "fosmodel: error: column 'gyro_y': a gyro, but the name does not "
                             "tell its units; give them as gyro_y=UNITS (e.g. gyro_y=deg/s)\n"),
     (["--split", "25s,5s"], "fosmodel: error: the split 25s,5s leaves nothing of the record "
                             "(3000 samples, 30 s at 100 Hz) to predict\n"),
     (["--aux", "temp"], "--aux: no channel 'temp' among the other columns (did you mean "
                         "'temp_c'?)"),
     (["--aux", "temp_c"], "--aux: 'temp_c' is not a companion of the modelled axis "
                           "(companions: none); a driver is offered as an input "
                           "already"),
     (["--horizons", "30s,30s"], "--horizons repeats a duration: (30.0, 30.0)"),
     (["--max-lag", "0"], "--max-lag must be an integer >= 1, got 0")],
)
def test_close_loop_bad_input_exit_2(record, tmp_path, capsys, extra, message):
    args = ["close-loop", record, "--column", "gyro_y", "--out", tmp_path / "o", *extra]
    code, _, err = _run(args, capsys)
    assert code == 2 and err.count("\n") == 1 and message in err
    assert not (tmp_path / "o").exists()


def test_close_loop_too_short_exit_2(record, tmp_path, capsys):
    code, _, err = _run(["close-loop", record, "--column", "gyro_y", "--out", tmp_path / "o"],
                        capsys)
    assert code == 2 and "too short for the split" in err


def test_cli_bursty_time_needs_uniform_and_prints_notes(tmp_path, capsys, bursty_csv):
    p, effective = bursty_csv()
    fit = ["fit", p, "--column", "gx", "--max-lag", 2, "--out", tmp_path / "m.json"]
    code, _, err = _run(fit, capsys)
    assert code == 2 and err.count("\n") == 1 and "pass --uniform" in err
    code, _, err = _run([*fit, "--uniform"], capsys)
    assert code == 0, err
    assert "fosmodel: note: column 't_s' (lines 2-401) looks like a host's bursty" in err
    assert json.loads((tmp_path / "m.json").read_text())["meta"]["rate_hz"] == pytest.approx(
        effective)


def test_cli_scale_and_outliers(tmp_path, capsys, spiky_csv):
    p, _, _ = spiky_csv(with_time=False)
    out = tmp_path / "m.json"
    code, _, err = _run(["fit", p, "--column", "a", "--scale", "a=1/2", "--scale", "b=0.5",
                         "--outliers", "clip", "--out", out], capsys)
    assert code == 0, err
    assert "fosmodel: note: scaled a by 0.5, b by 0.5\n" in err
    assert "fosmodel: note: column 'a': 2 outlier(s)" in err and "clipped to" in err
    for extra, message in ((["--scale", "a=x"], "--scale 'a=x': expected NAME=FACTOR"),
                           (["--scale", "aa=2"], "no column 'aa' (did you mean 'a'?)"),
                           (["--outliers", "drop"], "without a time column")):
        code, _, err = _run(["fit", p, "--column", "a", *extra, "--out", out], capsys)
        assert code == 2 and err.count("\n") == 1 and message in err


def test_fit_and_predict_on_segments_and_fill(tmp_path, capsys):
    t = np.r_[np.arange(0, 60, 0.01), np.arange(70, 130, 0.01)]
    y = lfilter([1.0], [1.0, -0.8], np.random.default_rng(2).standard_normal(len(t)))
    path = tmp_path / "gappy.csv"
    pd.DataFrame({"time": t, "gyro": y}).to_csv(path, index=False)
    code, _, err = _run(["fit", path, "--column", "gyro", "--out", tmp_path / "m.json"], capsys)
    assert code == 2 and "pass --fill" in err
    code, _, err = _run(["fit", path, "--column", "gyro", "--segments", "--out",
                         tmp_path / "m.json"], capsys)
    assert code == 0, err
    assert "kept as 2 contiguous segments of 6000, 6000 samples" in err
    code, _, err = _run(["predict", path, "--model", tmp_path / "m.json", "--segments",
                         "--out", tmp_path / "p.csv"], capsys)
    assert code == 0, err
    assert pd.read_csv(tmp_path / "p.csv")["prediction"].isna().sum() == 2 * 10
    with pytest.raises(SystemExit) as exc:  # a usage error: the study is not offered segments
        _run(["study", path, "--column", "gyro", "--units", "deg/s", "--segments", "--out",
              tmp_path / "s"], capsys)
    assert exc.value.code == 2 and not (tmp_path / "s").exists()
    assert capsys.readouterr().err == (
        "fosmodel: error: argument --segments: the model-order study needs a contiguous record; "
        "pass --fill to interpolate across the gaps (fosmodel study --help shows the usage)\n")
    code, _, err = _run(["fit", path, "--column", "gyro", "--fill", "--out",
                         tmp_path / "m2.json"], capsys)
    assert code == 0 and "filled by linear interpolation (1000 samples added" in err


def _imu_files(tmp_path, columns=(("gx", "gy"), ("gx", "gy"))):
    """imu1.csv and imu2.csv.gz, 900 s at 10 Hz, with the given columns each."""
    paths = [tmp_path / "imu1.csv", tmp_path / "imu2.csv.gz"]
    rng = np.random.default_rng(7)
    for path, names in zip(paths, columns):
        data = {name: lfilter([1.0], [1.0, -0.9, 0.4], rng.standard_normal(9000)) * 1e-3
                for name in names}
        pd.DataFrame({"time": np.arange(9000) / 10.0, **data}).to_csv(path, index=False)
    return paths


def _multi_study(paths, out, *extra):
    return ["study", *paths, "--columns", "gx,gy", "--sensor", "gyro", "--units", "deg/s",
            "--orders", "1-2", "--degrees", "1", "--protocol", "fair", "--split", "300s,200s",
            "--starts", "5", "--out", out, *extra]


@pytest.mark.slow
def test_study_of_many_files_and_columns(tmp_path, capsys):
    out, js = tmp_path / "out", tmp_path / "rows.json"
    code, stdout, err = _run(_multi_study(_imu_files(tmp_path), out, "--json", js), capsys)
    assert code == 0, err
    records = ["imu1_gx", "imu1_gy", "imu2_gx", "imu2_gy"]
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == records
    assert all((out / r / "report.md").exists() and (out / r / "order_fair.png").exists()
               for r in records)
    best = pd.read_csv(out / "best.csv")
    assert list(best.columns[:4]) == ["Record", "File", "Column", "Protocol"]
    assert list(best["Record"].unique()) == records and len(best) == 4 * 2 * 5  # +level too
    one = pd.read_csv(out / "imu2_gy" / "best.csv")
    pd.testing.assert_frame_equal(best[best["Record"] == "imu2_gy"].iloc[:, 3:].reset_index(
        drop=True), one)
    assert (out / "best.md").read_text().startswith("| Record | File | Column |")
    data = json.loads(js.read_text())
    assert [(r["report"], r["column"]) for r in data["records"]] == [
        (r, r[-2:]) for r in records]
    # per record 9 fits, and about the level FOS twice and the 7 baselines per time constant
    assert "study of 4 records, 156 fits written to" in stdout and "imu2_gy" in stdout
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_study_bad_column_in_second_file_writes_nothing(tmp_path, capsys):
    paths = _imu_files(tmp_path, columns=(("gx", "gy"), ("gx", "gz")))
    out, js = tmp_path / "out", tmp_path / "rows.json"
    code, _, err = _run(_multi_study(paths, out, "--json", js), capsys)
    assert code == 2 and err.count("\n") == 1, err
    assert f"{paths[1]}: no column 'gy'; columns: gx, gz" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["imu1.csv", "imu2.csv.gz"]


def test_study_refuses_reports_that_would_share_a_directory(tmp_path, capsys):
    path = _imu_files(tmp_path)[0]
    code, _, err = _run(_multi_study([path, path], tmp_path / "out"), capsys)
    assert code == 2 and err.count("\n") == 1
    assert f"{path} column 'gx' and {path} column 'gx' would both be reported in imu1_gx/" in err
    assert not (tmp_path / "out").exists()


def test_study_unreachable_scheduler_exit_2(tmp_path, capsys):
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"  # closed once the block ends
    path = _imu_files(tmp_path)[0]
    code, _, err = _run(_multi_study([path], tmp_path / "out", "--scheduler", address,
                                     "--connect-timeout", "1"), capsys)
    assert code == 2 and err.count("\n") == 1
    assert f"fosmodel: error: cannot connect to the Dask scheduler at {address}" in err
    assert not (tmp_path / "out").exists()


def test_fit_refuses_a_candidate_set_over_max_candidates(record, tmp_path, capsys):
    out = tmp_path / "m.json"
    code, stdout, err = _run(["fit", record, "--column", "gyro_y", "--max-lag", 50, "--degree", 2,
                              "--max-candidates", 1000, "--out", out], capsys)
    assert code == 2 and not out.exists()
    assert "candidates: 1326 (L=50, CP=2)" in stdout
    assert "1326 candidates exceed max_candidates=1000" in err and "MiB" in err
    assert len(err.strip().splitlines()) == 1


def test_commands_read_only_the_columns_they_use(record, tmp_path, capsys):
    frame = pd.read_csv(record)
    frame["notes"] = "warm"  # a text column the commands never touch
    path = tmp_path / "wide.csv"
    frame.to_csv(path, index=False)
    model = tmp_path / "m.json"
    assert _run(["fit", path, "--column", "gyro_y", "--exog", "temp_c:1", "--out", model],
                capsys)[0] == 0
    assert _run(["predict", path, "--model", model, "--out", tmp_path / "p.csv"], capsys)[0] == 0
    assert _run(["allan", path, "--column", "gyro_y", "--out", tmp_path / "allan"], capsys)[0] == 0
    code, _, err = _run(["fit", path, "--column", "notes", "--out", tmp_path / "x.json"], capsys)
    assert code == 2 and "column 'notes'" in err and "not a number" in err


@pytest.mark.parametrize("flag", [["--workers", "2"], ["--scheduler", "tcp://127.0.0.1:1"]])
def test_dask_options_without_the_distributed_extra_say_how_to_get_it(record, tmp_path, capsys,
                                                                      monkeypatch, flag):
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    monkeypatch.delitem(sys.modules, "fosmodel.study.distributed", raising=False)
    out = tmp_path / "study"
    code, _, err = _run(["study", record, "--column", "gyro_y", "--sensor", "gyro", "--units",
                         "deg/s", "--orders", "1", "--methods", "burg", *flag, "--out", out],
                        capsys)
    assert code == 2 and not out.exists()
    assert err.strip() == (f"fosmodel: error: {flag[0]}: running fits on Dask needs the "
                           "'distributed' extra: pip install 'fosmodel[distributed]'")


# --- one grammar: lengths with units, comma lists, units per column, -v anywhere, defaults ------


def _subparsers():
    import argparse

    parser = cli.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices


def test_every_option_of_every_command_has_help_ending_with_its_default():
    import argparse

    for name, command in _subparsers().items():
        text = "".join(command.format_help().split())  # wrapped lines, "single-" "threaded"
        formatter = command._get_formatter()
        for action in command._actions:
            if not action.option_strings or action.help == argparse.SUPPRESS:
                continue
            shown = formatter._expand_help(action)
            assert action.help, (name, action.option_strings)
            has_default = (action.nargs != 0 and action.default not in (None, argparse.SUPPRESS)
                           and action.default != [])
            if has_default:
                assert shown.endswith(f"(default: {action.default})"), (name, shown)
            assert "".join(shown.split()) in text, (name, shown)
        assert "(default:None)" not in text and "(default:False)" not in text, name
        assert "(default:[])" not in text and "==SUPPRESS==" not in text, name
    study = " ".join(_subparsers()["study"].format_help().split())
    for default in ("(default: 180s,180s)", "(default: 1-10)", "(default: 1,2)",
                    "(default: fos,yw,cov,burg,gm)", "(default: 30)", "(default: refuse)"):
        assert default in study
    assert "(default: 50%,20%)" in " ".join(_subparsers()["close-loop"].format_help().split())


@pytest.mark.parametrize("argv", [["-v", "fit", "r.csv", "--column", "g", "--out", "m.json"],
                                  ["fit", "r.csv", "-v", "--column", "g", "--out", "m.json"],
                                  ["study", "r.csv", "--column", "g", "--out", "o", "--verbose"]])
def test_verbose_before_or_after_the_command(argv):
    assert cli.build_parser().parse_args(argv).verbose is True
    quiet = [a for a in argv if a not in ("-v", "--verbose")]
    assert cli.build_parser().parse_args(quiet).verbose is False


def test_verbose_after_the_command_shows_the_traceback_of_a_bug(record, tmp_path, capsys,
                                                                monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr("fosmodel.io.model_file.read_model", broken)  # predict imports it
    argv = ["predict", record, "--model", tmp_path / "m.json", "--out", tmp_path / "p.csv"]
    code, _, err = _run([*argv, "-v"], capsys)
    assert code == 1 and "Traceback" in err and "RuntimeError: a bug" in err
    code, _, err = _run(argv, capsys)
    assert code == 1 and "Traceback" not in err


def test_multi_valued_options_take_comma_lists():
    parser = cli.build_parser()
    args = parser.parse_args(["fit", "r.csv", "--column", "g", "--exog", "a:1,b:2", "--exog",
                              "c:0", "--scale", "a=1/2,b=2", "--scale", "c=3", "--out", "m"])
    assert args.exog == [("a", 1), ("b", 2), ("c", 0)]
    assert args.scale == ["a=1/2", "b=2", "c=3"]
    # --aux no longer swallows the record named after it
    args = parser.parse_args(["close-loop", "--aux", "temp_c,hum", "r.csv", "--column", "g",
                              "--out", "o"])
    assert args.aux == ["temp_c", "hum"] and args.files == ["r.csv"]
    args = parser.parse_args(["study", "r.csv", "--columns", "gx,gy", "--orders", "1-3,8",
                              "--degrees", "1", "--methods", "fos,burg", "--out", "o"])
    assert (args.columns, args.orders, args.methods) == (["gx", "gy"], [1, 2, 3, 8],
                                                         ["fos", "burg"])


def test_a_scale_list_reads_as_the_repeated_option(tmp_path, capsys, spiky_csv):
    p, _, _ = spiky_csv(with_time=False)
    notes = []
    for scale in (["--scale", "a=1/2,b=0.5"], ["--scale", "a=1/2", "--scale", "b=0.5"]):
        code, _, err = _run(["fit", p, "--column", "a", *scale, "--outliers", "keep",
                             "--out", tmp_path / "m.json"], capsys)
        assert code == 0, err
        notes.append([line for line in err.splitlines() if "scaled" in line])
    assert notes[0] == notes[1] == ["fosmodel: note: scaled a by 0.5, b by 0.5"]


@pytest.mark.parametrize(("argv", "message"), [
    (["study", "r.csv", "--column", "gx", "--split", "180,180", "--out", "o"],
     "argument --split: expected TRAIN,EVALUATE with units: durations like 180s,180s (s, min or "
     "h) or percents of the record like 50%,20%, got '180,180' (fosmodel study --help shows the "
     "usage)"),
    (["close-loop", "r.csv", "--column", "gx", "--split", "0.5,0.2", "--out", "o"],
     "argument --split: expected TRAIN,EVALUATE with units: durations like 180s,180s (s, min or "
     "h) or percents of the record like 50%,20%, got '0.5,0.2' (fosmodel close-loop --help shows "
     "the usage)"),
    (["study", "r.csv", "--column", "gx", "--units", "deg", "--out", "o"],
     "argument --units: unknown units 'deg' (did you mean 'deg/s'?); valid units: m/s^2, g, mg "
     "(accel); rad/s, deg/s, deg/h (gyro) (fosmodel study --help shows the usage)"),
    (["allan", "r.csv", "--columns", "gx,ax", "--units", "gx=deg/s,=g", "--out", "o"],
     "argument --units: expected UNITS or COLUMN=UNITS,... (e.g. deg/s or gx=deg/s,ax=g), got "
     "'gx=deg/s,=g' (fosmodel allan --help shows the usage)"),
    (["allan", "r.csv", "--column", "gx", "--segments", "--out", "o"],
     "argument --segments: the Allan deviation needs a contiguous record; pass --fill to "
     "interpolate across the gaps (fosmodel allan --help shows the usage)"),
    (["fit", "r.csv", "--column", "gx", "--exog", "temp:2,hum", "--out", "m"],
     "argument --exog: expected NAME:K[,NAME:K...] (e.g. temp:5), got 'temp:2,hum' (fosmodel fit "
     "--help shows the usage)"),
    (["close-loop", "r.csv", "--column", "gx", "--segments", "--out", "o"],
     "argument --segments: the residual loop needs a contiguous record; pass --fill to "
     "interpolate across the gaps (fosmodel close-loop --help shows the usage)"),
])
def test_usage_errors_of_the_grammar(argv, message, capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(argv)
    assert exc.value.code == 2
    assert capsys.readouterr().err == f"fosmodel: error: {message}\n"


def test_segments_is_offered_only_where_a_record_may_have_gaps():
    for name, command in _subparsers().items():
        offered = "--segments" in command.format_help()
        assert offered == (name in ("fit", "predict")), name


def _mixed_imu(tmp_path):
    """900 s at 10 Hz of a gyro in deg/s (s1) and an accelerometer in g (s2): names that tell
    neither sensor nor units."""
    rng = np.random.default_rng(5)
    ar = [lfilter([1.0], [1.0, -0.9, 0.4], rng.standard_normal(9000)) for _ in range(2)]
    path = tmp_path / "mixed.csv"
    pd.DataFrame({"time": np.arange(9000) / 10.0, "s1": 0.05 * ar[0],
                  "s2": 2e-4 * ar[1]}).to_csv(path, index=False)
    return path


def test_a_study_of_gyro_and_accelerometer_columns_scores_each_in_its_own_units(tmp_path,
                                                                                capsys):
    from fosmodel.noise.metrics import equivalent_position_error

    path, js = _mixed_imu(tmp_path), tmp_path / "rows.json"
    code, stdout, err = _run(["study", path, "--columns", "s1,s2", "--units", "s1=deg/s,s2=g",
                              "--orders", "1-2", "--degrees", "1", "--methods", "fos,burg",
                              "--protocol", "fair", "--no-levels", "--split", "5min,50%",
                              "--starts", "5", "--out", tmp_path / "out", "--json", js], capsys)
    assert code == 0, err
    records = json.loads(js.read_text())["records"]
    assert [(r["column"], r["config"]["sensor"], r["config"]["units"]) for r in records] == [
        ("s1", "gyro", "deg/s"), ("s2", "accel", "g")]
    for r in records:
        assert (r["config"]["train_s"], r["config"]["evaluate_s"]) == (300.0, 450.0)
        assert r["split_samples"] == {"train": [0, 3000], "evaluate": [3000, 7500],
                                      "predict": [7500, 9000]}
        for row in r["rows"]:
            assert row["position_error_m"] == pytest.approx(equivalent_position_error(
                row["mse"], r["config"]["sensor"], r["config"]["units"]), rel=1e-12)
    assert "MSE (deg/s)^2" in stdout and "MSE (g)^2" in stdout
    for name, units in (("mixed_s1", "gyro, units deg/s"), ("mixed_s2", "accel, units g")):
        assert units in (tmp_path / "out" / name / "report.md").read_text()


def test_a_single_units_and_sensor_still_apply_to_every_column(tmp_path, capsys):
    path, js = _mixed_imu(tmp_path), tmp_path / "rows.json"
    code, _, err = _run(["study", path, "--columns", "s1,s2", "--sensor", "gyro", "--units",
                         "deg/h", "--orders", "1", "--degrees", "1", "--methods", "burg",
                         "--protocol", "fair", "--no-levels", "--split", "300s,300s",
                         "--starts", "5", "--out", tmp_path / "out", "--json", js], capsys)
    assert code == 0, err
    assert [(r["config"]["sensor"], r["config"]["units"])
            for r in json.loads(js.read_text())["records"]] == [("gyro", "deg/h")] * 2


@pytest.mark.slow
def test_study_split_in_percent_is_the_split_in_seconds(long_record, tmp_path, capsys):
    rows = []
    for split in ("50%,25%", "450s,225s", "7.5min,3.75min"):
        js = tmp_path / f"{split.replace('%', 'pc')}.json"
        code, _, err = _run(["study", long_record, "--column", "accel_y", "--units", "m/s^2",
                             "--orders", "1-2", "--degrees", "1", "--methods", "burg,fos",
                             "--protocol", "fair", "--no-levels", "--split", split, "--starts",
                             "5", "--out", tmp_path / split.replace("%", "pc"), "--json", js],
                            capsys)
        assert code == 0, err
        data = json.loads(js.read_text())
        rows.append([(r["method"], r["order"], r["mse"]) for r in data["rows"]])
        assert data["split_samples"]["evaluate"] == [4500, 6750]
    assert rows[0] == rows[1] == rows[2]


def test_close_loop_split_in_seconds_resolves_to_fractions_of_the_record(record, tmp_path,
                                                                         capsys):
    code, _, err = _run(["close-loop", record, "--column", "gyro_y", "--split", "20s,5s",
                         "--out", tmp_path / "o"], capsys)
    assert code == 2 and not (tmp_path / "o").exists()
    assert err.startswith("fosmodel: error: the record (3000 samples, 30 s at 100 Hz) is too "
                          "short for the split 0.666667 / 0.166667: ")


@pytest.mark.slow
def test_allan_takes_units_per_column_beside_the_names(tmp_path, capsys):
    path = _mixed_imu(tmp_path)
    out, js = tmp_path / "noise", tmp_path / "noise.json"
    code, _, err = _run(["allan", path, "--columns", "s1,s2", "--units", "s1=deg/s,s2=g",
                         "--out", out, "--json", js], capsys)
    assert code == 0, err
    assert "fosmodel: s1: gyro in deg/s (units given)" in err
    assert "fosmodel: s2: accel in g (units given)" in err
    axes = {a["column"]: a for a in json.loads(js.read_text())["axes"]}
    for column, si in (("s1", np.pi / 180), ("s2", 9.80665)):
        density = axes[column]["noise_density"]
        assert density["value"] == pytest.approx(density["record_units_value"] * si, rel=1e-12)
    # one column: --units alone gives the navigation units (its sensor from the units)
    code, stdout, err = _run(["allan", path, "--column", "s2", "--units", "g", "--out",
                              tmp_path / "one"], capsys)
    assert code == 0, err
    assert "Sensor:" in stdout and "accel" in stdout


def test_close_loop_reads_the_units_in_a_column_s_name(tmp_path, capsys):
    rng = np.random.default_rng(2)
    path = tmp_path / "gz.csv"
    gz = lfilter([1.0], [1.0, -0.9], rng.standard_normal(20_000)) * 0.01 + 0.3
    pd.DataFrame({"gz_dps": gz}).to_csv(path, index=False)
    code, out, err = _run(["close-loop", path, "--column", "gz_dps", "--rate", "100", "--out",
                           tmp_path / "loop"], capsys)
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == ("prediction segment: MSE (deg/s)^2, outage position error (m), "
                        "free-run bias RMS (deg/s)")
    assert lines[3].split()[-2] != "-"  # the outage error of the starting model, in metres


@pytest.mark.slow
def test_close_loop_on_a_readable_header_takes_any_channel_as_input(readable_csv, tmp_path,
                                                                   capsys):
    """A channel ``Accel Y (g)``, a companion asked for as an input, enters the model with its
    lags; the saved model is applied again, its inputs read from the record by their headers."""
    model = tmp_path / "final.json"
    code, out, err = _run(["close-loop", readable_csv, "--column", "Accel X (g)", "--rate",
                           "100", "--aux", "Accel Y (g)", "--out", tmp_path / "loop", "--model",
                           model], capsys)
    assert code == 0, err
    assert out.startswith("prediction segment: MSE (g)^2, outage position error (m), "
                          "free-run bias RMS (g)\n")
    assert "kept companion Accel Y (g) as an input, as asked (fast part, lags 0-10)" in err
    fitted = FOSModel.from_dict(json.loads(model.read_text()))
    code, out, err = _run(["predict", readable_csv, "--model", model, "--rate", "100", "--out",
                           tmp_path / "pred.csv"], capsys)
    assert code == 0, err
    assert "Accel Y (g)" in fitted.input_columns() and out.startswith(
        "one-step prediction of 'Accel X (g)' on ")
