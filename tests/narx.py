"""Records from known NARX models, for recovery tests (a test helper, not a test module)."""

from __future__ import annotations

import numpy as np

from fosmodel.core.candidates import Term


def narx(truth: dict[str, float], n: int, exog: dict[str, np.ndarray], noise_sd: float,
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
