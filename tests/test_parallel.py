"""Independent calls in worker processes give what the same calls give here."""

import operator
import os
import subprocess
import sys

import pytest

from fosmodel.core.parallel import in_workers

CALLS = [(operator.pow, (base, 3)) for base in range(7)]
HERE = [base**3 for base in range(7)]


@pytest.mark.parametrize("n_jobs", [1, 2])
def test_results_come_in_the_calls_order(n_jobs):
    assert list(in_workers(iter(CALLS), n_jobs)) == HERE


def test_unordered_results_are_the_same_results():
    assert sorted(in_workers(CALLS, 2, ordered=False)) == HERE



_GROWING = """
import os, time
import numpy as np

HELD = []

def hold(megabytes):
    HELD.append(np.ones(megabytes * 131_072))   # kept, as imported libraries stay
    time.sleep(1.1)                             # loky checks memory at most once a second
    return os.getpid()
"""
_RUN = """
from fosmodel.core.parallel import in_workers
from growing import hold

if __name__ == "__main__":
    print(len(set(in_workers([(hold, (1,))] * 2 + [(hold, (400,))] * 4, 2))))
"""


@pytest.mark.slow
def test_a_worker_that_grows_is_kept_not_retired(tmp_path):
    # loky retires a worker 300 MB above its size after its first call, and a call given to
    # a worker retired so could wait for ever; run apart, so that a wait fails the test
    (tmp_path / "growing.py").write_text(_GROWING)
    (tmp_path / "run.py").write_text(_RUN)
    done = subprocess.run([sys.executable, "run.py"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120, check=True)
    assert int(done.stdout) <= 2


def test_a_call_runs_in_the_caller_s_directory(tmp_path, monkeypatch):
    # the workers outlive a call: those started here must follow the caller elsewhere
    assert list(in_workers(CALLS[:2], 2)) == HERE[:2]
    monkeypatch.chdir(tmp_path)
    assert set(in_workers([(os.getcwd, ())] * 4, 2)) == {str(tmp_path)}
