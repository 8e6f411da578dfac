"""FOS fit time against statsmodels' Burg, sysidentpy's FROLS and scikit-learn's OMP, in one run.

The data are the paper's training window: 36,000 samples (3 minutes at 200 Hz)
of an AR-type signal.  Two signals are used: an AR(4) process (seed 000
models accelerometer errors as AR(4); the coefficients here are our choice),
and the first 3 minutes of the paper-like accelerometer record of
``data_synth``.  Every time is the best of several rounds, interleaved with
the times it is compared with (these machines are noisy); in each round a
function runs in a loop of consecutive calls lasting at least 20 ms and its
time is the loop's mean, as ``timeit`` does (a single fast call right after
FROLS would pay for the caches and fresh pages FROLS left behind).  FOS is always timed
through ``FOSModel(...).fit``: candidate generation, correlations, search and
coefficients.

Table 1, FOS against Burg at the same order L = 1, 5, 10, 20.  Burg
(``statsmodels.regression.linear_model.burg(y, L)``) has no cross-products,
so FOS with CP = 1 and CP = 2 at lag L are both set against Burg at order L.
FOS runs with its default stopping rule (``korenberg``) and at full order
(``max_terms = L``: as many weights as Burg estimates).  ``FOS ms`` is a fit
of a candidate set fitted before in the process (the usual case in a study:
the same orders on many records); ``1st ms`` is the first fit of a candidate
set, which also plans its correlation tables (``fosmodel.core.shapes.layout`` and
``direct_groups``, cached per candidate set like an FFT plan).

Table 2, FOS against FROLS (sysidentpy) on the identical candidate set (lags
1..L of y and their products up to CP), asked for the k terms FOS selects
(``k`` from FOS's ``korenberg`` rule, or fixed at 10); FOS is timed with
``stop="max_terms", max_terms=k``.  FROLS is given the signal minus its mean,
which is what FOS works on (FOS always takes the constant first; sysidentpy
offers the constant as one more candidate and does not centre; when it takes
it, it shows as the term ``1``).  The table lists the terms on which the two
differ.

Table 3, FOS against orthogonal matching pursuit (scikit-learn) on the same
candidates, as an explicit matrix: ``fosmodel.core.candidates.evaluate_terms`` on
the centred signal, columns centred and scaled to unit norm (OMP assumes unit
norm), then ``OrthogonalMatchingPursuit(n_nonzero_coefs=k,
fit_intercept=True)`` (its default ``precompute="auto"`` forms the Gram
matrix here, since N > C), and ``orthogonal_mp_gram`` on a Gram matrix and
``X^T y`` computed beforehand (the fastest sklearn path).  Times: ``build``
= the candidate matrix (generation, evaluation, centring, scaling),
``OMP`` = the estimator's fit on a built matrix, ``Gram`` = ``X^T X`` and
``X^T y``, ``mp_gram`` = ``orthogonal_mp_gram`` alone, ``FOS(X)`` =
``fosmodel.fos`` on the same built matrix.  OMP picks the candidate most
correlated with the residual, FOS the one whose orthogonal part lowers the
MSE most (Korenberg's Q); ``common`` counts the selected terms they share.

Run: ``python benchmarks/bench_fos_speed.py [--repeats R] [--quick]``
"""

from __future__ import annotations

import argparse
import warnings
from functools import partial

import numpy as np
from _common import interleaved_best, limit_blas, machine_line
from scipy.signal import lfilter
from sklearn.linear_model import OrthogonalMatchingPursuit, orthogonal_mp_gram
from statsmodels.regression.linear_model import burg

from data_synth import make_scenario
from fosmodel import FOSModel, fos
from fosmodel.core import CandidateSpec, center, clear_plans, evaluate_terms, generate_terms

N = 36_000


