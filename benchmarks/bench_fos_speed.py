"""FOS fit time against statsmodels' Burg, sysidentpy's FROLS and scikit-learn's OMP, in one run.

Every time is the median of several rounds, interleaved with the times it is
compared with (these machines are noisy); in each round a function runs in a
loop of consecutive calls lasting at least 20 ms and its time is the loop's
mean, as ``timeit`` does (a single fast call right after FROLS would pay for
the caches and fresh pages FROLS left behind).  BLAS runs on one thread (a
FOS fit limits itself to one; Burg's dot products are faster on one thread on
a shared 2-core machine too); ``--blas-threads`` changes it.  Before any timing the
allocator is settled (``_common.settle_allocator``): otherwise Burg's time swung by a
factor of 1-4 with the fit timed before it (page faults).  FOS is always timed
through ``FOSModel(...).fit``: candidate generation, correlations, search,
weights and their standard errors.  ``FOS ms`` is a fit of a candidate set
fitted before in the process (the usual case in a study: the same orders on
many records); ``1st ms`` is the first fit of a candidate set, which also plans
its correlation tables (``fosmodel.core.shapes.layout``, ``gram_columns`` and
``direct_groups``, cached per candidate set like an FFT plan).

Table 1, the small fit: FOS with L = 10 and 10 terms (``stop="max_terms"``)
and with its default rule (``korenberg``), CP = 1 and 2, against Burg
(``statsmodels.regression.linear_model.burg(y, 10)``) on an AR(3) record (weights
0.5, -0.2, 0.1, the short-memory colouring of ``data_synth``'s gyro noise, driven
by unit white noise) of 36,000 samples (3 minutes at 200 Hz, the paper's training
window) and of 360,000 (one hour at 100 Hz).  Targets: CP = 1 at most 0.5 times
Burg, CP = 2 at most 1.5 times, for the 10-term fits.  Ten terms of an AR(3) record
are three true lags and seven of the 62 other candidates, most of them
cross-products: each brings the Gram column of a product of two lags.  Its
``CPU`` column is the ratio of the median CPU times of the same loops (this
thread's): on a machine shared with other work the wall times also hold the
time a process waited for a core.

Table 2, FOS against Burg at the same order L = 1, 5, 10, 20 on 36,000 samples of
an AR(4) process (Park 2004, models accelerometer errors as AR(4); the weights
here are our choice) and of the first 3 minutes of the paper-like accelerometer
record of ``data_synth``.  Burg (``burg(y, L)``) has no cross-products, so FOS with
CP = 1 and CP = 2 at lag L are both set against Burg at order L.  FOS runs with
its default stopping rule and at full order (``max_terms = L``: as many weights as
Burg estimates).

Table 3, FOS against FROLS (sysidentpy) on the identical candidate set (lags
1..L of y and their products up to CP), asked for the k terms FOS selects
(``k`` from FOS's ``korenberg`` rule, or fixed at 10); FOS is timed with
``stop="max_terms", max_terms=k``.  FROLS is given the signal minus its mean,
which is what FOS works on (FOS always takes the constant first; sysidentpy
offers the constant as one more candidate and does not centre; when it takes
it, it shows as the term ``1``).  The table lists the terms on which the two
differ.

Table 4, FOS against orthogonal matching pursuit (scikit-learn) on the same
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

The figure of Table 1 goes to ``results/fos_speed.png`` and ``docs/pages/figures/``.

After Table 1 it times the parts of the CP = 2, 10-term fit on 36,000 samples: the first
batch of correlations, every Gram column, the search, and the rest of the fit; then the
same moments as BLAS products of the lag matrix (every cubic moment in one product, the
Gram column of each selected cross-product in one more), checked equal to the tables';
then where the wall time of the CP = 1 fit goes that its CPU time does not (context
switches and page faults of the timing thread).

Run: ``python benchmarks/bench_fos_speed.py [--repeats R] [--quick] [--small]``
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import time
import warnings
from functools import partial
from pathlib import Path

import numpy as np
from _common import interleaved_median, limit_blas, machine_line, settle_allocator
from numpy.lib.stride_tricks import sliding_window_view
from scipy.signal import lfilter
from sklearn.linear_model import OrthogonalMatchingPursuit, orthogonal_mp_gram
from statsmodels.regression.linear_model import burg

from data_synth import make_scenario
from fosmodel import FOSModel, fos
from fosmodel.core.blas import one_blas_thread
from fosmodel.core.candidates import CandidateSpec, evaluate_terms, generate_terms
from fosmodel.core.correlations import LagCorrelations
from fosmodel.core.fos import StopRule, center, fos_search
from fosmodel.core.shapes import clear_plans

N = 36_000
HOUR_100HZ = 360_000
HERE = Path(__file__).resolve().parent
FIGURES = HERE.parent / "docs" / "pages" / "figures"
TARGETS = {1: 0.5, 2: 1.5}  # most FOS / Burg for the 10-term fits, by CP


def ar3_signal(n: int, seed: int = 0) -> np.ndarray:
    """AR(3) with weights 0.5, -0.2, 0.1 driven by unit white noise."""
    e = np.random.default_rng(seed).standard_normal(n + 2000)
    return lfilter([1.0], [1.0, -0.5, 0.2, -0.1], e)[2000:]


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


def small_fit_table(lengths, repeats: int) -> list[dict]:
    print("Table 1. The small fit: AR(3), L = 10, FOS against Burg AR(10) "
          "(targets for 10 terms: CP 1 <= 0.5, CP 2 <= 1.5)")
    header = (f"{'N':>7} {'CP':>2} {'stop':<12} {'terms':>5} {'cross':>5} {'FOS ms':>8} "
              f"{'1st ms':>8} {'Burg ms':>8} {'FOS/Burg':>8} {'1st/Burg':>8} {'CPU':>5}  target")
    print(header)
    print("-" * len(header))
    rows = []
    for n in lengths:
        signal = ar3_signal(n)
        for degree in (1, 2):
            for stop, max_terms in (("max_terms", 10), ("korenberg", None)):
                model = FOSModel(max_lag=10, degree=degree, stop=stop, max_terms=max_terms)
                terms = model.fit(signal).terms_
                med = interleaved_median({"fos": partial(model.fit, signal),
                                          "first": partial(cold_fit, model, signal),
                                          "burg": partial(burg, signal, 10)}, repeats, cpu=True)
                ratio, first = med["fos"] / med["burg"], med["first"] / med["burg"]
                cpu = med["fos cpu"] / med["burg cpu"]
                target = TARGETS[degree] if max_terms else None
                verdict = "" if target is None else (
                    f"<= {target}: {'met' if ratio <= target else 'NOT met'}")
                rule = stop if max_terms is None else f"max_terms={max_terms}"
                rows.append(dict(n=n, degree=degree, rule=rule, ratio=ratio, first=first,
                                 target=target, cpu=cpu))
                print(f"{n:>7} {degree:>2} {rule:<12} {len(terms):>5} "
                      f"{sum('*' in t or '^' in t for t in terms):>5} {med['fos'] * 1e3:>8.2f} "
                      f"{med['first'] * 1e3:>8.2f} {med['burg'] * 1e3:>8.2f} {ratio:>8.2f} "
                      f"{first:>8.2f} {cpu:>5.2f}  {verdict}")
    return rows


def small_fit_parts(repeats: int) -> None:
    """Where the 10-term CP = 2 fit on 36,000 samples spends its time, against Burg's."""
    signal = ar3_signal(N)
    terms = [t for t in generate_terms(CandidateSpec(10, 2)) if not t.is_constant]
    mean = float(signal.mean())
    model = FOSModel(max_lag=10, degree=2, stop="max_terms", max_terms=10)
    model.fit(signal)
    gram = LagCorrelations(terms, {"y": signal}, 10, offsets={"y": mean})
    gram.column(len(terms) - 1)  # every column: the one search below reads them all
    rule = StopRule("max_terms", max_terms=10)

    def first_and_columns():
        corr = LagCorrelations(terms, {"y": signal}, 10, offsets={"y": mean})
        corr.column(len(terms) - 1)

    with one_blas_thread():
        med = interleaved_median({
            "fit": partial(model.fit, signal),
            "first batch": partial(LagCorrelations, terms, {"y": signal}, 10,
                                   offsets={"y": mean}),
            "with all Gram columns": first_and_columns,
            "search": partial(fos_search, gram, rule),
            "burg": partial(burg, signal, 10)}, repeats, cpu=True)
    cpu = {k[:-4]: v for k, v in med.items() if k.endswith(" cpu")}
    columns = cpu["with all Gram columns"] - cpu["first batch"]
    rest = cpu["fit"] - cpu["with all Gram columns"] - cpu["search"]
    print(f"\nWhere the CP 2, 10-term fit on {N} samples goes (median CPU ms, same run): "
          f"first batch (means, y and squares; 66 shapes of degree 3) "
          f"{cpu['first batch'] * 1e3:.2f}, every Gram column (220 shapes of degree 4) "
          f"{columns * 1e3:.2f}, search {cpu['search'] * 1e3:.2f}, the rest of the fit "
          f"{rest * 1e3:.2f}; the fit {cpu['fit'] * 1e3:.2f}, Burg {cpu['burg'] * 1e3:.2f}")
    fma = (66 + 220) * (N - 10)
    print(f"the shapes' {fma / 1e6:.1f} M multiply-adds take "
          f"{(cpu['with all Gram columns']) * 1e3:.2f} ms with the rest of the tables: "
          f"{fma / cpu['with all Gram columns'] / 1e9:.1f} G/s")


