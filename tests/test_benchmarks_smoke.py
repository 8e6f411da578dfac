"""The benchmarks still run: ``bench_correlations.py --quick`` end to end (no timing asserted).

It exits non-zero if the fast correlation path and the point-by-point reference
select different terms or weights that differ by more than 1e-8.  The other
scripts' ``--quick`` runs take longer than this suite allows (run them by hand).
"""

import os
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def test_bench_correlations_quick_runs_and_agrees():
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, str(BENCH / "bench_correlations.py"), "--quick"],
                         capture_output=True, text=True, env=env, timeout=120, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "same terms and weights within 1e-08: all" in out.stdout
    assert out.stdout.count(" yes ") == 3
