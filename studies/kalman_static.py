"""Park's (2004) static Kalman filter test (section 5.1, Tables 5.1-5.3) on a data_synth record.

A static accelerometer error record (scenario ``paper_accel_y`` at 20 Hz, four hours, seed
0) is split in halves.  On the first half Gauss-Markov, AR(4) (Burg) and FOS models are
fitted; FOS's maximum lag L is chosen among 4..10 by the one-step MSE on the last quarter of
the training half (fitted on the rest), then refitted on the whole half.  On the second half
the same filter runs with each model: states position error, velocity error and the error
model's states (:func:`fosmodel.filter.statespace.position_velocity_error_model`;
Park 2004, eq. 5.7),
with simulated position updates of standard deviation 0.01, 0.1 and 1 m, at every sample
(20 Hz) or in update/prediction cycles of 10/10, 30/30, 60/60 and 120/120 s.  The
accelerometer is compensated by the training mean (the calibrated bias, as Park (2004) removed
its Table 4.1 bias before filtering); the true position error is the double integral of the
compensated error, discretised like the filter.  Every model sees the same measurement noise.

Per case: mean, standard deviation and RMS (= sqrt(mean^2 + std^2)) of the position
estimation error over the test half, the % improvement of RMS over Gauss-Markov, and the RMS
the filter itself claims (``Filter sigma``, from its covariance: a consistent filter has it
close to the RMS).  A sweep gives FOS at every L of 4..10 at 0.1 m.  Tables (Markdown, CSV,
LaTeX) and a figure go to ``studies/results/kalman_static/``.

Run: ``python studies/kalman_static.py`` (about 2.5 minutes of CPU, the filter runs spread
over the cores).
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from itertools import repeat
from pathlib import Path

import numpy as np
import pandas as pd
from doc_pages import show_figure
from matplotlib.figure import Figure
from scipy.linalg import block_diag

from data_synth import make_scenario
from fosmodel import FOSModel
from fosmodel.filter import (
    KalmanFilter,
    StateSpace,
    position_velocity_error_model,
    run_filter,
    to_state_space,
)
from fosmodel.io import save_figure, write_tables
from fosmodel.models import ARModel, GaussMarkovModel
from fosmodel.typeset import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "kalman_static"
RATE = 20.0
DT = 1.0 / RATE
HOURS = 4.0
SEED = 0
SIGMAS_M = (0.01, 0.1, 1.0)
CYCLES_S = (None, 10, 30, 60, 120)  # None: an update at every sample
FOS_LAGS = range(4, 11)
SWEEP_SIGMA_M = 0.1
FIGURE_CASE = (30, 0.1)  # cycle, sigma of the figure
FIGURE_SECONDS = 600.0
GM = "1st-order GM"


def cycle_label(cycle: int | None) -> str:
    """``"20 Hz updates"`` or ``"30 s up / 30 s pred"``."""
    return "20 Hz updates" if cycle is None else f"{cycle} s up / {cycle} s pred"


# -- models ---------------------------------------------------------------------------------


def one_step_mse(model: object, y: np.ndarray) -> float:
    """One-step prediction MSE of a fitted model on ``y``."""
    return float(np.nanmean((y - model.predict(y)) ** 2))


def choose_fos_lag(train: np.ndarray) -> tuple[int, pd.DataFrame]:
    """L among FOS_LAGS with the lowest one-step MSE on the last quarter of ``train``."""
    cut = 3 * len(train) // 4
    rows = []
    for lag in FOS_LAGS:
        model = FOSModel(max_lag=lag).fit(train[:cut])
        rows.append({"L": lag, "terms": model.n_terms_,
                     "validation one-step MSE": one_step_mse(model, train[cut:])})
    frame = pd.DataFrame(rows)
    return int(frame.loc[frame["validation one-step MSE"].idxmin(), "L"]), frame


def fit_models(train: np.ndarray, fos_lags: list[int]) -> dict[str, object]:
    """Gauss-Markov, AR(4) by Burg and FOS at each maximum lag of ``fos_lags``."""
    models = {GM: GaussMarkovModel(rate=RATE).fit(train),
              "AR(4) Burg": ARModel(4, "burg").fit(train)}
    for lag in fos_lags:
        models[f"FOS L={lag}"] = FOSModel(max_lag=lag).fit(train)
    return models


# -- the filter -----------------------------------------------------------------------------


def integrate(a: np.ndarray) -> np.ndarray:
    """Position from acceleration as the filter propagates it: v[k] = v[k-1] + dt a[k-1]."""
    v = DT * np.r_[0.0, np.cumsum(a[:-1])]
    return DT * np.r_[0.0, np.cumsum(v[:-1])]


def updated(n: int, cycle: int | None) -> np.ndarray:
    """Samples with a position update: all, or the first half of each 2*cycle period."""
    if cycle is None:
        return np.ones(n, dtype=bool)
    return (np.arange(n) * DT) % (2 * cycle) < cycle


def position_error(model: object, accel: np.ndarray, noise: np.ndarray, sigma: float,
                   cycle: int | None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`filter_position_error` with a fitted model's shaping filter, started from its
    stationary covariance."""
    error = to_state_space(model)
    return filter_position_error(error, error.stationary_covariance(), accel, noise, sigma,
                                 cycle)


