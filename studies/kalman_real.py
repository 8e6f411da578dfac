"""Which error model to hand a filter: GM, AR, FOS, the Allan model, the FOS filter model and
the loop's final model.

Every model is judged in the aided filter a navigator runs (:mod:`fosmodel.filter.aided`): on
data it was not fitted on, position fixes of standard deviation 0.1 m in update/prediction
cycles of 30/30, 60/60, 120/120 s and 10/10 min (a cycle where the filtered half holds at
least two of its periods), free prediction in between.

Records (each axis split in halves: fitted on the first, filtered on the second):

- real: the gyros and accelerometers of the six ADIS16405 sessions (36 axes); the MPU-6050
  10-min session (sunsided, six axes, with its die temperature) and the 7.5-min one
  (tomisuarez2); the MTi-G gyro (outliers clipped, as the loader's ``outliers="clip"`` does);
  100 Hz records are block-averaged to 20 Hz (means of 5 samples, as ``kalman_static.py``);
- synthetic (:mod:`data_synth`): the day-long ``temperature_sweep`` (gx and ax driven by the
  temperature, ay not) and its control, the first thermal-calibration session
  (:func:`data_synth.thermal.thermal_sessions`, all six axes driven, 2 h at 1 Hz), and two
  15-min records with a wandering level (``slow_random_walk``, and
  ``slow_random_walk_temperature`` with its switching temperature).

Accelerometers (m/s^2) drive the 1-D position/velocity error filter (Park 2004, eq. 5.7);
gyros (rad/s) drive their tilt analogue, built here by :func:`tilt_system`: the angle error
integrates the gyro error and tilts gravity into the velocity error (``dv += dt g dtheta``),
so a gyro's error reaches position as ``g * angle``.  The true position error is the double
(triple) integral of the error left after the model's calibrated bias.

Models, each fitted on the first half: the 1st-order Gauss-Markov, AR(4) by Burg and FOS
(L chosen among 4..10 as ``kalman_static.py`` does), the three-term Allan model
(:func:`~fosmodel.filter.allan_statespace.allan_state_space`), the FOS filter model
(:class:`~fosmodel.filter.fos_filter.FOSFilterModel`, given the temperature where the record
has one), the loop's final model (:func:`fit_loop`), and an oracle: the Allan model fitted
on the *filtered* half (the training half's mean kept), the bound of what a model of these
terms fitted elsewhere can do.

Per axis, cycle and model: the RMS position estimation error, the filter's sigma over it, the
NEES, and the RMS over the Allan model's.  Tables go to ``studies/results/kalman_real/``
(``all_cases``, ``summary``, ``must_hold``, ``fos_filter_axes``), the figure ``in_filter``,
and the page section ``kalman-real`` of ``docs/pages/kalman.md``.

Run: ``python studies/kalman_real.py [--jobs 2]`` (about 7 minutes on 2 cores).  It skips
with one line when ``../shared/data`` is absent.
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from doc_pages import replace_section, show_figure
from kalman_static import choose_fos_lag
from matplotlib.figure import Figure
from scipy.linalg import block_diag

from data_synth import make_scenario
from data_synth.thermal import thermal_sessions
from fosmodel import FOSModel, InputError
from fosmodel.filter import (
    AidedRun,
    FOSFilterModel,
    StateSpace,
    accelerometer_run,
    aided_position_run,
    allan_state_space,
    initial_covariance,
    to_state_space,
)
from fosmodel.io import load_mpu6050_static, load_record, save_figure, write_tables
from fosmodel.loop import LoopConfig, close_loop, refit_on_all
from fosmodel.models import ARModel, GaussMarkovModel
from fosmodel.noise import STANDARD_GRAVITY, allan_deviation, fit_noise
from fosmodel.typeset import markdown_table

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
OUT = REPO / "studies" / "results" / "kalman_real"
JOBS = int(sys.argv[sys.argv.index("--jobs") + 1]) if "--jobs" in sys.argv else 2
SIGMA_M = 0.1
CYCLES_S = (30, 60, 120, 600)
SEED = 0
GM, AR, FOS, ALLAN, FFM, LOOPM, ORACLE = ("1st-order GM", "AR(4) Burg", "FOS", "Allan",
                                          "FOS filter", "Loop final", "Oracle Allan")
MODELS = (GM, AR, FOS, ALLAN, FFM, LOOPM, ORACLE)
CONSISTENT = (0.7, 1.5)  # the band for the filter's sigma over its actual RMS
DEG = np.pi / 180.0
ADIS_COLUMNS = ("gx_dps", "gy_dps", "gz_dps", "ax_g", "ay_g", "az_g")


@dataclass
class Axis:
    """One sensor axis: its record in SI units at its rate, and a temperature if measured."""

    group: str  # "real" or "synthetic"
    record: str
    axis: str
    sensor: str  # "accel" (m/s^2) or "gyro" (rad/s)
    y: np.ndarray
    rate: float
    temp: np.ndarray | None = None
    driven: bool = False  # a known (synthetic) or measured temperature driver
    fits: dict = field(default_factory=dict)


def block(y: np.ndarray, m: int) -> np.ndarray:
    n = len(y) // m * m
    return y[:n].reshape(-1, m).mean(axis=1)


def si(values: np.ndarray, column: str) -> tuple[str, np.ndarray]:
    """The sensor and the values in m/s^2 or rad/s, from a column's unit suffix."""
    if column.endswith("_g") or column in ("ax", "ay", "az"):
        return "accel", values * STANDARD_GRAVITY
    if column.endswith("_mps2"):
        return "accel", values
    if column.endswith("_dps") or column in ("gx", "gy", "gz"):
        return "gyro", values * DEG
    return "gyro", values  # the MTi-G: rad/s