def ar4_signal(seed: int = 0) -> np.ndarray:
    """AR(4) with weights 1.1, -0.15, -0.1, 0.05 (our choice; stable, real and complex roots)."""
    e = np.random.default_rng(seed).standard_normal(N + 2000)
    return lfilter([1.0], [1.0, -1.1, 0.15, 0.1, -0.05], e)[2000:]


def paper_signal(seed: int = 0) -> np.ndarray:
    rec = make_scenario("paper_accel_y", duration=N / 200.0, seed=seed)
    return rec.columns[rec.target]


def frols_terms(y: np.ndarray, lag: int, degree: int, n_terms: int) -> set[str]:
    """Fit sysidentpy's FROLS on lags 1..lag of y up to ``degree``; its terms, in our names."""
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    model = FROLS(ylag=lag, order_selection=False, n_terms=n_terms, model_type="NAR",
                  basis_function=Polynomial(degree=degree), estimator=LeastSquares())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(y=y.reshape(-1, 1))
    names = set()
    for row in model.final_model:  # codes 1000 + lag for y[n-lag], 0 for "no factor"
        lags = sorted(int(c) - 1000 for c in row if c)
        powers = {k: lags.count(k) for k in lags}
        names.add("*".join(f"y[n-{k}]" if p == 1 else f"y[n-{k}]^{p}"
                           for k, p in sorted(powers.items())) or "1")
    return names