def filter_position_error(error: StateSpace, p0_error: np.ndarray, accel: np.ndarray,
                          noise: np.ndarray, sigma: float,
                          cycle: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Estimated minus true position error at samples 1..N-1 (sample 0: both zero), and the
    filter's variance of it, with the error model ``error`` started from ``p0_error``."""
    system = position_velocity_error_model(error, DT)
    p0 = block_diag(np.zeros((2, 2)), p0_error)
    kf = KalmanFilter.from_state_space(system, [[sigma**2]], np.zeros(system.n_states), p0)
    truth = integrate(accel - error.mu)
    z = np.where(updated(len(truth), cycle), truth + sigma * noise, np.nan)
    inputs = error.input_matrix(None, len(truth))[1:] if error.n_inputs else None
    run = run_filter(kf, z[1:], inputs)
    return run.x[:, 0] - truth[1:], run.variance[:, 0]


def statistics(err: np.ndarray, variance: np.ndarray) -> dict[str, float]:
    """Park's (2004) mean, std and RMS of the error, and the RMS the filter claims."""
    mean, std = float(np.mean(err)), float(np.std(err))
    return {"Mean [m]": mean, "St.D [m]": std, "RMS [m]": float(np.hypot(mean, std)),
            "Filter sigma [m]": float(np.sqrt(np.mean(variance)))}


def improvement(frame: pd.DataFrame) -> pd.Series:
    """% RMS improvement over Gauss-Markov within each (case, sigma) group."""
    rms = frame["RMS [m]"]
    gm = rms.where(frame["Model"] == GM).groupby([frame["Case"], frame["sigma_R [m]"]])
    gm = gm.transform("first")
    return 100.0 * (gm - rms) / gm


# -- the study ------------------------------------------------------------------------------


def run_jobs(models: dict[str, object], accel: np.ndarray,
             jobs: list[tuple[int | None, float, str]]) -> tuple[pd.DataFrame, dict]:
    """Statistics per job ``(cycle, sigma, model name)``, the runs spread over processes;
    the errors of the figure's case."""
    noise = np.random.default_rng(SEED + 1).standard_normal(len(accel))
    with ProcessPoolExecutor() as pool:
        errors = pool.map(position_error, [models[n] for _, _, n in jobs], repeat(accel),
                          repeat(noise), [s for _, s, _ in jobs], [c for c, _, _ in jobs])
        rows, traces = [], {}
        for (cycle, sigma, name), (err, variance) in zip(jobs, errors):
            rows.append({"Case": cycle_label(cycle), "sigma_R [m]": sigma, "Model": name,
                         **statistics(err, variance)})
            if (cycle, sigma) == FIGURE_CASE:
                traces[name] = err
    return pd.DataFrame(rows), traces


def figure(traces: dict[str, np.ndarray]) -> Figure:
    """Position estimation error of each model over the first minutes of FIGURE_CASE."""
    cycle, sigma = FIGURE_CASE
    n = int(FIGURE_SECONDS * RATE)
    t = np.arange(1, n + 1) * DT
    fig = Figure(figsize=(10, 4.2), layout="constrained")
    ax = fig.subplots()
    for start in np.arange(cycle, FIGURE_SECONDS, 2 * cycle):
        ax.axvspan(start, start + cycle, color="0.92", lw=0)
    for name, err in traces.items():
        ax.plot(t, err[:n], lw=0.8, label=name)
    ax.set_xlabel("time into the test half (s); shaded: prediction only")
    ax.set_ylabel("position estimation error (m)")
    ax.set_title(f"Static test, {cycle_label(cycle)}, position updates sigma {sigma:g} m")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def seed_tables(frame: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """The three tables of Park (2004) (5.1: 20 Hz; 5.2: 30/30 s; 5.3: cycles at 0.1 m)."""
    cols = ["sigma_R [m]", "Model", "Mean [m]", "St.D [m]", "RMS [m]", "% Improv.",
            "Filter sigma [m]"]
    return {
        "table_20hz": frame[frame["Case"] == cycle_label(None)][cols],
        "table_30s": frame[frame["Case"] == cycle_label(30)][cols],
        "table_cycles": frame[frame["sigma_R [m]"] == SWEEP_SIGMA_M][["Case", *cols[1:]]],
    }


def lag_sweep(frame: pd.DataFrame, models: dict[str, object], test: np.ndarray) -> pd.DataFrame:
    """RMS per cycle case at SWEEP_SIGMA_M and test one-step MSE of every model."""
    rows = frame[frame["sigma_R [m]"] == SWEEP_SIGMA_M]
    sweep = rows.pivot_table(index="Model", columns="Case", values="RMS [m]", sort=False)
    sweep = sweep.reindex(list(models))
    sweep.columns = [f"RMS [m], {c}" for c in sweep.columns]
    sweep.insert(0, "test one-step MSE", [one_step_mse(m, test) for m in models.values()])
    return sweep.reset_index()


def main() -> None:
    rec = make_scenario("paper_accel_y", duration=HOURS * 3600, rate=RATE, seed=SEED)
    y = rec.columns[rec.target]
    train, test = y[: len(y) // 2], y[len(y) // 2:]
    best, lag_table = choose_fos_lag(train)
    fits = fit_models(train, list(FOS_LAGS))
    models = {k: v for k, v in fits.items() if not k.startswith("FOS") or k == f"FOS L={best}"}
    jobs = [(c, s, n) for c in CYCLES_S for s in SIGMAS_M for n in models]
    jobs += [(c, SWEEP_SIGMA_M, n) for c in CYCLES_S for n in fits if n not in models]
    rows, traces = run_jobs(fits, test, jobs)
    frame = rows[rows["Model"].isin(list(models))].reset_index(drop=True)
    frame.insert(frame.columns.get_loc("RMS [m]") + 1, "% Improv.", improvement(frame))
    sweep = lag_sweep(rows, fits, test)

    OUT.mkdir(parents=True, exist_ok=True)
    tables = {"all_cases": frame, **seed_tables(frame), "fos_lag_choice": lag_table,
              "fos_lag_sweep": sweep}
    for stem, table in tables.items():
        write_tables(table, OUT, stem)
        print(f"\n## {stem}\n\n{markdown_table(table, digits=4)}")
    save_figure(figure(traces), OUT, "position_error_30s")
    show_figure(OUT / "position_error_30s.png", "kalman_static_position_error_30s.png")
    print(f"\nFOS lag chosen: L={best}; results in {OUT}")


if __name__ == "__main__":
    main()
