"""Time the synthetic-record generator (plain script, not a test).

Run: ``python benchmarks/bench_data_synth.py [--repeat 3]``.  Prints, per
scenario, the best time to generate the record (all its sessions) and to write
its CSV + truth sidecars.  The targets: under 2 s to generate one hour at 200 Hz
(720,000 samples) for the paper scenarios, and well under a second per day-long
1 Hz six-axis session.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from functools import partial
from pathlib import Path

from data_synth import make_sessions, write_sessions

CASES = [
    ("paper_accel_y", {}),
    ("paper_gyro_y", {}),
    ("undeclared_nonlinear", {"duration": 300.0, "rate": 200.0}),
    ("undeclared_nonlinear", {"duration": 3600.0, "rate": 200.0}),
    ("gyro_array_8", {}),
    ("temperature_sweep", {}),
    ("temperature_sessions", {}),
    ("companion_noise", {}),
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
            gen, recs = best_of(args.repeat, partial(make_sessions, name, seed=0, **kw))
            wrt, _ = best_of(args.repeat, partial(write_sessions, recs, Path(tmp) / "rec.csv"))
            n = sum(rec.n_samples * len(rec.columns) for rec in recs)
            print(f"{name:<22} {n:>9} {gen:>11.3f} {wrt:>9.3f}")


if __name__ == "__main__":
    main()
