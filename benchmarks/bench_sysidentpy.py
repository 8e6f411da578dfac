"""fosmodel against SysIdentPy's FROLS on SysIdentPy's own GPU benchmark configuration.

SysIdentPy's ``examples/array-api-benchmark.ipynb`` fits ``FROLS(ylag=10, xlag=10,
order_selection=True, n_info_values=10, basis_function=Polynomial(degree=4),
estimator=LeastSquares())`` to ``get_siso_data(n, colored_noise=False, sigma=0.001,
train_percentage=80)``, the system ``y[k] = 0.2 y[k-1] + 0.1 y[k-1] x[k-1] + 0.9 x[k-2]
+ e[k]``.  At n = 25,000 (20,000 training rows; 10,626 candidates: every product of up
to four of ``y[k-1..k-10]`` and ``x[k-1..k-10]``) the notebook reports fits of 166 s with
NumPy and 4.39 s with PyTorch on CUDA (an RTX 3080 Ti): 38 times faster.

Here both run on the same rows in the same process: SysIdentPy's FROLS with NumPy as
the notebook configures it, and ``FOSModel(max_lag=10, degree=4, exog_lags={"x": 9},
stop="max_terms", max_terms=10)`` on ``y`` and the input delayed by one sample, whose
lags 0..9 are ``x[k-1..k-10]``: the identical candidate set, searched for the 10 terms
whose information criteria FROLS's order selection computes.  ``fosmodel first`` is a
fit with every cached plan cleared (as the first fit of this candidate set in a
process), ``fosmodel`` a later fit.  The rounds are interleaved (SysIdentPy, then
fosmodel's two), and each time is the median of the rounds.  Both find the system's
three terms (``x[n-1]``, ``y[n-1]``, ``y[n-1]*x[n-0]`` in fosmodel's names of the
delayed input): the script checks that they are fosmodel's first three and in FROLS's
final model (exit code 1 if not).

It also measures where a fosmodel fit's time goes (one fit, its parts read from the marks
the correlation provider carries, ``fosmodel.core.timed_parts``): the plan, the first pass
(every candidate's mean, correlation with y and mean square), and each Gram column's pair
products and matrix products, whose rate it sets against a 1024 x 1024 x 1024 matrix
product on one thread in the same run; and the fit's peak of allocated memory
(tracemalloc) against the ``N x C`` matrix SysIdentPy forms.
The figure goes to ``results/sysidentpy.png`` and ``docs/pages/figures/``.

Run: ``python benchmarks/bench_sysidentpy.py [--rounds R] [--rows N] [--quick]``
(about 15 minutes a round on a busy 2-core machine: SysIdentPy's fit).  It exits 0 with
a message when sysidentpy is not installed.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
from _common import limit_blas, machine_line, settle_allocator

from fosmodel import FOSModel
from fosmodel.core import Term, clear_plans, generate_terms, timed_parts
from fosmodel.core.blas import one_blas_thread
from fosmodel.core.pairs import pair_plan

HERE = Path(__file__).resolve().parent
FIGURES = HERE.parent / "docs" / "pages" / "figures"
TRUE_TERMS = ["x[n-1]", "y[n-1]", "y[n-1]*x[n-0]"]  # y[k-1], y[k-1] x[k-1], x[k-2]
PUBLISHED = {"SysIdentPy NumPy (published)": 166.3386, "SysIdentPy CUDA (published)": 4.3886}


def data(rows: int, seed: int = 0):
    """SysIdentPy's training rows: the notebook's get_siso_data at n = rows / 0.8."""
    from sysidentpy.utils.generate_data import get_siso_data

    np.random.seed(seed)  # noqa: NPY002 - get_siso_data draws from the global generator
    x, _, y, _ = get_siso_data(n=round(rows / 0.8), colored_noise=False, sigma=0.001,
                               train_percentage=80)
    return x, y


def frols_fit(x: np.ndarray, y: np.ndarray, lags: int):
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    model = FROLS(ylag=lags, xlag=lags, order_selection=True, n_info_values=10,
                  basis_function=Polynomial(degree=4), estimator=LeastSquares())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(X=x, y=y)
    return model


def frols_terms(model) -> set[str]:
    """FROLS's final terms in fosmodel's names of the delayed input.

    SysIdentPy codes y[k-l] as 1000 + l and x[k-l] as 2000 + l: the delayed input's lag
    l - 1.
    """
    return {Term(tuple(("y", c - 1000) if c < 2000 else ("x", c - 2001)
                       for c in (int(c) for c in row) if c)).name
            for row in model.final_model}


def fos_inputs(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """``y`` and the input delayed one sample (its lag l is x[k-1-l]), both from sample 1."""
    return y.ravel()[1:], {"x": x.ravel()[:-1]}


def fos_model(lags: int) -> FOSModel:
    return FOSModel(max_lag=lags, degree=4, exog_lags={"x": lags - 1}, stop="max_terms",
                    max_terms=10)


def fos_fit(y: np.ndarray, exog: dict, lags: int, first: bool) -> FOSModel:
    if first:
        clear_plans()
        pair_plan.cache_clear()
    return fos_model(lags).fit(y, exog)


def timed(fn, *args):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn(*args)
    return out, time.perf_counter() - t0, time.process_time() - c0


def where_time_goes(y: np.ndarray, exog: dict, lags: int) -> dict[str, float]:
    """One fit with its parts timed: seconds per part, and the tile products' multiply-adds.

    The parts are those the correlations mark (``fosmodel.core.timed_parts``): the plan,
    the first pass (every candidate's mean, correlation with y and mean square) and the
    Gram columns of the selected terms, each with its pair products and tile products.
    """
    clear_plans()
    pair_plan.cache_clear()
    with timed_parts() as parts:
        t0 = time.perf_counter()
        fos_model(lags).fit(y, exog)
        fit = time.perf_counter() - t0
    totals = {"fit": fit, **parts.seconds}
    for phase in ("first pass", "Gram columns"):  # zero where the set took the tables
        for part in ("", ": pair products", ": tile products"):
            totals.setdefault(phase + part, 0.0)
    totals.setdefault("plan", 0.0)
    totals["search and model"] = fit - totals["plan"] - totals["first pass"] - totals[
        "Gram columns"]
    totals["fma"] = sum(n for k, n in parts.counts.items() if k.endswith("tile multiply-adds"))
    return totals


def tile_entries(model: FOSModel) -> float:
    """Entries the tiles compute per candidate (1 would be none wasted)."""
    terms = [t for t in generate_terms(model.spec_) if not t.is_constant]
    return pair_plan(tuple(t.factors for t in terms)).n_entries / len(terms)


def peak_gemm_rate() -> float:
    """Multiply-adds per second of a 1024^3 matrix product on one BLAS thread (best of 3)."""
    a = np.random.default_rng(0).standard_normal((1024, 1024))
    best = np.inf
    with one_blas_thread():
        for _ in range(3):
            t0 = time.perf_counter()
            a @ a
            best = min(best, time.perf_counter() - t0)
    return 1024**3 / best


def fit_memory(y: np.ndarray, exog: dict, lags: int) -> float:
    """Peak bytes allocated (tracemalloc) during a later fit."""
    fos_model(lags).fit(y, exog)
    tracemalloc.start()
    fos_model(lags).fit(y, exog)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def figure(times: dict[str, float], parts: dict[str, float], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 3.8),
                                      gridspec_kw={"width_ratios": [1.6, 1]})
    names = list(times)
    colours = ["#9e9e9e" if "published" in n else "#ff7800" if "SysIdentPy" in n else "#1565c0"
               for n in names]
    left.barh(names[::-1], [times[n] for n in names][::-1], color=colours[::-1])
    left.set_xscale("log")
    left.set_xlabel("fit time (s), log scale")
    for i, n in enumerate(names[::-1]):
        left.text(times[n] * 1.1, i, f"{times[n]:.3g} s", va="center", fontsize=8)
    left.set_title("FROLS, ylag = xlag = 10, degree 4: 10,626 candidates, 20,000 rows",
                   fontsize=9)
    keys = ["plan", "first pass", "Gram columns", "search and model"]
    tiles = [parts.get(f"{k}: tile products", 0.0) for k in keys]
    pair = [parts.get(f"{k}: pair products", 0.0) for k in keys]
    other = [parts[k] - t - p for k, t, p in zip(keys, tiles, pair)]
    right.bar(keys, tiles, color="#1565c0", label="tile products")
    right.bar(keys, pair, bottom=tiles, color="#64b5f6", label="pair products")
    right.bar(keys, other, bottom=np.add(tiles, pair), color="#bbdefb", label="other")
    right.legend(fontsize=7)
    right.set_ylabel("seconds in one fosmodel fit")
    right.tick_params(axis="x", labelrotation=30, labelsize=8)
    right.set_title("where fosmodel's fit spends its time", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def parts_lines(y_fos: np.ndarray, exog: dict, lags: int,
                fos: FOSModel) -> tuple[list[str], dict[str, float]]:
    """The report of where a fosmodel fit's time goes, its memory, and the parts."""
    parts = where_time_goes(y_fos, exog, lags)
    tiles = parts["first pass: tile products"] + parts["Gram columns: tile products"]
    rate = parts["fma"] / max(tiles, 1e-12)
    peak = peak_gemm_rate()
    memory = fit_memory(y_fos, exog, lags)
    n = len(y_fos) - lags
    n_cand = fos.n_candidates_
    lines = ["", f"where one fosmodel fit's {parts['fit']:.3f} s go (instrumented fit, plans "
              "cleared):"]
    for k in ("plan", "first pass", "first pass: pair products", "first pass: tile products",
              "Gram columns", "Gram columns: pair products", "Gram columns: tile products",
              "search and model"):
        lines.append(f"  {k:<30} {parts[k]:7.3f} s  {100 * parts[k] / parts['fit']:5.1f} %")
    lines += [f"tile products: {parts['fma'] / 1e9:.1f} G multiply-adds at {rate / 1e9:.1f} G/s; "
              f"a 1024^3 product on one thread here: {peak / 1e9:.1f} G/s "
              f"({rate / peak:.0%} of it)",
              f"entries the tiles compute per candidate: {tile_entries(fos):.2f}",
              f"peak memory allocated during a fit: {memory / 2**20:.0f} MiB; the N x C matrix "
              f"of candidates would take {n * (n_cand - 1) * 8 / 2**20:,.0f} MiB"]
    return lines, parts


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--rows", type=int, default=20_000)
    parser.add_argument("--quick", action="store_true",
                        help="smoke check: lags 1-4 (495 candidates), 2,000 rows, one round")
    parser.add_argument("--blas-threads", type=int,
                        help="limit the BLAS threads (threadpoolctl); default: as the environment")
    parser.add_argument("--parts", action="store_true",
                        help="only where a fosmodel fit's time goes (no SysIdentPy fit)")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "sysidentpy.txt")
    args = parser.parse_args()
    try:
        import sysidentpy
    except ImportError:
        print("skipped: sysidentpy is not installed (pip install sysidentpy)")
        return 0
    limit = limit_blas(args.blas_threads)  # noqa: F841 - the limit holds while it is referenced
    settle_allocator()
    rows, rounds, lags = (2_000, 1, 4) if args.quick else (args.rows, args.rounds, 10)
    x, y = data(rows)
    y_fos, exog = fos_inputs(x, y)
    lines = [machine_line(), f"sysidentpy {sysidentpy.__version__}; {rows} training rows; "
             f"medians of {rounds} interleaved rounds (wall time; CPU time of this process)", ""]

    if args.parts:
        print("\n".join(lines[:1] + parts_lines(y_fos, exog, lags, fos_model(lags).fit(
            y_fos, exog))[0]))
        return 0
    times: dict[str, list[float]] = {"SysIdentPy": [], "fosmodel first": [], "fosmodel": []}
    cpu: dict[str, list[float]] = {k: [] for k in times}
    frols = fos = None
    for _ in range(rounds):
        frols, wall, c = timed(frols_fit, x, y, lags)
        times["SysIdentPy"].append(wall)
        cpu["SysIdentPy"].append(c)
        for key, first in (("fosmodel first", True), ("fosmodel", False)):
            fos, wall, c = timed(fos_fit, y_fos, exog, lags, first)
            times[key].append(wall)
            cpu[key].append(c)
    med = {k: float(np.median(v)) for k, v in times.items()}
    med_cpu = {k: float(np.median(v)) for k, v in cpu.items()}
    assert frols is not None and fos is not None
    n_cand = fos.n_candidates_
    lines.append(f"{'fit':<16} {'median s':>9} {'CPU s':>8} {'rounds (s)':<40}")
    for k, v in times.items():
        lines.append(f"{k:<16} {med[k]:>9.3f} {med_cpu[k]:>8.3f} "
                     f"{', '.join(f'{t:.3f}' for t in v):<40}")
    published = PUBLISHED["SysIdentPy NumPy (published)"] / PUBLISHED["SysIdentPy CUDA (published)"]
    ratio, first_ratio = med["SysIdentPy"] / med["fosmodel"], med["SysIdentPy"] / med[
        "fosmodel first"]
    lines += ["", f"candidates: fosmodel {n_cand} (the constant included), SysIdentPy "
              f"{frols.regressor_code.shape[0]}",
              f"SysIdentPy / fosmodel: {ratio:.0f}x (first fit: {first_ratio:.0f}x); "
              f"CPU time: {med_cpu['SysIdentPy'] / med_cpu['fosmodel']:.0f}x "
              f"({med_cpu['SysIdentPy'] / med_cpu['fosmodel first']:.0f}x); target >= 40x",
              f"published (20,000 rows): SysIdentPy NumPy / CUDA = {published:.0f}x"]
    found = frols_terms(frols)
    same = set(fos.terms_[:3]) == set(TRUE_TERMS) and set(TRUE_TERMS) <= found
    lines += [f"fosmodel's terms: {', '.join(fos.terms_)}",
              f"FROLS's terms:    {', '.join(sorted(found))}",
              f"the system's three terms first in fosmodel and in FROLS: {'yes' if same else 'NO'}"]

    more, parts = parts_lines(y_fos, exog, lags, fos)
    lines += more
    text = "\n".join(lines)
    print(text)
    if not args.quick:
        args.out.write_text(text + "\n")
        png = args.out.with_suffix(".png")
        figure({"SysIdentPy NumPy (here)": med["SysIdentPy"], **PUBLISHED,
                "fosmodel, first fit (here)": med["fosmodel first"],
                "fosmodel (here)": med["fosmodel"]}, parts, png)
        shutil.copy(png, FIGURES / png.name)
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
