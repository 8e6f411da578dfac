"""Fixtures shared by several test modules: NARX records of known terms, small record files."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fosmodel.core.candidates import Term


def _simulate_narx(truth: dict[str, float], n: int, exog: dict[str, np.ndarray], noise_sd: float,
                   seed: int, burn: int = 500) -> tuple[np.ndarray, float]:
    """Simulate ``y[n] = sum_m c_m P_m[n] + e[n]`` in raw coordinates; return y and its SNR in dB.

    ``truth`` maps term names (``"1"`` for the constant) to weights; the SNR is
    the variance of the model part over the variance of the equation error e.
    """
    rng = np.random.default_rng(seed)
    terms = [(Term.parse(k), v) for k, v in truth.items()]
    e = noise_sd * rng.standard_normal(n + burn)
    sig = {k: np.r_[np.zeros(burn), v] for k, v in exog.items()}
    y = np.zeros(n + burn)
    start = 1 + max(lag or 0 for t, _ in terms for _, lag in t.factors)
    for i in range(start, n + burn):
        v = e[i]
        for term, c in terms:
            for ch, lag in term.factors:
                c *= (y if ch == "y" else sig[ch])[i - (lag or 0)]
            v += c
        y[i] = v
    if not np.all(np.abs(y) < 1e6):
        raise RuntimeError("the NARX design diverged")
    model_part = y[burn:] - e[burn:]
    return y[burn:], float(10 * np.log10(np.var(model_part) / noise_sd**2))


@pytest.fixture
def narx() -> Callable[..., tuple[np.ndarray, float]]:
    """The simulator of records from known NARX models, for recovery tests.

    ``narx(truth, n, exog, noise_sd, seed, burn=500)`` returns the record and its SNR in dB.
    """
    return _simulate_narx


@pytest.fixture
def bursty_csv(tmp_path: Path) -> Callable[..., tuple[Path, float]]:
    """A writer of ``bursty.csv`` in the test's ``tmp_path``: 100 Hz samples received by a host
    in bursts of 5, 1 ms apart, every 50 ms.

    ``bursty_csv(n=400)`` returns the file and its effective rate in Hz.
    """
    def write(n: int = 400) -> tuple[Path, float]:
        k = np.arange(n)
        t = 0.05 * (k // 5) + 0.001 * (k % 5)
        rng = np.random.default_rng(3)
        path = tmp_path / "bursty.csv"
        pd.DataFrame({"t_s": t, "gx": rng.normal(size=n)}).to_csv(path, index=False)
        return path, (n - 1) / (t[-1] - t[0])

    return write


@pytest.fixture
def spiky_csv(tmp_path: Path) -> Callable[..., tuple[Path, np.ndarray, np.ndarray]]:
    """A writer of ``s.csv`` in the test's ``tmp_path``: columns a and b of 1000 normal samples
    with outliers at a[100], a[700] and b[700].

    ``spiky_csv(with_time)`` (a ``time`` column at 100 Hz first when true) returns the file
    and the columns a and b.
    """
    def write(with_time: bool) -> tuple[Path, np.ndarray, np.ndarray]:
        rng = np.random.default_rng(5)
        a, b = rng.normal(size=1000), rng.normal(size=1000)
        a[100], a[700], b[700] = 50.0, -60.0, 40.0
        frame = pd.DataFrame({"a": a, "b": b})
        if with_time:
            frame.insert(0, "time", np.arange(1000) / 100)
        frame.to_csv(tmp_path / "s.csv", index=False)
        return tmp_path / "s.csv", a, b

    return write
