"""The six-axis workflow: every axis through the Allan analysis, the study and the loop."""

from __future__ import annotations

import itertools
import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.io.model_file import read_model
from fosmodel.noise.axes import resolve_axes
from fosmodel.study.harness import METHODS
from fosmodel.workflows.imu import ImuConfig, run_imu
from fosmodel.workflows.imu_report import console_summary, write_imu_report, write_imu_tables

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


@pytest.mark.slow
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
        gyros = [x.axis.column for x in result.axes
                 if a.axis.sensor == "accel" and x.axis.sensor == "gyro"]
        assert a.loop.roles.companions == (*kind, *gyros)
        assert a.loop.roles.told.startswith("as given")
        assert not any(s.effect.kind == "companion" for s in a.loop.steps)
        assert [c["channel"] for c in a.loop.cross_axis] == [*kind, *gyros]
    assert "cross-axis noise (largest)" in result.loop_table()


@pytest.mark.slow
def test_the_rows_are_the_steps_run_alone(result, record):
    """A row of the tables is what the study and the loop of that axis give by themselves."""
    from fosmodel.loop.closeloop import close_loop
    from fosmodel.study.runner import run_study

    a = result.axes[3]
    config = ImuConfig(**SMALL).for_record(len(record.columns[a.axis.column]), record.rate)
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


@pytest.mark.slow
def test_two_workers_give_the_same_tables(pair):
    here, two, _ = pair
    pd.testing.assert_frame_equal(two.study_table(), here.study_table())
    pd.testing.assert_frame_equal(two.loop_table(), here.loop_table())


@pytest.mark.slow
def test_progress_names_each_step_of_each_axis(pair):
    lines = pair[2]
    assert lines[0].startswith("allan: 2 axes in ")
    assert sorted(line.split(" in ")[0] for line in lines[1:]) == [
        "loop: ax_mps2", "loop: gx_dps", "study: ax_mps2", "study: gx_dps"]
    assert lines[-1].endswith("4/4 tasks done")


@pytest.mark.slow
def test_the_report_holds_every_axis_the_exports_and_the_models(pair, record, tmp_path):
    result = pair[1]  # written by two workers
    paths = write_imu_report(result, tmp_path, "static imu")
    assert all(p.is_file() for p in paths)
    page = (tmp_path / "report.md").read_text()
    # every error says what it is, its horizon and its segment: one segment for both steps
    assert ("- Outage position error (m, 30 s): in each of 5 outages of 30 s spread evenly over "
            "the prediction segment (360-600 s of the record), the model's free run") in page
    assert ("- Errors on the prediction segment (360-600 s of the record) (the study's: both "
            "steps score on one segment)") in page
    assert page.count("What the columns are:") == 2
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


@pytest.mark.slow
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
    with pytest.raises(InputError, match=r"^the record has 60000 samples \(600 s at 100 Hz\), "
                                         r"too short for these settings, which need at least "
                                         r"1199.9 s: the loop needs 1199.9 s \(the split 0.5 / "
                                         r"0.45: the evaluation segment needs "):
        run_imu(record.columns, axes, record.rate,
                config=ImuConfig(**SMALL, loop_split=(0.5, 0.45), n_jobs=1))


SUBSETS = [s for k in range(1, len(METHODS) + 1) for s in itertools.combinations(METHODS, k)]


@pytest.fixture(scope="module")
def every_method(record):
    """Two axes through every step, the study with every method."""
    axes = [a for a in resolve_axes(list(record.columns)) if a.column in ("gx_dps", "ax_mps2")]
    return run_imu(record.columns, axes, record.rate, "static_imu",
                   config=ImuConfig(**{**SMALL, "methods": METHODS}, n_jobs=1))


def _with_methods(result, methods):
    """``result`` as a run with only ``methods`` gives it: each fit is independent of the
    others, so the study of a subset is its rows of the study of all (checked below)."""
    config = replace(result.config, methods=methods)
    axes = []
    for a in result.axes:
        rows = a.study.rows[a.study.rows["method"].str.removesuffix("+level").isin(methods)]
        study = replace(a.study, rows=rows.reset_index(drop=True),
                        config=replace(a.study.config, methods=methods))
        axes.append(replace(a, study=study))
    return replace(result, config=config, axes=axes)


