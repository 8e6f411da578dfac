"""CSV + truth sidecar writing (data_synth.io)."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from data_synth import (
    make_scenario,
    make_sessions,
    session_paths,
    truth_path,
    write_record,
    write_sessions,
)
from data_synth.scenarios import SCENARIOS

EFFECT_WORDS = (
    "temperature_bias",
    "vibration",
    "nonlinear",
    "drift",
    "bias_step",
    "g_sensitivity",
    "undeclared",
    "declared",
    "#",
)


def test_sidecar_path_beside_the_csv(tmp_path):
    assert truth_path("out/rec.csv").as_posix() == "out/rec.truth.json"
    rec = make_scenario("unrelated_temperature", duration=5.0, seed=1)
    csv, side = write_record(rec, tmp_path / "rec.csv")
    assert csv == tmp_path / "rec.csv" and side == tmp_path / "rec.truth.json"
    assert csv.exists() and side.exists()


def test_csv_round_trips_float64_exactly(tmp_path):
    rec = make_scenario("undeclared_aux_lag", duration=20.0, seed=2)
    csv, side = write_record(rec, tmp_path / "r.csv")
    lines = csv.read_text().splitlines()
    assert lines[0] == "time,gyro_x,accel_x" and len(lines) == rec.n_samples + 1
    frame = pd.read_csv(csv)
    assert list(frame.columns) == ["time", "gyro_x", "accel_x"]
    np.testing.assert_array_equal(frame["time"].to_numpy(), rec.time())
    for col, values in rec.columns.items():
        np.testing.assert_array_equal(frame[col].to_numpy(), values)
    assert lines[1].split(",")[0] == "0.0" and lines[2].split(",")[0] == "0.01"
    truth = json.loads(side.read_text())
    assert truth["columns"]["time"].pop("written") is True
    assert truth == json.loads(json.dumps(rec.truth))


def test_without_time_column(tmp_path):
    rec = make_scenario("clean", duration=1.0)
    csv, side = write_record(rec, tmp_path / "r.csv", time=False)
    assert csv.read_text().splitlines()[0] == "gyro_x"
    assert "time" not in json.loads(side.read_text())["columns"]


@pytest.mark.parametrize("name", ["paper_gyro_y", "undeclared_temperature", "gyro_array_8"])
def test_same_seed_same_bytes_different_seed_different_bytes(tmp_path, name):
    paths = []
    for sub, seed in (("a", 7), ("b", 7), ("c", 8)):
        (tmp_path / sub).mkdir()
        rec = make_scenario(name, duration=5.0, seed=seed)
        paths.append(write_record(rec, tmp_path / sub / "rec.csv"))
    (a_csv, a_js), (b_csv, b_js), (c_csv, c_js) = paths
    assert a_csv.read_bytes() == b_csv.read_bytes() and a_js.read_bytes() == b_js.read_bytes()
    assert a_csv.read_bytes() != c_csv.read_bytes() and a_js.read_bytes() != c_js.read_bytes()


@pytest.mark.parametrize(
    "name", [n for n, sc in SCENARIOS.items() if n.startswith(("undeclared", "temperature_"))
             and not n.endswith("_control") and sc.sessions == 1]
)
def test_undeclared_effects_leave_no_trace_in_the_csv(tmp_path, name):
    rec = make_scenario(name, duration=5.0, seed=3)
    csv, side = write_record(rec, tmp_path / "r.csv")
    text = csv.read_text()
    header, *rows = text.splitlines()
    assert header.split(",") == ["time", *rec.columns]
    assert not any(word in text for word in EFFECT_WORDS)
    np.array([row.split(",") for row in rows], dtype=float)  # every other line is numbers
    # the truth keeps them
    truth = json.loads(side.read_text())
    assert any(not s["declared"] for s in truth["sources"])


def test_headers_match_the_controls(tmp_path):
    def header(name):
        csv, _ = write_record(make_scenario(name, duration=1.0), tmp_path / f"{name}.csv")
        return csv.read_text().splitlines()[0]

    assert (
        header("undeclared_temperature")
        == header("unrelated_temperature")
        == header("temperature_and_vibration")
        == "time,gyro_x,temp_c"
    )
    assert {
        header(n)
        for n in (
            "clean",
            "undeclared_vibration",
            "undeclared_nonlinear",
            "undeclared_drift",
            "undeclared_step",
        )
    } == {"time,gyro_x"}


def test_failed_write_leaves_the_old_files(tmp_path):
    rec = make_scenario("clean", duration=1.0, seed=1)
    csv, side = write_record(rec, tmp_path / "r.csv")
    before = csv.read_bytes(), side.read_bytes()
    bad = make_scenario("clean", duration=2.0, seed=2)
    bad.truth["sources"][0]["params"]["sigma"] = float("nan")  # not valid JSON
    with pytest.raises(ValueError):
        write_record(bad, csv)
    assert (csv.read_bytes(), side.read_bytes()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv", "r.truth.json"]


@pytest.mark.parametrize("name", ["gyro_array_8", "undeclared_aux_lag", "paper_gyro_y"])
def test_fosmodel_loader_reads_the_csv(tmp_path, name):
    from fosmodel.io.loader import load_record

    rec = make_scenario(name, duration=30.0, seed=1)
    csv, _ = write_record(rec, tmp_path / "r.csv")
    loaded = load_record(csv)
    assert loaded.names == list(rec.columns)
    assert loaded.rate == pytest.approx(rec.rate, rel=1e-9)
    for col, values in rec.columns.items():
        np.testing.assert_array_equal(loaded.data[col], values)


def test_sessions_go_to_numbered_files(tmp_path):
    assert session_paths("out/day.csv", 2) == [Path("out/day_s1.csv"), Path("out/day_s2.csv")]
    records = make_sessions("temperature_sessions_control", duration=30.0, seed=1)
    written = write_sessions(records, tmp_path / "c.csv", time=False)
    assert [p.name for p, _ in written] == ["c_s1.csv", "c_s2.csv", "c_s3.csv"]
    for rec, (csv, side) in zip(records, written):
        assert csv.read_text().splitlines()[0] == ",".join(rec.columns)
        assert json.loads(side.read_text())["session"] == rec.truth["session"]
