"""The benchmarks still run: ``bench_correlations.py --quick`` end to end (no timing asserted).

It exits non-zero if the fast correlation path and the point-by-point reference
select different terms or weights that differ by more than 1e-8.  The other
scripts' ``--quick`` runs take longer than this suite allows (run them by hand);
``bench_distributed.py``'s study is checked to be the one it says it times.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.mark.slow
def test_bench_correlations_quick_runs_and_agrees():
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, str(BENCH / "bench_correlations.py"), "--quick"],
                         capture_output=True, text=True, env=env, timeout=120, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "same terms and weights within 1e-08: all" in out.stdout
    assert out.stdout.count(" yes ") == 3


def test_bench_distributed_plans_the_40_fit_study_it_describes():
    # the study's defaults grew models about the level (152 fits); the benchmark keeps its own
    sys.path.insert(0, str(BENCH))
    try:
        import bench_distributed
    finally:
        sys.path.remove(str(BENCH))
    plan = bench_distributed.make_plan(2500.0)
    assert len(plan.tasks) == 40
    assert {task.method for task in plan.tasks} == {"fos", "yw", "cov", "burg"}
    assert {task.level_tau for task in plan.tasks} == {None}
