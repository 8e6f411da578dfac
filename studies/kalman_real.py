"""From Allan to a filter: the Allan-derived error model beside GM, AR and FOS on real records.

Issue 17 part 5.  The accelerometers x, y and z of the six static ADIS16405 sessions (18
axes, ``../shared/data/adis16405``) are converted from g to m/s^2 (9.80665) and block-averaged
from 100 Hz to 20 Hz (means of 5 samples: the rate of ``kalman_static.py``, whose fits and
filter this study imports).  Each axis is split in halves of 100,000 samples (1.39 h).

On the first half: the 1st-order Gauss-Markov, AR(4) by Burg and FOS (maximum lag L chosen
among 4..10 as ``kalman_static.py`` does) models, and the Allan model of
:mod:`fosmodel.filter.allan_statespace`: the Allan deviation of the training half, its IEEE Std 952
fit, and the white + Gauss-Markov + random-walk state space (terms not resolved at their
upper limits).  GM, AR and FOS start from their stationary covariance; the Allan model from
:func:`~fosmodel.filter.allan_statespace.initial_covariance` (white and Gauss-Markov stationary, the
random walk from its spread about the training mean).

On the second half: the 1-D position/velocity error filter (seed 000 eq. 5.7) with simulated
position updates of standard deviation 0.1 m in update/prediction cycles of 30/30, 60/60 and
120/120 s; the accelerometer is compensated by the training mean and the true position error
is its double integral (as in ``kalman_static.py``).  Every model of an axis sees the same
measurement noise.  Per axis, model and cycle: the RMS position estimation error and the RMS
the filter claims (``Filter sigma``); their ratio is 1 for a consistent filter and below 1
for an overconfident one.

Tables (Markdown, CSV, LaTeX) go to ``studies/results/kalman_real/``: ``all_cases`` (every
run), ``summary`` (per cycle and model, over the axes) and ``axes`` (per axis: the Allan terms
used, the slowest time constant of the fitted models, the shift of the mean between the
halves); the figure ``consistency`` sets the ratio of every run beside one axis's Allan
deviation, fit and state-space model.

Run: ``python studies/kalman_real.py`` (about 2.5 minutes on 2 cores).  It skips with one
line when ``../shared/data`` is absent.
"""

from __future__ import annotations

import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from doc_pages import show_figure
from kalman_static import (
    GM,
    RATE,
    choose_fos_lag,
    cycle_label,
    filter_position_error,
    fit_models,
    statistics,
)
from matplotlib.figure import Figure

from fosmodel.filter.allan_statespace import (
    allan_state_space,
    initial_covariance,
    model_adev,
    model_terms,
)
from fosmodel.filter.statespace import StateSpace, to_state_space
from fosmodel.io.loader import load_record
from fosmodel.io.output import save_figure, write_tables
from fosmodel.noise.allan import allan_deviation
from fosmodel.noise.allan_fit import NoiseFit, fit_noise
from fosmodel.noise.metrics import STANDARD_GRAVITY
from fosmodel.typeset.markdown import markdown_table

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
OUT = REPO / "studies" / "results" / "kalman_real"
SESSIONS = range(1, 7)
COLUMNS = ("ax_g", "ay_g", "az_g")
BLOCK = 5  # 100 Hz / 5 = kalman_static's 20 Hz
SIGMA_M = 0.1
CYCLES_S = (30, 60, 120)
SEED = 0
ALLAN = "Allan (white+GM+RW)"
MODELS = (GM, "AR(4) Burg", "FOS", ALLAN)
CONSISTENT = (0.5, 2.0)  # a filter sigma within a factor 2 of the actual RMS
FIGURE_AXIS = "imu1 ax"


@dataclass(frozen=True)
class AxisFit:
    """One axis's halves and the error models fitted on the first."""

    train: np.ndarray
    test: np.ndarray
    models: dict[str, tuple[StateSpace, np.ndarray]]  # name: (shaping filter, its P0)
    allan: NoiseFit
    fos_lag: int