def load_axes() -> list[Axis]:
    axes = []

    def add(group, record, columns, rate, m, temp=None, driven=(), names=None):
        for column in names or columns:
            sensor, y = si(np.asarray(columns[column], dtype=float), column)
            t = None if temp is None else block(np.asarray(temp, dtype=float), m)
            axes.append(Axis(group, record, column, sensor, block(y, m), rate / m, t,
                             column in driven))

    for k in range(1, 7):
        rec = load_record(DATA / "adis16405" / f"imu{k}.csv.gz", rate=100, outliers="keep")
        add("real", f"ADIS16405 imu{k}", {c: rec.column(c) for c in ADIS_COLUMNS}, 100.0, 5)
    rec = load_record(DATA / "mpu6050_sunsided" / "unmoved-with-x-pointing-forward-10min.csv.gz",
                      uniform=True)
    cols = {c: rec.column(c) for c in rec.names}
    add("real", "MPU-6050 sunsided", cols, rec.rate, 5, temp=cols["temp_c"],
        driven=("ax_g", "ay_g", "az_g", "gx_dps", "gy_dps", "gz_dps"),
        names=[c for c in rec.names if c != "temp_c"])
    rec = load_mpu6050_static()
    add("real", "MPU-6050 tomisuarez2", {c: rec.column(c) for c in rec.names}, rec.rate, 5)
    rec = load_record(DATA / "mtig_contaminated" / "gyro_x.csv.gz", rate=100, outliers="clip")
    add("real", "MTi-G", {"gyro_x": rec.column("gyro_x")}, 100.0, 5)

    sweep = make_scenario("temperature_sweep", seed=SEED)
    add("synthetic", "temperature_sweep", sweep.columns, 1.0, 1, sweep.columns["temp_c"],
        driven=("gx_dps", "ax_mps2"), names=["gx_dps", "ax_mps2", "ay_mps2"])
    control = make_scenario("temperature_sweep_control", seed=SEED)
    add("synthetic", "temperature_sweep_control", control.columns, 1.0, 1,
        control.columns["temp_c"], names=["gx_dps", "ax_mps2"])
    session = thermal_sessions(SEED)[0]
    add("synthetic", "thermal session", session.columns, 1.0, 1, session.columns["temp_c"],
        driven=ADIS_COLUMNS[:3] + ("ax_mps2", "ay_mps2", "az_mps2"),
        names=[c for c in session.columns if c != "temp_c"])
    walk = make_scenario("slow_random_walk", seed=SEED)
    add("synthetic", "slow_random_walk", walk.columns, walk.rate, 5, names=["gyro_x"])
    walk_t = make_scenario("slow_random_walk_temperature", seed=SEED)
    add("synthetic", "slow_random_walk_temperature", walk_t.columns, walk_t.rate, 5,
        walk_t.columns["temp_c"], driven=("gyro_x",), names=["gyro_x"])
    for a in axes:  # the sweep's gyros are in deg/s, named gyro_x in the slow records
        if a.record.startswith("slow_"):
            a.y = a.y * DEG
    return axes


