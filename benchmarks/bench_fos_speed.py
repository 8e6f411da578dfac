"""FOS fit time against statsmodels' Burg and sysidentpy's FROLS, as ratios measured in one run.

The data are the paper's training window: 36,000 samples (3 minutes at 200 Hz)
of an AR-type signal.  Two signals are used: an AR(4) process (seed 000
models accelerometer errors as AR(4); the coefficients here are our choice),
and the first 3 minutes of the paper-like accelerometer record of
``data_synth``.  Each timing is the best of several interleaved repeats (these
machines are noisy); FOS is timed including candidate generation and the
full search.

FROLS runs on the identical candidate set (lags 1..L of y and their
products up to CP) and is asked for as many terms as FOS selected.  It is
given the signal minus its mean, which is what FOS works on (FOS always takes
the constant first; sysidentpy offers the constant as one more candidate and
does not centre).  The script prints the terms on which the two differ.

Run: ``python benchmarks/bench_fos_speed.py [--repeats R]``
"""

from __future__ import annotations

import argparse
import platform
import time
import warnings
from functools import partial

import numpy as np
from scipy.signal import lfilter
from statsmodels.regression.linear_model import burg

from data_synth import make_scenario
from fosmodel import FOSModel

N = 36_000
L = 10


def ar4_signal(seed: int = 0) -> np.ndarray:
    """AR(4) with weights 1.1, -0.15, -0.1, 0.05 (our choice; stable, real and complex roots)."""
    e = np.random.default_rng(seed).standard_normal(N + 2000)
    return lfilter([1.0], [1.0, -1.1, 0.15, 0.1, -0.05], e)[2000:]


def paper_signal(seed: int = 0) -> np.ndarray:
    rec = make_scenario("paper_accel_y", duration=N / 200.0, seed=seed)
    return rec.columns[rec.target]


def best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def frols_terms(y: np.ndarray, degree: int, n_terms: int) -> tuple[set[str], object]:
    """Fit sysidentpy's FROLS on the same candidates; return its terms in fosmodel's names."""
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    model = FROLS(ylag=L, order_selection=False, n_terms=n_terms, model_type="NAR",
                  basis_function=Polynomial(degree=degree), estimator=LeastSquares())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(y=y.reshape(-1, 1))
    names = set()
    for row in model.final_model:  # codes 1000 + lag for y[n-lag], 0 for "no factor"
        lags = sorted(int(c) - 1000 for c in row if c)
        if lags:
            parts = [f"y[n-{lag}]" for lag in sorted(set(lags))]
            powers = {lag: lags.count(lag) for lag in set(lags)}
            names.add("*".join(p if powers[int(p[4:-1])] == 1 else f"{p}^{powers[int(p[4:-1])]}"
                               for p in parts))
    return names, model


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {platform.python_version()}, "
          f"numpy {np.__version__}; N = {N}, L = {L}; best of {args.repeats}\n")
    header = (f"{'signal':<8} {'CP':>2} {'stop':<13} {'terms':>5} {'FOS ms':>8} {'Burg ms':>8} "
              f"{'FOS/Burg':>8} {'FROLS ms':>9} {'FROLS/FOS':>9} same terms")
    print(header)
    print("-" * len(header))
    for label, signal in (("AR(4)", ar4_signal()), ("paper", paper_signal())):
        for degree in (1, 2):
            for stop, max_terms in (("korenberg", None), ("max_terms", 10)):
                model = FOSModel(max_lag=L, degree=degree, stop=stop, max_terms=max_terms)
                fit_fos = partial(model.fit, signal)
                fit_burg = partial(burg, signal, L)
                fos_model = fit_fos()
                k = len(fos_model.terms_)
                t_fos = t_burg = np.inf
                for _ in range(args.repeats):  # interleave to share the machine's noise
                    t_fos = min(t_fos, best_time(fit_fos, 1))
                    t_burg = min(t_burg, best_time(fit_burg, 1))
                centred = signal - signal.mean()
                frols_names, _ = frols_terms(centred, degree, k)
                t_frols = best_time(partial(frols_terms, centred, degree, k),
                                    max(3, args.repeats // 5))
                only_fos = sorted(set(fos_model.terms_) - frols_names)
                only_frols = sorted(frols_names - set(fos_model.terms_))
                same = "yes" if not (only_fos or only_frols) else (
                    f"FOS only {only_fos}, FROLS only {only_frols}")
                print(f"{label:<8} {degree:>2} {stop:<13} {k:>5} {t_fos * 1e3:>8.3f} "
                      f"{t_burg * 1e3:>8.3f} {t_fos / t_burg:>8.2f} {t_frols * 1e3:>9.1f} "
                      f"{t_frols / t_fos:>9.0f} {same}")


if __name__ == "__main__":
    main()
