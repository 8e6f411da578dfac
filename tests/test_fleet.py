"""A fleet of records: the same summary in this process and on Dask; a rerun resumes."""

from __future__ import annotations

import itertools
import json
import shutil

import pandas as pd
import pytest
from threadpoolctl import threadpool_limits

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.io.loader import load_record
from fosmodel.io.split import SplitSpec
from fosmodel.noise.axes import resolve_axes
from fosmodel.study.harness import METHODS
from fosmodel.workflows.fleet import MARKER, FleetConfig, record_name, run_fleet
from fosmodel.workflows.imu import STEPS, ImuConfig, run_imu

SMALL = ImuConfig(orders=(1, 2), degrees=(1,), methods=("fos", "burg"), n_starts=5)
CONFIG = FleetConfig(imu=SMALL, split=SplitSpec.parse("50%,25%"))
NAMES = ["imu0", "imu1", "imu2"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Three short six-axis sessions (100 Hz, 4 minutes), as CSV."""
    from data_synth import make_scenario, write_record

    folder = tmp_path_factory.mktemp("fleet")
    paths = []
    for seed, name in enumerate(NAMES):
        write_record(make_scenario("static_imu", duration=240.0, seed=seed),
                     folder / f"{name}.csv")
        paths.append(folder / f"{name}.csv")
    return paths


@pytest.fixture(scope="module")
def here(files, tmp_path_factory):
    store = tmp_path_factory.mktemp("here")
    return store, run_fleet(files, store, CONFIG)


@pytest.mark.slow
def test_a_row_per_record_and_axis_and_a_folder_per_record(here):
    store, result = here
    axes = ["gx_dps", "gy_dps", "gz_dps", "ax_mps2", "ay_mps2", "az_mps2"]
    assert list(result.table["record"]) == [n for n in NAMES for _ in axes]
    assert list(result.table["axis"]) == axes * 3
    assert {"N fitted", "FOS outage error (m, 30 s)", "effects kept"} <= set(result.table)
    assert result.ran == NAMES and result.skipped == []
    pd.testing.assert_frame_equal(pd.read_csv(store / "fleet.csv"), result.table)
    for name in NAMES:
        marker = json.loads((store / name / MARKER).read_text())
        assert marker["steps"] == list(STEPS) and marker["n_samples"] == 24_000
        assert result.seconds[name] == marker["seconds"]["total"]


def test_the_rows_are_the_six_axis_workflow_on_the_record(here, files):
    """A record's rows are what run_imu gives on it (one BLAS thread, as the fleet's tasks)."""
    rec = load_record(files[1])
    axes = resolve_axes(rec.names, declared=rec.units)
    columns = {a.column: rec.column(a.column) for a in axes}
    with threadpool_limits(limits=1, user_api="blas"):
        alone = run_imu(columns, axes, 100.0, config=ImuConfig(
            orders=(1, 2), degrees=(1,), methods=("fos", "burg"), n_starts=5, n_jobs=1,
            train_s=120.0, evaluate_s=60.0))
    rows = here[1].table[here[1].table["record"] == "imu1"].reset_index(drop=True)
    for table in (alone.study_table(), alone.loop_table()):
        for column in table.columns.drop(["axis", "units"]):  # NaN equals NaN here
            pd.testing.assert_series_equal(rows[column], table[column], check_names=False,
                                           check_dtype=False, obj=column)


@pytest.mark.slow
def test_two_dask_workers_give_the_same_summary(here, files, tmp_path):
    from fosmodel.study.distributed import local_client

    with local_client(2) as client:
        result = run_fleet(files, tmp_path, CONFIG, client=client)
    pd.testing.assert_frame_equal(result.table, here[1].table)
    assert sorted(result.ran) == NAMES


@pytest.mark.slow
def test_a_rerun_redoes_only_the_record_whose_marker_is_missing(here, files, tmp_path):
    shutil.copytree(here[0], tmp_path, dirs_exist_ok=True)  # copy2 keeps the times
    stamps = {n: (tmp_path / n / MARKER).stat().st_mtime_ns for n in NAMES}
    (tmp_path / "imu1" / MARKER).unlink()  # as if the run stopped before imu1 was published
    again = run_fleet(files, tmp_path, CONFIG)
    assert again.ran == ["imu1"] and again.skipped == ["imu0", "imu2"]
    assert {n: (tmp_path / n / MARKER).stat().st_mtime_ns for n in ("imu0", "imu2")} == \
        {n: stamps[n] for n in ("imu0", "imu2")}
    pd.testing.assert_frame_equal(again.table, here[1].table)
    other_steps = run_fleet(files, tmp_path, FleetConfig(imu=SMALL, steps=("allan",)))
    assert other_steps.ran == NAMES  # another configuration: every record again
    assert list(other_steps.table.columns) == ["record", "axis", "sensor", "units", "N fitted",
                                               "B fitted", "K fitted"]


@pytest.mark.slow
def test_a_failed_record_is_named_after_the_others_are_stored(files, tmp_path):
    bad = tmp_path / "imu9.csv"
    bad.write_text("gx_dps,ax_mps2\n0.1,oops\n")
    with pytest.raises(InputError) as error:
        run_fleet([*files, bad], tmp_path / "store", FleetConfig(imu=SMALL, steps=("allan",)))
    message = str(error.value)
    assert message.startswith("record imu9: ") and message.endswith(
        f"(1 of 4 records failed; the other 3 are stored in {tmp_path / 'store'}, and a rerun "
        "does only the failed)")
    assert all((tmp_path / "store" / n / MARKER).is_file() for n in NAMES)
    assert not (tmp_path / "store" / "imu9").exists() and not (tmp_path / "store" /
                                                                 "fleet.csv").exists()
    bad.write_bytes(files[0].read_bytes())  # the record mended
    again = run_fleet([*files, bad], tmp_path / "store", FleetConfig(imu=SMALL, steps=("allan",)))
    assert again.ran == ["imu9"] and again.skipped == NAMES


def test_a_fleet_refused_whole_leaves_no_store(tmp_path, capsys):
    """A refused record leaves no folder and no marker; with no record stored, no store."""
    bad = tmp_path / "imu9.csv"
    bad.write_text("gx_dps,ax_mps2\n0.1,oops\n")
    argv = ["fleet", str(bad), "--steps", "allan", "--out", str(tmp_path / "a" / "store")]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("fosmodel: error: record imu9: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["imu9.csv"]


def test_the_reports_of_a_chosen_step_on_a_chosen_axis(files, tmp_path):
    result = run_fleet(files[:1], tmp_path, FleetConfig(imu=SMALL, steps=("allan",),
                                                        columns=("gz_dps",), reports=True))
    assert list(result.table["axis"]) == ["gz_dps"]
    assert {p.name for p in (tmp_path / "imu0" / "report" / "noise").iterdir()} >= {
        "imu_noise.json", "allan_gyro.png", "noise.md"}


@pytest.mark.parametrize("bad, message", [
    (dict(files=[]), "no record in the fleet"),
    (dict(files=["no/such/imu1.csv"]), "no/such/imu1.csv: no such file"),
    (dict(files=["imu1.csv", "imu1.csv.gz"]),
     "two records named 'imu1' (imu1.csv and imu1.csv.gz): the store keeps a folder per "
     "name; rename one"),
    (dict(steps=("allan", "fit")), "unknown step 'fit'; the steps are allan, study, loop"),
])
def test_refusals(bad, message, files, tmp_path, monkeypatch):
    monkeypatch.chdir(files[0].parent)  # where imu1.csv is
    (files[0].parent / "imu1.csv.gz").write_bytes(b"")
    config = FleetConfig(steps=bad.get("steps", STEPS))
    with pytest.raises(InputError) as error:
        run_fleet(bad.get("files", files), tmp_path / "store", config)
    assert str(error.value) == message
    assert not (tmp_path / "store").exists()


@pytest.mark.parametrize("path, name", [("d/imu1.csv.gz", "imu1"), ("s.v2.parquet", "s.v2"),
                                        ("bag_2024", "bag_2024"), ("x.npy", "x")])
def test_record_name(path, name):
    assert record_name(path) == name


def test_the_command_runs_and_resumes(files, tmp_path, capsys):
    args = ["fleet", *map(str, files), "--steps", "allan", "--out", str(tmp_path / "store")]
    assert cli.main(args) == 0
    assert cli.main(args) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("fleet of 3 records: 3 run, 0 already in the store; 18 rows")
    assert out[1].startswith("fleet of 3 records: 0 run, 3 already in the store; 18 rows")
    assert cli.main(["fleet", str(files[0]), "--steps", "allan,fit", "--out",
                     str(tmp_path / "x")]) == 2
    assert capsys.readouterr().err.strip() == ("fosmodel: error: unknown step 'fit'; the steps "
                                               "are allan, study, loop")


def test_a_split_too_long_for_a_record_is_refused_by_name(files, tmp_path):
    config = FleetConfig(imu=SMALL, split=SplitSpec.parse("150s,60s"))
    with pytest.raises(InputError) as error:
        run_fleet(files[:1], tmp_path, config)
    message = str(error.value)
    assert message.startswith(
        "record imu0: the record has 24000 samples (240 s at 100 Hz), too short for these "
        "settings, which need at least 270 s: the study needs 270 s (the split 150 s / 60 s "
        "leaves 3000 samples to predict, 6000 are needed (a 30 s outage horizon and two 30 s "
        "bias windows)); the loop needs 270 s (")
    assert message.endswith("shorten train_s= and evaluate_s= (the loop's: loop_split=) or "
                            "horizon_s=, or give a longer record (1 of 1 records failed)")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_the_full_report_of_a_record_has_every_axis_timed(files, tmp_path):
    result = run_fleet(files[:1], tmp_path, FleetConfig(imu=SMALL, split=CONFIG.split,
                                                        columns=("gx_dps", "ax_mps2"),
                                                        reports=True))
    report = tmp_path / "imu0" / "report"
    assert {"noise", "study", "loop", "models", "filter"} <= {p.name for p in report.iterdir()}
    timing = pd.read_csv(report / "timing.csv")
    assert list(timing["axis"]) == ["gx_dps", "ax_mps2"]
    assert (timing[["study (s)", "loop (s)"]] > 0).all().all()
    marker = json.loads((tmp_path / "imu0" / MARKER).read_text())["seconds"]
    assert marker["study"] == pytest.approx(timing["study (s)"].sum(), abs=0.02)
    assert list(result.table["axis"]) == ["gx_dps", "ax_mps2"]


@pytest.mark.slow
def test_the_command_on_a_running_scheduler_gives_the_in_process_summary(files, tmp_path):
    from distributed import get_task_stream

    from fosmodel.study.distributed import local_client

    args = ["fleet", *map(str, files), "--steps", "allan"]
    assert cli.main([*args, "--out", str(tmp_path / "here")]) == 0
    with local_client(1) as client, get_task_stream(client) as tasks:  # a cluster already up
        assert cli.main([*args, "--out", str(tmp_path / "there"), "--scheduler",
                         client.scheduler.address]) == 0
        assert client.scheduler_info()["workers"]  # still up: the command only connected
    assert len(tasks.data) == len(files)  # a task per record, run there
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "there" / "fleet.csv"),
                                  pd.read_csv(tmp_path / "here" / "fleet.csv"))


SUBSETS = [s for k in range(1, len(METHODS) + 1) for s in itertools.combinations(METHODS, k)]


@pytest.mark.parametrize("methods", SUBSETS, ids=",".join)
def test_the_study_step_takes_every_subset_of_methods(methods, files, tmp_path, capsys):
    store = tmp_path / "store"
    assert cli.main(["fleet", str(files[0]), "--columns", "gx_dps,ax_mps2", "--orders", "1",
                     "--degrees", "1", "--methods", ",".join(methods), "--steps", "study",
                     "--split", "50%,25%", "--out", str(store)]) == 0, capsys.readouterr().err
    table = pd.read_csv(store / "fleet.csv", keep_default_na=False, na_values=[""])
    assert list(table["axis"]) == ["gx_dps", "ax_mps2"]
    assert (table["FOS"] == "not studied").all() != ("fos" in methods)
    assert (table["best baseline"] == "not studied").all() != bool(set(methods) - {"fos"})
    assert table["FOS / baseline (outage)"].notna().all() == (
        "fos" in methods and len(methods) > 1)


def test_a_refused_fleet_leaves_no_store_behind(files, tmp_path):
    config = FleetConfig(imu=SMALL, split=SplitSpec.parse("150s,60s"))
    with pytest.raises(InputError, match="^record imu0: the record has 24000 samples"):
        run_fleet(files[:1], tmp_path / "store", config)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_says_which_records_are_kept(files, tmp_path, monkeypatch, capsys):
    """Interrupted between records, fleet says which finished records are on disk (a rerun
    skips them) and exits 130: the code and the message agree with what is there."""
    import fosmodel.workflows.fleet as fleet_module

    store = tmp_path / "store"

    def interrupted(paths, out, config, **kwargs):
        (out / "imu0").mkdir(parents=True)
        (out / "imu0" / MARKER).write_text("{}")
        raise KeyboardInterrupt

    monkeypatch.setattr(fleet_module, "run_fleet", interrupted)
    code = cli.main(["fleet", *map(str, files), "--out", str(store)])
    err = capsys.readouterr().err
    assert code == 130
    assert err == (f"fosmodel: interrupted; 1 of 3 records finished and kept in "
                   f"{store.resolve()}/ (imu0): a rerun skips them\n")