# -- fitting ---------------------------------------------------------------------------------


def _stationary(error: StateSpace) -> tuple[StateSpace, np.ndarray] | None:
    try:
        return error, error.stationary_covariance()
    except InputError:  # an unstable fit has no starting covariance: left out, and counted
        return None


def fit_axis(a: Axis) -> dict:
    """Every model of an axis fitted on the first half: name -> (error, P0, test inputs)."""
    half = len(a.y) // 2
    train, test = a.y[:half], a.y[half:]
    out: dict = {}
    lag, _ = choose_fos_lag(train)
    for name, model in ((GM, GaussMarkovModel(rate=a.rate)), (AR, ARModel(4, "burg")),
                        (FOS, FOSModel(max_lag=lag))):
        made = _stationary(to_state_space(model.fit(train)))
        # a FOS model's constant (its intercept) is its one input, "1"
        out[name] = None if made is None else (
            *made, made[0].input_matrix(None, len(test)) if made[0].n_inputs else None)
    units = "m/s^2" if a.sensor == "accel" else "rad/s"
    for name, part in ((ALLAN, train), (ORACLE, test)):
        fit = fit_noise(allan_deviation(part, a.rate, units=units, sensor=a.sensor))
        error = allan_state_space(fit, mu=float(np.mean(train)))
        out[name] = (error, initial_covariance(error, half), None)
    exog = None if a.temp is None else {"temp_c": a.temp[:half]}
    res = FOSFilterModel().fit(train, a.rate, exog=exog)
    inputs = (res.input_matrix({"temp_c": a.temp[half:]}, len(test)) if res.drivers
              else None)
    out[FFM] = (res.to_state_space(), res.initial_covariance(), inputs)
    out[LOOPM], out["_loop"] = fit_loop(a, units)
    out["_fos_lag"], out["_ffm"] = lag, res
    return out


def fit_loop(a: Axis, units: str) -> tuple[tuple | None, str]:
    """The loop's final model, as ``close-loop --model`` hands it on, fitted on the first half.

    The loop runs on the first half alone (its own fitting, evaluation and prediction
    segments inside it, the temperature its one channel where measured), the model it hands
    on is refitted on that whole half, and its state space starts from
    :func:`initial_covariance`.  None, with the reason, where the loop refuses the record or
    keeps terms no linear filter holds (written for an EKF, not judged here).
    """
    half = len(a.y) // 2
    channels = {} if a.temp is None else {"temp_c": a.temp[:half]}
    try:
        res = close_loop(a.y[:half], channels, LoopConfig(rate=a.rate, sensor=a.sensor,
                                                         units=units))
        error = to_state_space(refit_on_all(res, a.y[:half]))
    except InputError as exc:
        return None, str(exc).split(";")[0]
    kept = "; ".join(s.effect.describe() for s in res.steps) or "none"
    full = {} if a.temp is None else {"temp_c": a.temp}
    inputs = error.input_matrix(full, len(a.y))[half:] if error.n_inputs else None
    return (error, initial_covariance(error, half), inputs), kept


# -- the filters -----------------------------------------------------------------------------


def tilt_system(error: StateSpace, dt: float) -> StateSpace:
    """The 1-D tilt analogue of the position/velocity error filter for a gyro error model.

    States ``dp, dv, dtheta`` then the error model's: ``dtheta[k] = dtheta[k-1] + dt w[k-1]``
    with ``w = H x`` the gyro error (rad/s), ``dv[k] = dv[k-1] + dt g dtheta[k-1]``,
    ``dp[k] = dp[k-1] + dt dv[k-1]``; the fix measures ``dp``.
    """
    p = error.n_states
    phi = np.zeros((p + 3, p + 3))
    phi[:3, :3] = [[1.0, dt, 0.0], [0.0, 1.0, dt * STANDARD_GRAVITY], [0.0, 0.0, 1.0]]
    phi[2, 3:] = dt * error.H[0]
    phi[3:, 3:] = error.Phi
    return StateSpace(Phi=phi, B=np.vstack([np.zeros((3, error.n_inputs)), error.B]),
                      G=np.vstack([np.zeros((3, error.G.shape[1])), error.G]),
                      H=np.eye(1, p + 3), Q=error.Q.copy(), mu=0.0,
                      state_names=("dp", "dv", "dtheta", *error.state_names),
                      input_names=error.input_names)


