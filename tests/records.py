"""Small record files for loader and command-line tests (a test helper, not a test module)."""

import numpy as np
import pandas as pd


def bursty_csv(tmp_path, n=400):
    """100 Hz samples received by a host in bursts of 5, 1 ms apart, every 50 ms."""
    k = np.arange(n)
    t = 0.05 * (k // 5) + 0.001 * (k % 5)
    rng = np.random.default_rng(3)
    path = tmp_path / "bursty.csv"
    pd.DataFrame({"t_s": t, "gx": rng.normal(size=n)}).to_csv(path, index=False)
    return path, (n - 1) / (t[-1] - t[0])


def spiky_csv(tmp_path, with_time):
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=1000), rng.normal(size=1000)
    a[100], a[700], b[700] = 50.0, -60.0, 40.0
    frame = pd.DataFrame({"a": a, "b": b})
    if with_time:
        frame.insert(0, "time", np.arange(1000) / 100)
    frame.to_csv(tmp_path / "s.csv", index=False)
    return tmp_path / "s.csv", a, b