def omp_matrix(y: np.ndarray, lag: int, degree: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The candidate matrix FOS searches, centred and with unit-norm columns, and the target."""
    terms = [t for t in generate_terms(CandidateSpec(lag, degree)) if not t.is_constant]
    yc, _ = center(y)
    X = evaluate_terms(terms, {"y": yc}, lag)
    X -= X.mean(axis=0)
    X /= np.linalg.norm(X, axis=0)
    return X, yc[lag:], [t.name for t in terms]


def cold_fit(model: FOSModel, signal: np.ndarray) -> None:
    """Fit as the first fit of its candidate set in the process (no cached layout)."""
    clear_plans()
    model.fit(signal)


def burg_table(signals: dict, lags, repeats: int) -> list[float]:
    print("Table 1. FOS against Burg at the same order L (Burg has no cross-products)")
    header = (f"{'signal':<7} {'L':>3} {'CP':>2} {'cands':>5} {'stop':<14} {'terms':>5} "
              f"{'FOS ms':>8} {'1st ms':>8} {'Burg ms':>8} {'FOS/Burg':>8} {'1st/Burg':>8}")
    print(header)
    print("-" * len(header))
    ratios = []
    for label, signal in signals.items():
        for lag in lags:
            for degree in (1, 2):
                for stop, max_terms in (("korenberg", None), ("max_terms", lag)):
                    model = FOSModel(max_lag=lag, degree=degree, stop=stop, max_terms=max_terms)
                    k = len(model.fit(signal).terms_)
                    best = interleaved_best({"fos": partial(model.fit, signal),
                                             "first": partial(cold_fit, model, signal),
                                             "burg": partial(burg, signal, lag)}, repeats)
                    ratio, first = best["fos"] / best["burg"], best["first"] / best["burg"]
                    ratios.append(ratio)
                    rule = stop if max_terms is None else f"max_terms={max_terms}"
                    print(f"{label:<7} {lag:>3} {degree:>2} {model.n_candidates_ - 1:>5} "
                          f"{rule:<14} {k:>5} {best['fos'] * 1e3:>8.2f} "
                          f"{best['first'] * 1e3:>8.2f} {best['burg'] * 1e3:>8.2f} "
                          f"{ratio:>8.2f} {first:>8.2f}")
    return ratios


def selection_rows(signals: dict, lags, degrees, k_rules, repeats: int, frols_repeats: int):
    """Time FOS, FROLS and the OMP paths per configuration; return one dict per row."""
    rows = []
    for label, signal in signals.items():
        centred = signal - signal.mean()
        for lag in lags:
            for degree in degrees:
                for k_rule in k_rules:
                    if k_rule == "korenberg":
                        k = len(FOSModel(max_lag=lag, degree=degree).fit(signal).terms_)
                    else:
                        k = int(k_rule)
                    model = FOSModel(max_lag=lag, degree=degree, stop="max_terms", max_terms=k)
                    fos_terms = model.fit(signal).terms_
                    X, target, names = omp_matrix(signal, lag, degree)
                    omp = OrthogonalMatchingPursuit(n_nonzero_coefs=k, fit_intercept=True)
                    omp_terms = {names[i] for i in np.flatnonzero(omp.fit(X, target).coef_)}
                    gram, xy = X.T @ X, X.T @ target
                    mp_coef = orthogonal_mp_gram(gram, xy, n_nonzero_coefs=k)
                    mp_terms = {names[i] for i in np.flatnonzero(mp_coef)}
                    on_x = fos(X, target, max_terms=k, stop="max_terms")
                    fos_x = [names[i] for i in on_x.support]
                    frols = frols_terms(centred, lag, degree, k)
                    best = interleaved_best({
                        "fos": partial(model.fit, signal),
                        "first": partial(cold_fit, model, signal),
                        "build": partial(omp_matrix, signal, lag, degree),
                        "omp": partial(omp.fit, X, target),
                        "gram": lambda X=X, target=target: (X.T @ X, X.T @ target),
                        "mp_gram": partial(orthogonal_mp_gram, gram, xy, n_nonzero_coefs=k),
                        "fos_x": partial(fos, X, target, max_terms=k, stop="max_terms"),
                        "frols": partial(frols_terms, centred, lag, degree, k),
                    }, repeats, few={"frols": frols_repeats})
                    rows.append(dict(
                        signal=label, lag=lag, degree=degree, cands=X.shape[1], k_rule=k_rule,
                        k=k, fos_terms=fos_terms, fos_x_same=fos_x == fos_terms, frols=frols,
                        omp=omp_terms, mp_same=mp_terms == omp_terms, best=best))
    return rows


def frols_table(rows) -> list[float]:
    print("Table 2. FOS against FROLS (sysidentpy) on the identical candidate set, k terms each")
    header = (f"{'signal':<7} {'L':>3} {'CP':>2} {'cands':>5} {'k from':<9} {'k':>3} "
              f"{'FOS ms':>8} {'1st ms':>8} {'FROLS ms':>9} {'FROLS/FOS':>9} {'FROLS/1st':>9}"
              "  same terms")
    print(header)
    print("-" * len(header))
    ratios = []
    for r in rows:
        b = r["best"]
        only_fos = sorted(set(r["fos_terms"]) - r["frols"])
        only_frols = sorted(r["frols"] - set(r["fos_terms"]))
        same = "yes" if not (only_fos or only_frols) else (
            f"FOS only {only_fos}, FROLS only {only_frols}")
        ratios.append(b["frols"] / b["fos"])
        print(f"{r['signal']:<7} {r['lag']:>3} {r['degree']:>2} {r['cands']:>5} "
              f"{r['k_rule']:<9} {r['k']:>3} {b['fos'] * 1e3:>8.2f} {b['first'] * 1e3:>8.2f} "
              f"{b['frols'] * 1e3:>9.1f} {ratios[-1]:>9.0f} {b['frols'] / b['first']:>9.0f}"
              f"  {same}")
    return ratios


def omp_table(rows) -> dict[str, list[float]]:
    print("Table 3. FOS against OMP (scikit-learn) on the same candidates as an explicit matrix")
    header = (f"{'signal':<7} {'L':>3} {'CP':>2} {'cands':>5} {'k':>3} {'FOS ms':>8} "
              f"{'build ms':>8} {'OMP ms':>7} {'Gram ms':>7} {'mp_gram':>7} {'FOS(X)':>7} | "
              f"{'(build+OMP)/FOS':>15} {'OMP/FOS':>7} {'mp_gram/FOS':>11} "
              f"{'OMP/FOS(X)':>10} {'common':>6}")
    print(header)
    print("-" * len(header))
    out: dict[str, list[float]] = {"with_build": [], "omp": [], "mp_gram": [], "omp_fos_x": []}
    for r in rows:
        b = r["best"]
        ratios = {"with_build": (b["build"] + b["omp"]) / b["fos"], "omp": b["omp"] / b["fos"],
                  "mp_gram": b["mp_gram"] / b["fos"], "omp_fos_x": b["omp"] / b["fos_x"]}
        for key, value in ratios.items():
            out[key].append(value)
        common = len(r["omp"] & set(r["fos_terms"]))
        notes = []
        if not r["fos_x_same"]:
            notes.append("fos(X) selected other terms than FOSModel!")
        if not r["mp_same"]:
            notes.append("mp_gram selected other terms than the OMP estimator")
        print(f"{r['signal']:<7} {r['lag']:>3} {r['degree']:>2} {r['cands']:>5} {r['k']:>3} "
              f"{b['fos'] * 1e3:>8.2f} {b['build'] * 1e3:>8.2f} {b['omp'] * 1e3:>7.2f} "
              f"{b['gram'] * 1e3:>7.2f} {b['mp_gram'] * 1e3:>7.2f} {b['fos_x'] * 1e3:>7.2f} | "
              f"{ratios['with_build']:>15.2f} {ratios['omp']:>7.2f} {ratios['mp_gram']:>11.2f} "
              f"{ratios['omp_fos_x']:>10.2f} {common:>3}/{r['k']:<2} {' '.join(notes)}")
    return out


def span(values) -> str:
    return f"{min(values):.3g} to {max(values):.3g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--quick", action="store_true",
                        help="smoke check: AR(4) only, fewer orders and repeats (under a minute)")
    parser.add_argument("--blas-threads", type=int,
                        help="limit the BLAS threads (threadpoolctl); default: as the environment")
    args = parser.parse_args()
    limit = limit_blas(args.blas_threads)  # noqa: F841 - the limit holds while it is referenced
    repeats = 3 if args.quick else args.repeats
    signals = {"AR(4)": ar4_signal()}
    if not args.quick:
        signals["paper"] = paper_signal()
    print(machine_line())
    print(f"N = {N} samples; best of {repeats} interleaved rounds (FROLS: fewer), each the mean "
          "of a loop of calls lasting at least 20 ms\n")

    burg_ratios = burg_table(signals, (1, 10) if args.quick else (1, 5, 10, 20), repeats)
    print()
    rows = selection_rows(signals, (10,) if args.quick else (10, 20), (1, 2),
                          ("korenberg",) if args.quick else ("korenberg", "10"),
                          repeats, 1 if args.quick else max(3, repeats // 5))
    frols_ratios = frols_table(rows)
    print()
    omp = omp_table(rows)
    print("\nSummary (ratios > 1 mean FOS is faster, except FOS/Burg):")
    print(f"  FOS/Burg: {span(burg_ratios)}")
    print(f"  FROLS/FOS: {span(frols_ratios)} (target >= 100: met in "
          f"{sum(r >= 100 for r in frols_ratios)} of {len(frols_ratios)})")
    print(f"  OMP/FOS, OMP given the matrix: {span(omp['omp'])}; with the matrix built: "
          f"{span(omp['with_build'])}; orthogonal_mp_gram given the Gram matrix: "
          f"{span(omp['mp_gram'])} (target > 1: met in {sum(r > 1 for r in omp['omp'])}, "
          f"{sum(r > 1 for r in omp['with_build'])}, {sum(r > 1 for r in omp['mp_gram'])} "
          f"of {len(omp['omp'])})")
    print(f"  OMP / fosmodel.fos on the same built matrix: {span(omp['omp_fos_x'])}")


if __name__ == "__main__":
    main()
