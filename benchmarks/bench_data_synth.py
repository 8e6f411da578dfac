"""Time the synthetic-record generator (plain script, not a test).

Run: ``python benchmarks/bench_data_synth.py [--repeat 3]``.  Prints, per
scenario, the best time to generate the record and to write its CSV + truth
sidecar.  The target of issue 3 is under 2 s to generate one hour at 200 Hz
(720,000 samples) for the paper scenarios.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from functools import partial
from pathlib import Path

from data_synth import make_scenario, write_record

CASES = [
    ("paper_accel_y", {}),
    ("paper_gyro_y", {}),
    ("undeclared_nonlinear", {"duration": 300.0, "rate": 200.0}),
    ("undeclared_nonlinear", {"duration": 3600.0, "rate": 200.0}),
    ("gyro_array_8", {}),
]


def best_of(repeat: int, fn):
    """Smallest wall time of ``repeat`` calls and the last result."""
    best, result = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"{'scenario':<22} {'values':>9} {'generate s':>11} {'write s':>9}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, kw in CASES:
            gen, rec = best_of(args.repeat, partial(make_scenario, name, seed=0, **kw))
            wrt, _ = best_of(args.repeat, partial(write_record, rec, Path(tmp) / "rec.csv"))
            n = rec.n_samples * len(rec.columns)
            print(f"{name:<22} {n:>9} {gen:>11.3f} {wrt:>9.3f}")


if __name__ == "__main__":
    main()