@pytest.mark.slow
def test_the_study_of_a_subset_of_methods_is_its_rows_of_the_study_of_all(every_method, record):
    from fosmodel.study.runner import run_study

    a = every_method.axes[1]
    config = ImuConfig(**{**SMALL, "methods": ("yw", "gm")})
    alone = run_study(record.columns[a.axis.column], config.study_config(record.rate, a.axis))
    pd.testing.assert_frame_equal(
        alone.rows.drop(columns="runtime_s"),
        _with_methods(every_method, ("yw", "gm")).axes[1].study.rows.drop(columns="runtime_s"))


@pytest.mark.parametrize("methods", SUBSETS, ids=",".join)
@pytest.mark.slow
def test_every_subset_of_methods_gives_the_tables_and_the_console(every_method, methods,
                                                                  tmp_path):
    result = _with_methods(every_method, methods)
    tables = write_imu_tables(result, tmp_path, "static imu")
    study = tables["study"][0]
    has_fos, has_base = "fos" in methods, bool(set(methods) - {"fos"})
    assert (study["FOS"] == "not studied").all() != has_fos
    assert (study["best baseline"] == "not studied").all() != has_base
    assert study["FOS outage error (m, 30 s)"].notna().all() == has_fos
    assert study["baseline outage error (m, 30 s)"].notna().all() == has_base
    ratio = study["FOS / baseline (outage)"]
    if has_fos and has_base:
        np.testing.assert_array_equal(ratio, study["FOS outage error (m, 30 s)"]
                                      / study["baseline outage error (m, 30 s)"])
    else:
        assert ratio.isna().all()
    assert pd.read_csv(tmp_path / "study.csv").shape == study.shape
    summary = console_summary(result).splitlines()
    gx = next(line for line in summary if line.split()[:1] == ["gx_dps"])
    fos_cell, base_cell = gx.split()[-6:-4]  # the gx_dps line's study columns
    assert (fos_cell == "-") != has_fos and (base_cell == "-") != has_base


@pytest.mark.parametrize("settings", [dict(train_s=180.0, evaluate_s=180.0),
                                      dict(train_s=20.0, evaluate_s=30.0, horizon_s=5.0),
                                      dict(train_s=20.0, evaluate_s=30.0, loop_split=(0.3, 0.3))])
def test_the_least_length_a_short_record_is_told_is_the_least_that_runs(settings):
    """The one message of a record too short gives the least length these settings take:
    a record of that many samples passes every step's check, one sample fewer does not."""
    import re

    axes = resolve_axes(["gx_dps"])
    config = ImuConfig(**SMALL, **settings)
    with pytest.raises(InputError) as error:
        config.check(6_000, 100.0, axes)
    message = str(error.value)
    assert message.startswith("the record has 6000 samples (60 s at 100 Hz), too short for "
                              "these settings, which need at least ")
    least = round(float(re.search(r"which need at least ([0-9.]+) s", message)[1]) * 100)
    config.check(least, 100.0, axes)
    with pytest.raises(InputError):
        config.check(least - 1, 100.0, axes)


def test_a_segment_too_short_for_its_windows_is_told_whatever_the_length():
    config = ImuConfig(**SMALL, train_s=4.0, evaluate_s=4.0)
    with pytest.raises(InputError, match=r"^the record has 6000 samples \(60 s at 100 Hz\), "
                                         r"too short for these settings: the study needs 68 s "
                                         r"\(.*\); the loop cannot run "
                                         r"with these settings, whatever the record's length "
                                         r"\(.*three outages of 5 s.*\); change train_s= and "
                                         r"evaluate_s= \(the loop's: loop_split=\) or "
                                         r"horizon_s=$"):
        config.check(6_000, 100.0, resolve_axes(["gx_dps"]))


@pytest.mark.slow
def test_the_loop_scores_on_the_study_s_prediction_segment_unless_given_its_own(result):
    """One split by default: an axis's study and loop errors are on one prediction segment."""
    for a in result.axes:
        assert a.loop.segments == a.study.split
    config = ImuConfig(**SMALL, loop_split=(0.5, 0.2)).for_record(60_000, 100.0)
    assert config.loop_split == (0.5, 0.2)
    assert ImuConfig(**SMALL).for_record(60_000, 100.0).loop_split == (0.3, 0.3)
