"""Studies on a Dask cluster give the same numbers as in this process, runtime aside."""

import os
import pickle
import socket

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter
from threadpoolctl import threadpool_info

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.study import harness
from fosmodel.study.distributed import WORKER_ENV, connect_scheduler, local_client
from fosmodel.study.harness import StudyConfig, plan_study
from fosmodel.study.runner import run_studies, run_study

RATE = 10.0
CONFIG = StudyConfig(rate=RATE, sensor="accel", units="m/s^2", orders=(1, 2, 3), degrees=(1, 2),
                     train_s=300.0, evaluate_s=200.0, n_starts=5)


def _record(seed, n=9000, ar=(1.0, -0.9, 0.4)):
    return lfilter([1.0], list(ar), np.random.default_rng(seed).standard_normal(n)) * 1e-3


@pytest.fixture(scope="module")
def client():
    with local_client(2) as client:
        yield client


def _without_runtime(result):
    return result.rows.drop(columns="runtime_s")


@pytest.mark.slow
def test_cluster_gives_the_in_process_table(client):
    growing = 1e-3 * 1.0005 ** np.arange(9000) + 1e-3 * _record(2)  # unstable fits, notes
    plans = [plan_study(_record(1), CONFIG), plan_study(growing, CONFIG)]
    here = run_studies(plans)
    there = run_studies(plans, client=client)
    assert len(here) == len(there) == 2
    for a, b in zip(here, there):
        pd.testing.assert_frame_equal(_without_runtime(a), _without_runtime(b), check_exact=True)
        assert a.warnings == b.warnings and a.split == b.split
        assert (b.rows["runtime_s"] > 0).all()
    assert here[1].warnings  # the comparison covered the notes too
    single = run_study(_record(1), CONFIG, client=client)
    pd.testing.assert_frame_equal(_without_runtime(single), _without_runtime(here[0]),
                                  check_exact=True)


def test_fos_is_one_task_for_both_protocols():
    plan = plan_study(_record(1), CONFIG)
    n_fos, n_ar = len(CONFIG.orders) * len(CONFIG.degrees), 3 * len(CONFIG.orders)
    n_taus = len(plan.level_taus)
    # baselines (and gm) per protocol; about the level (fair only) FOS once and the
    # baselines once per level time constant
    n_level = n_fos + n_taus * (n_ar + 1)
    assert n_taus == 4 and len(plan.tasks) == n_fos + 2 * (n_ar + 1) + n_level
    assert set(plan.signals) == {None, "wavelet"}
    result = harness.assemble(plan, [harness.run_task(plan, task) for task in plan.tasks])
    assert len(result.rows) == 2 * (n_fos + n_ar + 1) + n_level
    fos = result.rows[result.rows["method"] == "fos"]
    assert (fos.groupby(["order", "degree"])["runtime_s"].nunique() == 1).all()
    with pytest.raises(ValueError, match="1 scores for"):
        harness.assemble(plan, [harness.run_task(plan, plan.tasks[0])])


def _at_odd_offset(buffer):
    """The bytes of ``buffer`` at an address that is not 8-byte aligned."""
    data = bytearray(buffer.raw().nbytes + 4)
    data[4:] = buffer.raw()
    return memoryview(data)[4:]


def test_unpickled_plan_has_aligned_signals_and_gives_the_same_rows():
    """Dask hands arrays over in buffers at any offset; numpy sums unaligned ones differently."""
    plan = plan_study(_record(1), CONFIG)
    buffers = []
    data = pickle.dumps(plan, protocol=5, buffer_callback=buffers.append)
    back = pickle.loads(data, buffers=[_at_odd_offset(b) for b in buffers])
    assert buffers and all(a.flags.aligned for pair in back.signals.values() for a in pair)
    for task in plan.tasks[::5]:
        here, there = harness.run_task(plan, task).row, harness.run_task(back, task).row
        assert {**here, "runtime_s": 0} == {**there, "runtime_s": 0}


def _blas_threads():
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


class _ThreadSpy:
    """A Gauss-Markov model that records how many BLAS threads its fit may use."""

    threads: list = []

    def __init__(self, *args, **kwargs):
        self.model = harness.make_baseline("gm", 1, rate=RATE)

    def fit(self, y):
        _ThreadSpy.threads.append(_blas_threads())
        self.model.fit(y)
        return self

    def __getattr__(self, name):
        return getattr(self.model, name)


def _worker_env():
    return {name: os.environ.get(name) for name in WORKER_ENV}


def test_each_fit_uses_one_blas_thread(client, monkeypatch):
    assert all(set(t) == {1} for t in client.run(_blas_threads).values())
    expected = {k: str(v) if v is not None else os.environ.get(k) for k, v in WORKER_ENV.items()}
    assert all(env == expected for env in client.run(_worker_env).values())
    _ThreadSpy.threads = []
    monkeypatch.setattr(harness, "make_model", _ThreadSpy)
    run_study(_record(1), StudyConfig(**{**CONFIG.__dict__, "methods": ("gm",)}))
    assert _ThreadSpy.threads and all(set(t) == {1} for t in _ThreadSpy.threads)


def _closed_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_scheduler_is_an_input_error():
    address = f"tcp://127.0.0.1:{_closed_port()}"
    with pytest.raises(InputError, match=f"cannot connect to the Dask scheduler at {address}"):
        connect_scheduler(address, timeout=1.0)
    with pytest.raises(InputError, match="cannot connect"):
        connect_scheduler("no-port-here", timeout=1.0)


@pytest.fixture(scope="module")
def two_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("records")
    paths = [folder / "imu1.csv", folder / "imu2.csv"]
    for seed, path in enumerate(paths):
        pd.DataFrame({"time": np.arange(9000) / RATE, "ax": _record(seed)}).to_csv(path,
                                                                                  index=False)
    return paths


def _study(files, out, *extra):
    args = ["study", *files, "--columns", "ax", "--sensor", "accel", "--units", "m/s^2",
            "--orders", "1-2", "--degrees", "1", "--protocol", "fair", "--split", "300s,200s",
            "--starts", "5", "--out", out, *extra]
    return cli.main([str(a) for a in args])


def _tables(out):
    return {p.relative_to(out): pd.read_csv(p).drop(columns="Fit time (s)", errors="ignore")
            for p in sorted(out.rglob("*.csv"))}


@pytest.fixture(scope="module")
def tables_here(two_files, tmp_path_factory):
    out = tmp_path_factory.mktemp("here")
    assert _study(two_files, out) == 0
    return _tables(out)


@pytest.mark.parametrize("how", ["--workers", "--scheduler"])
@pytest.mark.slow
def test_cli_on_a_cluster_writes_the_in_process_tables(two_files, tables_here, tmp_path, client,
                                                       capsys, how):
    there = ["--workers", "2"] if how == "--workers" else ["--scheduler", client.scheduler.address]
    assert _study(two_files, tmp_path / "out", *there) == 0, capsys.readouterr().err
    tables = _tables(tmp_path / "out")
    assert len(tables) == 1 + 2 * 4 and tables.keys() == tables_here.keys()
    for name, table in tables_here.items():
        pd.testing.assert_frame_equal(table, tables[name], check_exact=True)