def load_axes() -> dict[str, np.ndarray]:
    """Each accelerometer axis of each session in m/s^2 at 20 Hz (block means), keyed
    ``"imu1 ax"``."""
    out = {}
    for k in SESSIONS:
        rec = load_record(DATA / "adis16405" / f"imu{k}.csv.gz", rate=100)
        for column in COLUMNS:
            y = np.asarray(rec.column(column), dtype=float) * STANDARD_GRAVITY
            n = len(y) // BLOCK * BLOCK
            out[f"imu{k} {column[:2]}"] = y[:n].reshape(-1, BLOCK).mean(axis=1)
    return out


def fit_axis(y: np.ndarray) -> AxisFit:
    """Split ``y`` in halves and fit every model on the first."""
    train, test = y[: len(y) // 2], y[len(y) // 2:]
    lag, _ = choose_fos_lag(train)
    models = {}
    for name, model in fit_models(train, [lag]).items():
        error = to_state_space(model)
        models["FOS" if name.startswith("FOS") else name] = (error,
                                                             error.stationary_covariance())
    allan = fit_noise(allan_deviation(train, RATE, units="m/s^2", sensor="accel"))
    error = allan_state_space(allan, mu=float(np.mean(train)))
    models[ALLAN] = (error, initial_covariance(error, len(train)))
    return AxisFit(train, test, models, allan, lag)


def _run(job: tuple) -> tuple[np.ndarray, np.ndarray]:
    """One filter run (a top-level function, for the process pool)."""
    return filter_position_error(*job)


def run_filters(fits: dict[str, AxisFit]) -> pd.DataFrame:
    """Statistics of every (axis, cycle, model) run, spread over processes."""
    keys, jobs = [], []
    for i, (axis, fit) in enumerate(fits.items()):
        noise = np.random.default_rng([SEED, i]).standard_normal(len(fit.test))
        for cycle in CYCLES_S:
            for name in MODELS:
                error, p0 = fit.models[name]
                keys.append((axis, cycle, name))
                jobs.append((error, p0, fit.test, noise, SIGMA_M, cycle))
    with ProcessPoolExecutor() as pool:
        results = list(pool.map(_run, jobs, chunksize=4))
    rows = []
    for (axis, cycle, name), (err, variance) in zip(keys, results):
        stats = statistics(err, variance)
        rows.append({"Axis": axis, "Cycle": cycle_label(cycle), "Model": name,
                     **stats, "Sigma / RMS": stats["Filter sigma [m]"] / stats["RMS [m]"]})
    return pd.DataFrame(rows)


def summarise(frame: pd.DataFrame) -> pd.DataFrame:
    """Per cycle and model, over the axes: median RMS and filter sigma, and the ratio's
    median, range and the axes within :data:`CONSISTENT`."""
    lo, hi = CONSISTENT
    groups = frame.groupby(["Cycle", "Model"], sort=False)
    ratio = groups["Sigma / RMS"]
    return pd.DataFrame({
        "Median RMS [m]": groups["RMS [m]"].median(),
        "Median filter sigma [m]": groups["Filter sigma [m]"].median(),
        "Median sigma / RMS": ratio.median(), "Min sigma / RMS": ratio.min(),
        "Max sigma / RMS": ratio.max(),
        f"Axes with sigma / RMS in {lo:g}-{hi:g}": ratio.apply(
            lambda r: f"{int(r.between(lo, hi).sum())} of {len(r)}"),
    }).reset_index()


def slowest_time_constant(error: StateSpace) -> float:
    """The longest time constant (s) of a shaping filter's stable modes: how long its
    filter expects an estimated error to last."""
    radius = np.abs(np.linalg.eigvals(error.Phi))
    return float(-1.0 / (RATE * np.log(radius[radius < 1.0].max())))


def axes_table(fits: dict[str, AxisFit]) -> pd.DataFrame:
    """Per axis: the Allan terms the model uses (``*``: an upper limit), its Gauss-Markov
    sigma and correlation time, the sinusoid it does not carry, FOS's L, the slowest time
    constant of the other models, and how far the test half's mean is from the training
    half's (the bias left after calibration)."""
    rows = []
    for axis, fit in fits.items():
        terms = model_terms(fit.allan)
        error = fit.models[ALLAN][0]
        gm = error.state_names.index("gauss-markov bias")
        phi, q = error.Phi[gm, gm], error.Q[gm, gm]
        row = {"Axis": axis}
        for term, label in (("N", "N [m/s/sqrt(s)]"), ("B", "B [m/s^2]"),
                            ("K", "K [m/s^2/sqrt(s)]")):
            row[label] = f"{terms[term].value:.3g}" + ("*" if terms[term].source != "fitted"
                                                       else "")
        row |= {"GM sigma [m/s^2]": np.sqrt(q / (1.0 - phi**2)),
                "GM Tc [s]": -1.0 / (RATE * np.log(phi)),
                "S not carried [m/s^2]": terms["S"].value if "S" in terms else np.nan,
                "FOS L": fit.fos_lag}
        row |= {f"{name} slowest [s]": slowest_time_constant(fit.models[name][0])
                for name in MODELS[:3]}
        row["Test - training mean [m/s^2]"] = float(np.mean(fit.test) - np.mean(fit.train))
        rows.append(row)
    return pd.DataFrame(rows)


def figure(frame: pd.DataFrame, fit: AxisFit) -> Figure:
    """Left: filter sigma / actual RMS of every axis per model and cycle.  Right: the Allan
    deviation of FIGURE_AXIS's training half, its IEEE Std 952 fit and the state space's."""
    fig = Figure(figsize=(11, 4.4), layout="constrained")
    left, right = fig.subplots(1, 2, width_ratios=[3, 2])
    for j, cycle in enumerate(frame["Cycle"].unique()):
        for i, name in enumerate(MODELS):
            ratio = frame[(frame["Cycle"] == cycle) & (frame["Model"] == name)]["Sigma / RMS"]
            x = i + 0.25 * (j - 1) + np.linspace(-0.06, 0.06, len(ratio))
            left.semilogy(x, ratio, "o", ms=3.5, color=f"C{j}", label=cycle if i == 0 else None)
    left.axhline(1.0, color="0.3", lw=0.8)
    left.axhspan(*CONSISTENT, color="0.92", lw=0)
    left.set_xticks(range(len(MODELS)), MODELS)
    left.set_ylabel("filter sigma / actual RMS position error")
    left.set_title(f"ADIS16405 accelerometers, 18 axes, updates sigma {SIGMA_M:g} m")
    left.legend(fontsize="small")
    left.grid(True, which="both", axis="y", alpha=0.3)
    res = fit.allan.result
    right.loglog(res.taus, res.adev, "o", ms=3, color="C0", label="training half")
    right.loglog(res.taus, fit.allan.model_adev(res.taus), "-", color="k", lw=1,
                 label="IEEE Std 952 fit")
    right.loglog(res.taus, model_adev(fit.models[ALLAN][0], res.taus, RATE), "--", color="C3",
                 label="white + GM + RW state space")
    right.set_xlabel(r"averaging time $\tau$ (s)")
    right.set_ylabel("Allan deviation (m/s$^2$)")
    right.set_title(f"ADIS16405 {FIGURE_AXIS}, 20 Hz")
    right.legend(fontsize="small")
    right.grid(True, which="both", alpha=0.3)
    return fig


def main() -> None:
    if not DATA.is_dir():
        print(f"skipping: {DATA} not found (the real recordings are not part of this "
              "repository; see the README's 'Data and licences')")
        return
    start = time.perf_counter()
    fits = {axis: fit_axis(y) for axis, y in load_axes().items()}
    frame = run_filters(fits)
    OUT.mkdir(parents=True, exist_ok=True)
    tables = {"all_cases": frame, "summary": summarise(frame), "axes": axes_table(fits)}
    for stem, table in tables.items():
        write_tables(table, OUT, stem)
        print(f"\n## {stem}\n\n{markdown_table(table, digits=4)}")
    save_figure(figure(frame, fits[FIGURE_AXIS]), OUT, "consistency")
    show_figure(OUT / "consistency.png", "kalman_real_consistency.png")
    print(f"\n{time.perf_counter() - start:.0f} s; results in {OUT}")


if __name__ == "__main__":
    main()