def tilt_truth(omega: np.ndarray, dt: float) -> np.ndarray:
    """The position error a gyro error makes through the tilt, discretised as the filter."""
    theta = dt * np.r_[0.0, np.cumsum(omega[:-1])]
    v = dt * STANDARD_GRAVITY * np.r_[0.0, np.cumsum(theta[:-1])]
    return dt * np.r_[0.0, np.cumsum(v[:-1])]


def run_one(job: tuple) -> AidedRun:
    sensor, error, p0, test, noise, cycle, dt, inputs = job
    if sensor == "accel":
        return accelerometer_run(error, p0, test, noise, SIGMA_M, cycle, dt, inputs)
    system = tilt_system(error, dt)
    return aided_position_run(system, block_diag(np.zeros((3, 3)), p0),
                              tilt_truth(test - error.mu, dt), noise, SIGMA_M, cycle, dt,
                              inputs)


def cycles_for(a: Axis) -> list[int]:
    """The cycles whose period fits twice into the filtered half."""
    half_s = (len(a.y) - len(a.y) // 2) / a.rate
    return [c for c in CYCLES_S if 4 * c <= half_s]


def run_filters(axes: list[Axis]) -> pd.DataFrame:
    keys, jobs = [], []
    for i, a in enumerate(axes):
        test = a.y[len(a.y) // 2:]
        noise = np.random.default_rng([SEED, i]).standard_normal(len(test))
        for cycle in cycles_for(a):
            for name in MODELS:
                made = a.fits[name]
                if made is None:
                    continue
                error, p0, inputs = made
                # a compensation is the model's feedthrough D: the client subtracts it
                reading = test if inputs is None or not error.D.any() else \
                    test - inputs @ error.D[0]
                keys.append((a, cycle, name))
                jobs.append((a.sensor, error, p0, reading, noise, cycle, 1.0 / a.rate, inputs))
    with ProcessPoolExecutor(JOBS) as pool:
        runs = list(pool.map(run_one, jobs, chunksize=8))
    rows = [{"Group": a.group, "Record": a.record, "Axis": a.axis, "Sensor": a.sensor,
             "Driven": a.driven, "Cycle [s]": cycle, "Model": name, "RMS [m]": run.rms,
             "Filter sigma [m]": run.sigma, "Sigma / RMS": run.sigma_over_rms,
             "NEES": run.nees} for (a, cycle, name), run in zip(keys, runs)]
    frame = pd.DataFrame(rows)
    allan = frame[frame["Model"] == ALLAN].set_index(["Record", "Axis", "Cycle [s]"])["RMS [m]"]
    ref = allan.reindex(pd.MultiIndex.from_frame(frame[["Record", "Axis", "Cycle [s]"]]))
    frame["RMS / Allan"] = frame["RMS [m]"].to_numpy() / ref.to_numpy()
    return frame


# -- tables ----------------------------------------------------------------------------------


def summarise(frame: pd.DataFrame) -> pd.DataFrame:
    lo, hi = CONSISTENT
    groups = frame.groupby(["Group", "Cycle [s]", "Model"], sort=False)
    ratio, rel = groups["Sigma / RMS"], groups["RMS / Allan"]
    return pd.DataFrame({
        "Axes": groups.size(),
        "Median RMS [m]": groups["RMS [m]"].median(),
        "Median RMS / Allan": rel.median(),
        "Share RMS <= Allan": rel.apply(lambda r: float((r <= 1.0).mean())),
        "Median sigma / RMS": ratio.median(), "Min sigma / RMS": ratio.min(),
        "Max sigma / RMS": ratio.max(),
        f"Share sigma / RMS in {lo:g}-{hi:g}": ratio.apply(
            lambda r: float(r.between(lo, hi).mean())),
        "Median NEES": groups["NEES"].median(),
    }).reset_index()


def must_hold(frame: pd.DataFrame) -> pd.DataFrame:
    """The issue's conditions on the FOS filter model, each with what the run gives."""
    lo, hi = CONSISTENT
    ffm = frame[frame["Model"] == FFM]
    real = ffm[ffm["Group"] == "real"]
    rows = []
    for cycle, part in real.groupby("Cycle [s]"):
        med = part["RMS / Allan"].median()
        rows.append({"Condition": f"real axes, median RMS / Allan at {cycle} s <= 0.9",
                     "Value": f"{med:.3f} ({len(part)} axes)", "Holds": bool(med <= 0.9)})
    share = float((real["RMS / Allan"] <= 1.0).mean())
    rows.append({"Condition": "real axis-cycles with RMS <= Allan's >= 80 %",
                 "Value": f"{100 * share:.0f} % of {len(real)}", "Holds": share >= 0.8})
    for group, part in ffm.groupby("Group"):
        inside = part["Sigma / RMS"].between(lo, hi)
        rows.append({"Condition": f"{group} axis-cycles with sigma / RMS in {lo:g}-{hi:g}",
                     "Value": f"{int(inside.sum())} of {len(part)} "
                              f"({part['Sigma / RMS'].min():.2f}-"
                              f"{part['Sigma / RMS'].max():.2f})",
                     "Holds": bool(inside.all())})
    driven = ffm[ffm["Driven"]]
    for (record, axis), part in driven.groupby(["Record", "Axis"], sort=False):
        last = part[part["Cycle [s]"] == part["Cycle [s]"].max()].iloc[0]
        rows.append({"Condition": f"driver record {record} {axis}: RMS / Allan at "
                                  f"{last['Cycle [s]']} s <= 0.5",
                     "Value": f"{last['RMS / Allan']:.3f}",
                     "Holds": bool(last["RMS / Allan"] <= 0.5)})
    return pd.DataFrame(rows)


def fos_filter_axes(axes: list[Axis]) -> pd.DataFrame:
    rows = []
    for a in axes:
        res = a.fits["_ffm"]
        gms = [c for c in res.components if c.kind == "gauss-markov"]
        walk = [c for c in res.components if c.kind == "random walk"][0]
        rows.append({"Record": a.record, "Axis": a.axis, "Rate [Hz]": a.rate,
                     "N": res.white_density,
                     "GM time constants [s]": ", ".join(f"{c.tau_s:g}" for c in gms) or "-",
                     "GM sigmas": ", ".join(f"{np.sqrt(c.variance):.3g}" for c in gms) or "-",
                     "K": np.sqrt(walk.variance),
                     "Drivers": ", ".join(f"{d.name}: {d.coef:.3g}" for d in res.drivers)
                     or "-", "FOS L": a.fits["_fos_lag"],
                     "Unstable fits left out": ", ".join(
                         n for n in (GM, AR, FOS) if a.fits[n] is None) or "-",
                     "Loop final model": (a.fits["_loop"] if a.fits[LOOPM] is not None
                                          else f"not in the filter: {a.fits['_loop']}")})
    return pd.DataFrame(rows)


def figure(frame: pd.DataFrame) -> Figure:
    fig = Figure(figsize=(12, 4.6), layout="constrained")
    left, right = fig.subplots(1, 2)
    real = frame[frame["Group"] == "real"]
    shown = [m for m in MODELS if m != ALLAN]
    for j, cycle in enumerate(CYCLES_S):
        for i, name in enumerate(shown):
            part = real[(real["Cycle [s]"] == cycle) & (real["Model"] == name)]
            x = i + 0.18 * (j - 1.5) + np.linspace(-0.05, 0.05, len(part))
            left.semilogy(x, part["RMS / Allan"], "o", ms=2.5, color=f"C{j}",
                          label=f"{cycle} s" if i == 0 else None)
        for i, name in enumerate(MODELS):
            part = real[(real["Cycle [s]"] == cycle) & (real["Model"] == name)]
            x = i + 0.18 * (j - 1.5) + np.linspace(-0.05, 0.05, len(part))
            right.semilogy(x, part["Sigma / RMS"], "o", ms=2.5, color=f"C{j}")
    left.axhline(1.0, color="0.3", lw=0.8)
    left.set_xticks(range(len(shown)), shown, fontsize="small")
    left.set_ylabel("RMS position error / the Allan model's")
    left.set_title("real axes: error against the Allan model's")
    left.legend(fontsize="small", title="cycle")
    right.axhspan(*CONSISTENT, color="0.92", lw=0)
    right.axhline(1.0, color="0.3", lw=0.8)
    right.set_xticks(range(len(MODELS)), MODELS, fontsize="small")
    right.set_ylabel("filter sigma / actual RMS")
    right.set_title("real axes: does the filter know its error?")
    for ax in (left, right):
        ax.grid(True, which="both", axis="y", alpha=0.3)
    return fig


# -- the page --------------------------------------------------------------------------------


def page_section(frame: pd.DataFrame, summary: pd.DataFrame, holds: pd.DataFrame,
                 axes: list[Axis], link: str, seconds: float) -> str:
    real = [a for a in axes if a.group == "real"]
    synth = [a for a in axes if a.group == "synthetic"]
    lines = [
        f"`python studies/kalman_real.py` ({seconds / 60:.0f} min on {JOBS} cores; it needs "
        f"`../shared/data`): {len(real)} real axes ({sum(a.sensor == 'gyro' for a in real)} "
        f"gyros) and {len(synth)} synthetic ones, each fitted on its first half and filtered "
        "on its second, position fixes σ 0.1 m. Per group, cycle and model: the median RMS "
        "position error over the Allan model's, the share of axes at or below it, and the "
        "filter's sigma over its actual error (median and range) and NEES (median).", ""]
    for group in ("real", "synthetic"):
        part = summary[summary["Group"] == group]
        table = part.pivot_table(index="Model", columns="Cycle [s]",
                                 values="Median RMS / Allan", sort=False).reindex(list(MODELS))
        table.columns = [f"RMS / Allan, {c} s" for c in table.columns]
        ratio = part.groupby("Model", sort=False).agg(
            lo=("Min sigma / RMS", "min"), hi=("Max sigma / RMS", "max"),
            med=("Median sigma / RMS", "median"), nees=("Median NEES", "median"),
            share=("Share RMS <= Allan", "mean")).reindex(list(MODELS))
        table["Share <= Allan"] = ratio["share"].map(lambda v: f"{100 * v:.0f} %")
        table["Sigma / RMS"] = [f"{m:.2f} ({lo:.2f}-{hi:.2f})" for m, lo, hi in
                                zip(ratio["med"], ratio["lo"], ratio["hi"])]
        table["NEES"] = ratio["nees"]
        lines += [f"**{group.capitalize()} axes.**", "",
                  markdown_table(table.reset_index(), digits=3), ""]
    lines += verdict(frame, axes)
    lines += ["What was asked of the FOS filter model, and what this run gives:", "",
              markdown_table(holds, digits=3), "",
              f"![RMS over the Allan model's, and filter sigma over RMS]({link})", ""]
    return "\n".join(lines)


def _span(values: pd.Series) -> str:
    return f"{values.min():.2f}-{values.max():.2f}"


def verdict(frame: pd.DataFrame, axes: list[Axis]) -> list[str]:
    """The run's answers in sentences: the FOS filter model against the Allan model and the
    oracle, its consistency, and what its drivers bought."""
    real = frame[frame["Group"] == "real"]
    med = real.groupby(["Model", "Cycle [s]"])["RMS / Allan"].median()
    ffm = real[real["Model"] == FFM]
    lo, hi = CONSISTENT
    inside = ffm["Sigma / RMS"].between(lo, hi)
    above = ffm["Sigma / RMS"] > hi
    share = 100 * float((ffm["RMS / Allan"] <= 1.0).mean())
    allan_in = real[real["Model"] == ALLAN]["Sigma / RMS"].between(lo, hi)
    kept = [a for a in axes if a.fits["_ffm"].drivers]
    driven = frame[(frame["Model"] == FFM) & frame["Driven"]]
    longest = driven[driven["Cycle [s]"] == driven.groupby(["Record", "Axis"])["Cycle [s]"]
                     .transform("max")]
    gained = longest[longest["RMS / Allan"] <= 0.5]
    fitted = med.drop([ALLAN, ORACLE, LOOPM], level=0)
    loop = real[real["Model"] == LOOPM]
    loop_in = loop["Sigma / RMS"].between(lo, hi)
    n_real = len({(a.record, a.axis) for a in axes if a.group == "real"})
    n_loop = len(loop.groupby(["Record", "Axis"]))
    return [
        f"On the real axes the FOS filter model's median RMS is {_span(med[FFM])} times the "
        f"Allan model's over the cycles (at or below it on {share:.0f} % of {len(ffm)} "
        f"axis-cycles); the oracle, the Allan model fitted on the filtered half "
        f"itself, reaches {_span(med[ORACLE])}, the bound on what a model of these terms fitted "
        f"on another stretch can gain. GM, AR(4) and FOS of the samples are "
        f"{_span(fitted.drop(FFM, level=0))} times the Allan model's. The FOS filter model's sigma "
        f"over its actual RMS lies in {lo:g}-{hi:g} on {int(inside.sum())} of {len(ffm)} real "
        f"axis-cycles ({_span(ffm['Sigma / RMS'])}; the Allan model's on "
        f"{int(allan_in.sum())} of {int(allan_in.size)}); of the {int((~inside).sum())} "
        f"outside, {int(above.sum())} claim more error than they make, "
        f"{int((above & (ffm['Cycle [s]'] == max(CYCLES_S))).sum())} of those at the "
        f"{max(CYCLES_S) // 60}-min cycle, where its random walk dominates what it claims.",
        "",
        f"The loop's final model (fitted on the first half by the loop, refitted there on "
        f"all of it, as `close-loop --model` writes it) is in the filter on {n_loop} of "
        f"{n_real} real axes"
        + (" (the others keep terms only an EKF holds, or the loop refused the half: "
           "`fos_filter_axes`)" if n_loop < n_real else "")
        + f": its median RMS is {_span(med[LOOPM])} times the "
        f"Allan model's over the cycles, its sigma over RMS in {lo:g}-{hi:g} on "
        f"{int(loop_in.sum())} of {len(loop)} axis-cycles ({_span(loop['Sigma / RMS'])}).",
        "",
        f"A driver was kept on {len(kept)} of {len(axes)} axes ("
        + ", ".join(f"{a.record} {a.axis}" for a in kept) + "). At the longest cycle the FOS "
        f"filter model's RMS is at most half the Allan model's on {len(gained)} of "
        f"{len(longest)} axes with a temperature ("
        + ", ".join(f"{r['Record']} {r['Axis']} {r['RMS / Allan']:.2f}"
                    for _, r in longest.iterrows()) + ").",
        ""]


def main() -> None:
    if not DATA.is_dir():
        print(f"skipping: {DATA} not found (the real recordings are not part of this "
              "repository; see the README's 'Data and licences')")
        return
    start = time.perf_counter()
    axes = load_axes()
    with ProcessPoolExecutor(JOBS) as pool:
        for a, fits in zip(axes, pool.map(fit_axis, axes)):
            a.fits = fits
    print(f"fitted {len(axes)} axes in {time.perf_counter() - start:.0f} s", flush=True)
    frame = run_filters(axes)
    OUT.mkdir(parents=True, exist_ok=True)
    summary, holds = summarise(frame), must_hold(frame)
    tables = {"all_cases": frame, "summary": summary, "must_hold": holds,
              "fos_filter_axes": fos_filter_axes(axes)}
    for stem, table in tables.items():
        write_tables(table, OUT, stem)
        print(f"\n## {stem}\n\n{markdown_table(table, digits=4)}")
    save_figure(figure(frame), OUT, "in_filter")
    link = show_figure(OUT / "in_filter.png", "kalman_real_in_filter.png")
    seconds = time.perf_counter() - start
    replace_section("kalman-real", page_section(frame, summary, holds, axes, link, seconds))
    print(f"\n{seconds:.0f} s; results in {OUT}")


if __name__ == "__main__":
    main()
