"""The six-axis workflow: every axis through the Allan analysis, the study and the loop."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.io.model_file import read_model
from fosmodel.noise.axes import resolve_axes
from fosmodel.workflows.imu import ImuConfig, run_imu
from fosmodel.workflows.imu_report import write_imu_report

SMALL = dict(orders=(1, 2), degrees=(1,), methods=("fos", "burg"), n_starts=5)


@pytest.fixture(scope="module")
def record():
    from data_synth import make_scenario

    return make_scenario("static_imu", duration=600.0, seed=3)


@pytest.fixture(scope="module")
def result(record):
    axes = resolve_axes(list(record.columns))
    return run_imu(record.columns, axes, record.rate, "static_imu",
                   config=ImuConfig(**SMALL, n_jobs=1))


def test_every_axis_goes_through_every_step(result, record):
    columns = list(record.columns)
    assert [a.axis.column for a in result.axes] == columns
    assert [a.axis.column for a in result.noise.axes] == columns
    for a in result.axes:
        assert set(a.study.rows["method"]) == {"fos", "burg", "fos+level", "burg+level"}
        assert set(a.study.rows["order"]) == {1, 2}
        assert a.loop.config.sensor == a.axis.sensor and a.loop.config.units == a.axis.units
        assert set(a.seconds) == {"study", "loop"}
    study, loop = result.study_table(), result.loop_table()
    assert list(study["axis"]) == columns and list(loop["axis"]) == columns
    assert (study["FOS / baseline (outage)"]
            == study["FOS outage error (m, 30 s)"]
            / study["baseline outage error (m, 30 s)"]).all()


def test_each_axis_has_the_other_axes_of_its_kind_as_companions(result):
    for a in result.axes:
        kind = [x.axis.column for x in result.axes
                if x.axis.sensor == a.axis.sensor and x is not a]
        assert a.loop.roles.companions == tuple(kind) and a.loop.roles.told == "as given"
        assert not any(s.effect.kind == "companion" for s in a.loop.steps)
        assert [c["channel"] for c in a.loop.cross_axis] == kind
    assert "cross-axis noise (largest)" in result.loop_table()


def test_the_rows_are_the_steps_run_alone(result, record):
    """A row of the tables is what the study and the loop of that axis give by themselves."""
    from fosmodel.loop.closeloop import close_loop
    from fosmodel.study.runner import run_study

    a = result.axes[3]
    config = ImuConfig(**SMALL)
    alone = run_study(record.columns[a.axis.column], config.study_config(record.rate, a.axis))
    pd.testing.assert_frame_equal(alone.rows.drop(columns="runtime_s"),
                                  a.study.rows.drop(columns="runtime_s"))
    others = {k: v for k, v in record.columns.items() if k != a.axis.column}
    loop = close_loop(record.columns[a.axis.column], others,
                      config.loop_config(record.rate, a.axis, [x.axis for x in result.axes]))
    assert loop.after == a.loop.after and len(loop.steps) == len(a.loop.steps)


@pytest.fixture(scope="module")
def pair(record):
    """A gyro and an accelerometer axis, in this process (with its progress lines) and on
    two workers."""
    axes = [a for a in resolve_axes(list(record.columns)) if a.column in ("gx_dps", "ax_mps2")]
    lines = []
    here = run_imu(record.columns, axes, record.rate, "static_imu",
                   config=ImuConfig(**SMALL, n_jobs=1), progress=lines.append)
    two = run_imu(record.columns, axes, record.rate, "static_imu",
                  config=ImuConfig(**SMALL, n_jobs=2))
    return here, two, lines


def test_two_workers_give_the_same_tables(pair):
    here, two, _ = pair
    pd.testing.assert_frame_equal(two.study_table(), here.study_table())
    pd.testing.assert_frame_equal(two.loop_table(), here.loop_table())


def test_progress_names_each_step_of_each_axis(pair):
    lines = pair[2]
    assert lines[0].startswith("allan: 2 axes in ")
    assert sorted(line.split(" in ")[0] for line in lines[1:]) == [
        "loop: ax_mps2", "loop: gx_dps", "study: ax_mps2", "study: gx_dps"]
    assert lines[-1].endswith("4/4 tasks done")


def test_the_report_holds_every_axis_the_exports_and_the_models(pair, record, tmp_path):
    result = pair[1]  # written by two workers
    paths = write_imu_report(result, tmp_path, "static imu")
    assert all(p.is_file() for p in paths)
    page = (tmp_path / "report.md").read_text()
    columns = [a.axis.column for a in result.axes]
    for column in columns:
        assert f"| {column} |" in page
        assert (tmp_path / "study" / column / "report.md").is_file()
        assert (tmp_path / "loop" / column / "report.md").is_file()
        model = read_model(tmp_path / "models" / f"{column}.json")
        loop = result.axes[columns.index(column)].loop
        assert ("starting" in model.meta_["model"]) == bool(loop.worse() and loop.steps)
        pred = model.predict(record.columns[column])
        assert np.isfinite(pred[model.lag_window_:]).all()
    for name in ("imu.yaml", "imu_params.m", "imu_noise.json"):
        assert (tmp_path / "noise" / name).is_file()
    for stem in ("noise", "study", "loop", "timing"):
        assert {p.name for p in tmp_path.glob(f"{stem}.*")} == {f"{stem}.{e}" for e in
                                                                 ("md", "csv", "tex")}


def test_the_filter_model_is_the_axes_allan_models_side_by_side(result):
    from fosmodel.filter.allan_statespace import allan_state_space

    data = json.loads(json.dumps(result.filter_dict()))
    blocks = [allan_state_space(a.fit) for a in result.noise.axes]
    sizes = [b.n_states for b in blocks]
    phi, p0 = np.array(data["Phi"]), np.array(data["P0"])
    assert phi.shape == (sum(sizes), sum(sizes)) and np.array(data["H"]).shape[0] == 6
    at = 0
    for block, size in zip(blocks, sizes):
        np.testing.assert_array_equal(phi[at:at + size, at:at + size], block.Phi)
        at += size
    np.testing.assert_allclose(p0, p0.T)
    assert np.linalg.eigvalsh(p0).min() >= 0


def test_bad_input_is_refused_in_one_line(record):
    axes = resolve_axes(list(record.columns))
    with pytest.raises(InputError, match=r"^no axis to analyse$"):
        run_imu(record.columns, [], record.rate)
    with pytest.raises(InputError, match=r"^no column 'gx_dps' among the signals given$"):
        run_imu({k: v for k, v in record.columns.items() if k != "gx_dps"}, axes, record.rate)
    short = {**record.columns, "gy_dps": record.columns["gy_dps"][:-1]}
    with pytest.raises(InputError, match=r"^the columns differ in length: gx_dps 60000, "
                                         r"gy_dps 59999, "):
        run_imu(short, axes, record.rate)


def test_a_loop_split_too_short_is_refused_before_any_work(record, monkeypatch):
    import fosmodel.workflows.imu as workflow

    monkeypatch.setattr(workflow, "imu_noise", lambda *a, **k: pytest.fail("Allan ran"))
    axes = resolve_axes(list(record.columns))[:1]
    with pytest.raises(InputError, match=r"^the record \(60000 samples, 600 s at 100 Hz\) is too "
                                         r"short for the split 0.5 / 0.45: "):
        run_imu(record.columns, axes, record.rate,
                config=ImuConfig(**SMALL, loop_split=(0.5, 0.45), n_jobs=1))