def lag_matrix_product(lags: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """``lags.T @ diag(weight) @ lags`` by matrix products over blocks of 2,048 rows.

    ``lags`` column-major: from it, in blocks that stay in cache, BLAS ran this product
    twice as fast as in one call or from a row-major copy (36,000 x 11, one thread).
    """
    out = np.zeros((lags.shape[1], lags.shape[1]))
    for lo in range(0, len(lags), 2048):
        block = lags[lo : lo + 2048]
        out += (block * weight[lo : lo + 2048, None]).T @ block
    return out


def blas_alternatives(repeats: int) -> None:
    """The same moments as matrix products of the lag matrix, against the tables.

    With ``X`` the N x (L + 1) lag matrix (``X[n, i] = y(n - i)`` over the window, a
    column-major copy of a sliding window), every cubic moment ``sum y(n) y(n-i) y(n-j)`` is
    one product ``X' diag(y) X``, and the Gram column of a selected cross-product
    ``s = y(n-a) y(n-b)`` against every candidate is ``X' diag(s) X`` and ``X' s``.  Both
    products compute every (i, j) twice, and from the candidates' moments themselves
    rather than their shapes; the tables sum each shape once.  The first batch of the
    tables holds the cubic moments and more (the means, 11 quartic shapes of the squares,
    the Gram columns of the linear candidates).
    """
    signal = ar3_signal(N)
    y = signal - signal.mean()
    terms = [t for t in generate_terms(CandidateSpec(10, 2)) if not t.is_constant]
    model = FOSModel(max_lag=10, degree=2, stop="max_terms", max_terms=10).fit(signal)
    selected = [t for t in terms if t.name in model.terms_ and t.degree == 2]
    n = N - 10
    corr = LagCorrelations(terms, {"y": y}, 10)

    def lag_matrix() -> np.ndarray:
        return np.asfortranarray(sliding_window_view(y, 11)[:, ::-1])  # X[n, i] = y(n - i)

    def cubic() -> np.ndarray:
        x = lag_matrix()
        return lag_matrix_product(x, x[:, 0])

    def columns() -> list[np.ndarray]:
        x = lag_matrix()
        out = []
        for term in selected:
            (_, a), (_, b) = term.factors
            s = x[:, a] * x[:, b]
            out.append(np.concatenate([x.T @ s, lag_matrix_product(x, s).ravel()]))
        return out

    # the same moments from both: every candidate's mean(y p_c), and the selected Gram columns
    x, lags = lag_matrix(), [[g for _, g in t.factors] for t in terms]
    linear, cubic_moments = x.T @ x[:, 0] / n, cubic() / n
    target = np.array([linear[g[0]] if len(g) == 1 else cubic_moments[g[0], g[1]] for g in lags])
    worst = float(np.abs(target - corr.target).max() / np.abs(corr.target).max())
    for term, col in zip(selected, columns()):
        table = corr.column(terms.index(term))
        lin, quad = col[:11] / n, col[11:].reshape(11, 11) / n
        blas = np.array([lin[g[0]] if len(g) == 1 else quad[g[0], g[1]] for g in lags])
        worst = max(worst, float(np.abs(blas - table).max() / np.abs(table).max()))

    def tables() -> None:
        LagCorrelations(terms, {"y": y}, 10).column(len(terms) - 1)  # and every Gram column

    with one_blas_thread():
        med = interleaved_median({"first": partial(LagCorrelations, terms, {"y": y}, 10),
                                  "tables": tables, "cubic": cubic, "columns": columns},
                                 repeats, cpu=True)
    cpu = {k[:-4]: v * 1e3 for k, v in med.items() if k.endswith(" cpu")}
    print(f"the same moments as products of the lag matrix X (36,000 x 11, column-major, "
          f"BLAS on one thread; median CPU ms): every cubic moment as X' diag(y) X "
          f"{cpu['cubic']:.2f} against {cpu['first']:.2f} for the whole first batch from the "
          f"tables; the Gram columns of the {len(selected)} cross-products the fit selects "
          f"as X' diag(s) X and X' s {cpu['columns']:.2f} against "
          f"{cpu['tables'] - cpu['first']:.2f} for every Gram column from the tables; the "
          f"two agree to {worst:.1e} of the largest moment")


def waiting(repeats: int) -> None:
    """Where the wall time of the CP = 1, 10-term fit goes that its CPU time does not.

    Loops of consecutive calls (at least 20 ms each, interleaved with Burg's), with the
    thread's context switches and page faults from ``getrusage``: a call that waits for
    a core shows involuntary switches, one that waits for anything else voluntary ones.
    """
    if not hasattr(resource, "RUSAGE_THREAD"):  # Linux only
        return
    signal = ar3_signal(N)
    model = FOSModel(max_lag=10, degree=1, stop="max_terms", max_terms=10)
    fns = {"FOS CP 1": partial(model.fit, signal), "Burg": partial(burg, signal, 10)}
    number = {name: max(1, int(0.02 / _cpu_per_call(fn))) for name, fn in fns.items()}
    totals = {name: np.zeros(6) for name in fns}  # calls, wall, cpu, involuntary, voluntary, faults
    for _ in range(repeats):
        for name, fn in fns.items():
            r0, t0, c0 = resource.getrusage(resource.RUSAGE_THREAD), time.perf_counter(), \
                time.thread_time()
            for _ in range(number[name]):
                fn()
            t1, c1 = time.perf_counter(), time.thread_time()
            r1 = resource.getrusage(resource.RUSAGE_THREAD)
            totals[name] += [number[name], t1 - t0, c1 - c0, r1.ru_nivcsw - r0.ru_nivcsw,
                             r1.ru_nvcsw - r0.ru_nvcsw, r1.ru_minflt - r0.ru_minflt]
    parts = []
    for name, (calls, wall, cpu, inv, vol, faults) in totals.items():
        wait = f", {(wall - cpu) / inv * 1e3:.1f} ms waited a switch" if inv else ""
        parts.append(f"{name} {wall / calls * 1e3:.2f} ms wall and {cpu / calls * 1e3:.2f} ms "
                     f"CPU a call, per 1,000 calls {inv / calls * 1e3:.0f} involuntary and "
                     f"{vol / calls * 1e3:.0f} voluntary context switches and "
                     f"{faults / calls * 1e3:.0f} page faults{wait}")
    print(f"where the wall time goes (loops of {repeats} rounds, this thread's getrusage; load "
          f"average {os.getloadavg()[0]:.1f}): " + "; ".join(parts))


def _cpu_per_call(fn) -> float:
    fn()  # the first fit of a candidate set plans it
    t0 = time.thread_time()
    fn()
    return max(time.thread_time() - t0, 1e-6)


def small_fit_figure(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 3.6))
    labels, x = [], 0
    for degree in (1, 2):
        for r in (r for r in rows if r["degree"] == degree):
            ax.bar(x - 0.2, r["ratio"], 0.4, color="#1565c0",
                   label="later fit" if x == 0 else None)
            ax.bar(x + 0.2, r["first"], 0.4, color="#90caf9",
                   label="first fit of the candidate set" if x == 0 else None)
            if r["target"] is not None:
                ax.plot([x - 0.45, x + 0.45], [r["target"]] * 2, color="#c62828",
                        label="target" if degree == 1 and r["n"] == rows[0]["n"] else None)
            labels.append(f"CP {degree}, {r['rule'].replace('max_terms=', '')} terms\n"
                          f"N = {r['n']:,}".replace("korenberg terms", "korenberg"))
            x += 1
    ax.axhline(1.0, color="grey", lw=0.8, ls="--")
    ax.set_xticks(range(len(labels)), labels, fontsize=7)
    ax.set_ylabel("FOS fit time / Burg AR(10)")
    ax.set_title("L = 10 on an AR(3) record: median of interleaved rounds", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def burg_table(signals: dict, lags, repeats: int) -> list[float]:
    print("Table 2. FOS against Burg at the same order L (Burg has no cross-products)")
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
                    best = interleaved_median({"fos": partial(model.fit, signal),
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
                    best = interleaved_median({
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
    print("Table 3. FOS against FROLS (sysidentpy) on the identical candidate set, k terms each")
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
    print("Table 4. FOS against OMP (scikit-learn) on the same candidates as an explicit matrix")
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
                        help="smoke check: 36,000 samples, fewer orders and repeats")
    parser.add_argument("--blas-threads", type=int, default=1,
                        help="limit the BLAS threads (threadpoolctl; 0: as the environment)")
    parser.add_argument("--figure", type=Path, default=HERE / "results" / "fos_speed.png")
    parser.add_argument("--small", action="store_true", help="Table 1 alone (and its figure)")
    args = parser.parse_args()
    limit = limit_blas(args.blas_threads or None)  # noqa: F841 - holds while referenced
    settle_allocator()
    repeats = 3 if args.quick else args.repeats
    signals = {"AR(4)": ar4_signal()}
    if not args.quick:
        signals["paper"] = paper_signal()
    print(machine_line())
    print(f"median of {repeats} interleaved rounds (FROLS: fewer), each the mean of a loop of "
          "calls lasting at least 20 ms\n")

    small = small_fit_table((N,) if args.quick else (N, HOUR_100HZ), repeats)
    small_fit_parts(repeats)
    blas_alternatives(repeats)
    waiting(repeats)
    if not args.quick:
        small_fit_figure(small, args.figure)
        shutil.copy(args.figure, FIGURES / args.figure.name)
    if args.small:
        return
    print(f"\nN = {N} samples in Tables 2-4")
    burg_ratios = burg_table(signals, (1, 10) if args.quick else (1, 5, 10, 20), repeats)
    print()
    rows = selection_rows(signals, (10,) if args.quick else (10, 20), (1, 2),
                          ("korenberg",) if args.quick else ("korenberg", "10"),
                          repeats, 1 if args.quick else max(3, repeats // 5))
    frols_ratios = frols_table(rows)
    print()
    omp = omp_table(rows)
    print("\nSummary (ratios > 1 mean FOS is faster, except FOS/Burg):")
    for r in (r for r in small if r["target"] is not None):
        print(f"  small fit, N = {r['n']}, CP {r['degree']}, 10 terms: FOS/Burg {r['ratio']:.2f} "
              f"(first fit {r['first']:.2f}, CPU time {r['cpu']:.2f}); target <= {r['target']}: "
              f"{'met' if r['ratio'] <= r['target'] else 'NOT met'}")
    print(f"  FOS/Burg at the same order: {span(burg_ratios)}")
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
