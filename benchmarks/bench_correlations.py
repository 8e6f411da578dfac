"""Korenberg's fast correlation path against the point-by-point reference, in one run.

``FOSModel(correlations="fast")`` (the default) gets every correlation the
search needs from tables of lagged-signal correlations with end corrections
(:class:`fosmodel.core.correlations.LagCorrelations`);
``FOSModel(correlations="reference")`` builds the N x C candidate matrix with
:func:`fosmodel.core.candidates.evaluate_terms` and runs the same kernel on it point
by point (:class:`fosmodel.core.fos.DataCorrelations`).  Both are timed through
``fit`` (``stop="max_terms"``), interleaved, best of ``--repeats`` loops; the script
checks that they select the same terms in the same order and that their
weights agree to 1e-8 relative to the largest weight (exit code 1 if not).

For reference it also times, on the matrix built beforehand (``build``, the
``evaluate_terms`` call), the public ``fosmodel.fos(X, y)`` on explicit data
(which must select the same terms too) both ways: ``precompute=False``
(``DataCorrelations``, one Gram column per step) and ``precompute=True``
(``_GramCorrelations``, the whole Gram matrix first).

The signals are those of ``bench_scaling.py``: an AR(4) process with a small
product of lags 1 and 3, and AR(1) exogenous channels that drive it.

Run: ``python benchmarks/bench_correlations.py [--repeats R] [--quick]``
"""

from __future__ import annotations

import argparse
import sys
from functools import partial

import numpy as np
from _common import interleaved_best, limit_blas, machine_line
from bench_scaling import make_signals

from fosmodel import FOSModel, fos
from fosmodel.core import CandidateSpec, center, evaluate_terms, generate_terms

TOL = 1e-8
FULL = [  # (N, L, CP, exogenous lags, k)
    (36_000, 10, 1, {}, 10),
    (36_000, 10, 2, {}, 10),
    (36_000, 20, 2, {}, 10),
    (36_000, 10, 2, {"x1": 10}, 10),
    (36_000, 50, 2, {}, 10),
    (100_000, 10, 2, {}, 10),
    (100_000, 20, 2, {}, 10),
    (300_000, 20, 2, {}, 10),
]
QUICK = [(20_000, 10, 1, {}, 10), (20_000, 10, 2, {}, 10), (20_000, 20, 2, {}, 10)]


def candidate_matrix(y, exog, lag, degree, exog_lags):
    """The reference path's N x C matrix, target and term names, from the centred signals."""
    spec = CandidateSpec(lag, degree, exog_lags)
    terms = [t for t in generate_terms(spec) if not t.is_constant]
    signals = {name: center(v)[0] for name, v in {"y": y, **exog}.items()}
    n0 = spec.lag_window
    return evaluate_terms(terms, signals, n0), signals["y"][n0:], [t.name for t in terms]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="smoke check: small N, 2 repeats")
    parser.add_argument("--blas-threads", type=int,
                        help="limit the BLAS threads (threadpoolctl); default: as the environment")
    args = parser.parse_args()
    limit = limit_blas(args.blas_threads)  # noqa: F841 - the limit holds while it is referenced
    repeats = 2 if args.quick else args.repeats
    print(machine_line())
    print(f"best of {repeats} interleaved rounds, each the mean of a loop of calls lasting at "
          "least 20 ms; stop='max_terms'\n")
    header = (f"{'N':>8} {'L':>3} {'CP':>2} {'exog':<6} {'cands':>5} {'k':>3} {'fast ms':>8} "
              f"{'ref ms':>9} {'ref/fast':>8} | {'build ms':>8} {'fos(X) ms':>9} "
              f"{'Gram ms':>8} | {'same terms':>10} {'coef rel diff':>13}")
    print(header)
    print("-" * len(header))
    ok = True
    ratios = []
    for n, lag, degree, exog_lags, k in QUICK if args.quick else FULL:
        y, exog = make_signals(n, exog_lags)
        ex = exog or None
        kw = dict(max_lag=lag, degree=degree, exog_lags=exog_lags or None, stop="max_terms",
                  max_terms=k)
        fast, ref = FOSModel(**kw), FOSModel(correlations="reference", **kw)
        fast.fit(y, ex)
        ref.fit(y, ex)
        X, target, names = candidate_matrix(y, exog, lag, degree, exog_lags)
        on_x = fos(X, target, stop="max_terms", max_terms=k, precompute=False)
        same = fast.terms_ == ref.terms_ == [names[i] for i in on_x.support]
        scale = float(np.max(np.abs(ref.coef_)))
        diff = (float(np.max(np.abs(fast.coef_ - ref.coef_))) / scale
                if fast.terms_ == ref.terms_ else np.inf)
        row_ok = same and diff <= TOL
        ok &= row_ok
        best = interleaved_best({
            "fast": partial(fast.fit, y, ex),
            "ref": partial(ref.fit, y, ex),
            "build": partial(candidate_matrix, y, exog, lag, degree, exog_lags),
            "fos_x": partial(fos, X, target, stop="max_terms", max_terms=k, precompute=False),
            "gram": partial(fos, X, target, stop="max_terms", max_terms=k, precompute=True),
        }, repeats)
        del X
        ratios.append(best["ref"] / best["fast"])
        exog_txt = ",".join(f"{c}:{v}" for c, v in exog_lags.items()) or "-"
        print(f"{n:>8} {lag:>3} {degree:>2} {exog_txt:<6} {fast.n_candidates_ - 1:>5} {k:>3} "
              f"{best['fast'] * 1e3:>8.1f} {best['ref'] * 1e3:>9.1f} {ratios[-1]:>8.1f} | "
              f"{best['build'] * 1e3:>8.1f} {best['fos_x'] * 1e3:>9.1f} "
              f"{best['gram'] * 1e3:>8.1f} | {'yes' if same else 'NO':>10} {diff:>13.1e}"
              f"{'' if row_ok else '  FAILED'}")
    print(f"\nreference / fast: {min(ratios):.3g} to {max(ratios):.3g}; "
          f"same terms and weights within {TOL:g}: {'all' if ok else 'NOT all'}")
    if not ok:
        sys.exit(1)


if __name__ == "__main__":
    main()
