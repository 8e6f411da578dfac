"""Arrays of gyros measuring one rate (Koldbæk and Totu 2011, chapters 6-10).

1. Koldbæk and Totu's (2011) closed-form averaging drift (Tables 10.1-10.2, eqs. 7.13-7.16).
2. The steady-state Kalman gain of the virtual-gyro filter: the three-gyro example of eq. 8.8
   against the thesis's converged gain (eq. 8.9) and our own recursive run.
3. Table 10.3 (unequal correlations Q_3, Q_5): averaging in closed form and the Kalman
   filter's exact angle-error standard deviation, where the thesis has only simulations.
4. Monte Carlo on data_synth arrays (Koldbæk and Totu 2011, Table 5.1 gyros, 102.4 Hz, one
   hour, 100 runs):
   gyro 1 alone, the average and the constant-gain Kalman filter, against the closed forms.
5. FOS of gyro 1's error with the other seven gyros as inputs, against AR of its own past.

Writes tables and ``drift.png`` to ``studies/results/gyro_array/``.

Run: ``python studies/gyro_array.py`` (about ten minutes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from doc_pages import show_figure
from matplotlib.figure import Figure

from data_synth import CorrelatedRandomWalk, CorrelatedWhiteNoise, compose, make_scenario
from data_synth.scenarios import ARRAY_ARW, ARRAY_RRW
from fosmodel.filter import (
    CORR_EQ_8_8,
    CORR_Q3,
    CORR_Q5,
    ArrayModel,
    angle_error_std,
    averaging_angle_std,
    averaging_rate_std,
    conditional_variance,
    constant_gain_filter,
    covariance,
    cross_gyro_comparison,
    kalman_angle_std,
    recursive_gain,
    steady_state_gain,
)
from fosmodel.io import save_figure, write_tables, write_text
from fosmodel.typeset import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "gyro_array"
NAMES = tuple(f"gyro_{i}" for i in range(1, 9))
RATE, HOUR, RUNS, CHUNK = 102.4, 3600.0, 100, 5
#: Koldbæk and Totu (2011) eq. 8.9 (the thesis's converged recursive gain, three-gyro example).
GAIN_EQ_8_9 = np.array([
    [0.332815351545374, 0.332820262807916, 0.332827785499759],
    [3.31879037392269e-05, -7.49804087920127e-06, -2.56898612103661e-05],
    [-2.58677834142207e-06, 3.13564393958052e-05, -2.87696601089407e-05],
    [-1.32559067993142e-05, -2.12469682356657e-05, 3.45028735409536e-05]])
#: Monte-Carlo cases: name -> correlation of the bias-driving noises.
CASES = {"uncorrelated": 0.0, "rho_w = -0.1": -0.1, "Q_5 (eq. 10.3)": CORR_Q5}


def closed_form_table() -> pd.DataFrame:
    rows = [("single gyro", 1, 0.0, 1, 36.4), ("8, uncorrelated", 8, 0.0, 1, 12.87),
            ("8, rho = -0.1", 8, -0.1, 1, 7.15), ("8, rho = -0.1428571", 8, -0.1428571, 1, 1.44),
            ("8, rho = 0.3", 8, 0.3, 1, 22.56), ("8, rho = -0.1428571", 8, -0.1428571, 10, 4.57)]
    return pd.DataFrame([{
        "gyros": name, "hours": h, "angle drift (deg), eq. 7.15/7.16":
            averaging_angle_std(HOUR * h, 100.0, n_gyros=n, rho_w=rho),
        "Koldbæk and Totu (2011) (Table 10.2 / text)": thesis,
        "rate noise after 1 h (deg/s), eq. 7.13": averaging_rate_std(HOUR, 100.0, n_gyros=n,
                                                                     rho_w=rho),
    } for name, n, rho, h, thesis in rows])


def gain_tables() -> tuple[pd.DataFrame, pd.DataFrame]:
    model = ArrayModel.from_noise(3, 100.0, corr_w=CORR_EQ_8_8)
    steady, recursive = steady_state_gain(model), recursive_gain(model, 400_000)
    rows = ["omega", "b_1", "b_2", "b_3"]
    gains = pd.concat([pd.DataFrame(k, columns=["z_1", "z_2", "z_3"]).assign(state=rows, gain=g)
                       for g, k in (("steady state (DARE)", steady),
                                    ("recursive, 400000 steps", recursive),
                                    ("Koldbæk and Totu (2011) eq. 8.9", GAIN_EQ_8_9))])
    scale = np.abs(GAIN_EQ_8_9[1:]).max()
    diff = pd.DataFrame([{"pair": p, "max |difference|, rate row": np.abs(a[0] - b[0]).max(),
                          "max |difference| / max |bias gain|, bias rows":
                              np.abs(a[1:] - b[1:]).max() / scale}
                         for p, a, b in (("DARE - recursive", steady, recursive),
                                         ("DARE - eq. 8.9", steady, GAIN_EQ_8_9),
                                         ("recursive - eq. 8.9", recursive, GAIN_EQ_8_9))])
    return gains[["gain", "state", "z_1", "z_2", "z_3"]], diff


def table_10_3() -> pd.DataFrame:
    thesis = {("Q_3", 1): (9.66, 9.24, 4.23), ("Q_3", 2): (29.17, 25.91, 8.03),
              ("Q_5", 1): (13.88, 13.14, 3.23), ("Q_5", 2): (37.32, 36.98, 4.38)}
    rows = []
    for name, corr in (("Q_3", CORR_Q3), ("Q_5", CORR_Q5)):
        model = ArrayModel.from_noise(8, 100.0, corr_w=corr)
        kalman = kalman_angle_std(model, steady_state_gain(model), 720_000, every=360_000)
        for h in (1, 2):
            sim_avg, eq_avg, sim_kf = thesis[(name, h)]
            rows.append({"case": name, "hours": h, "averaging (sim, thesis)": sim_avg,
                         "averaging (eq, thesis)": eq_avg,
                         "averaging (eq. 7.16, ours)": float(angle_error_std(
                             360_000 * h, 0.01, model.cov_w, model.cov_v)),
                         "Kalman (sim, thesis)": sim_kf, "Kalman (exact, ours)": kalman[h - 1]})
    return pd.DataFrame(rows)


def array_model(corr_w) -> ArrayModel:
    """The data_synth gyro_array_8 gyros: Table 5.1 ARW/RRW at 102.4 Hz."""
    root = np.sqrt(RATE)
    return ArrayModel(covariance(np.array(ARRAY_RRW) * root, corr_w, 8),
                      covariance(np.array(ARRAY_ARW) * root, 0.0, 8), RATE)


def still_array(seed: int, corr_w) -> np.ndarray:
    if np.ndim(corr_w) == 0:
        rec = make_scenario("gyro_array_8", duration=HOUR, seed=seed, rho_rrw=corr_w)
    else:
        rec = compose([CorrelatedWhiteNoise(NAMES, ARRAY_ARW, 0.0, name="arw"),
                       CorrelatedRandomWalk(NAMES, ARRAY_RRW, corr_w, name="rrw")],
                      duration=HOUR, rate=RATE, seed=seed, target="gyro_1",
                      column_units={n: "deg/s" for n in NAMES})
    return np.column_stack([rec.columns[n] for n in NAMES])


def monte_carlo(corr_w, every: int) -> dict[str, np.ndarray]:
    """Angle errors of gyro 1, the average and the Kalman filter at every ``every`` samples."""
    gain = steady_state_gain(array_model(corr_w))
    out = {"single": [], "average": [], "kalman": []}
    for first in range(0, RUNS, CHUNK):
        z = np.stack([still_array(seed, corr_w) for seed in range(first, first + CHUNK)])
        rates = {"single": z[..., 0], "average": z.mean(axis=2),
                 "kalman": constant_gain_filter(z, gain)[..., 0]}
        for k, r in rates.items():
            out[k].append((np.cumsum(r, axis=1) / RATE)[:, every - 1 :: every])
    return {k: np.concatenate(v) for k, v in out.items()}


def closed_forms(corr_w, n_steps: int, every: int) -> dict[str, np.ndarray]:
    model = array_model(corr_w)
    steps = np.arange(every, n_steps + 1, every)
    return {"single": angle_error_std(steps, model.ts, model.cov_w, model.cov_v, np.eye(8)[0]),
            "average": angle_error_std(steps, model.ts, model.cov_w, model.cov_v),
            "kalman": kalman_angle_std(model, steady_state_gain(model), n_steps, every)}


def drift_study() -> tuple[pd.DataFrame, Figure]:
    n_steps, every = round(HOUR * RATE), round(60 * RATE)
    minutes = np.arange(1, n_steps // every + 1) * every / RATE / 60
    fig = Figure(figsize=(13, 4.2), layout="constrained")
    rows = []
    for ax, (case, corr) in zip(fig.subplots(1, len(CASES), sharey=True), CASES.items()):
        mc, cf = monte_carlo(corr, every), closed_forms(corr, n_steps, every)
        for (k, sim), color in zip(mc.items(), ("C0", "C1", "C2")):
            rms = np.sqrt(np.mean(sim**2, axis=0))
            ax.plot(minutes, cf[k], color=color, label=f"{k} (closed form / exact)")
            ax.plot(minutes[4::5], rms[4::5], "o", color=color, mfc="none",
                    label=f"{k} ({RUNS} runs)")
            rows.append({"case": case, "estimate": k, "closed form, 1 h (deg)": cf[k][-1],
                         f"Monte Carlo RMS, {RUNS} runs (deg)": rms[-1],
                         "ratio": rms[-1] / cf[k][-1],
                         "standard error of the ratio": 1 / np.sqrt(2 * RUNS)})
        ax.set_title(f"bias walks: {case}")
        ax.set_xlabel("time (min)")
        ax.grid(alpha=0.3)
    fig.axes[0].set_ylabel("angle error standard deviation (deg)")
    fig.axes[0].legend(fontsize="small")
    fig.suptitle("Still arrays of 8 gyros (data_synth, Koldbæk and Totu 2011, Table 5.1 ARW/RRW, "
                 "102.4 Hz)")
    return pd.DataFrame(rows), fig


def fos_study() -> pd.DataFrame:
    sigma_v = np.array(ARRAY_ARW) * np.sqrt(RATE)
    rows = []
    for params in ({}, {"rho_arw": 0.3}, {"rho_arw": -0.1}, {"rho_rrw": -0.1}, {"rho_rrw": 0.9}):
        for seed in range(5):
            rec = make_scenario("gyro_array_8", duration=600.0, seed=seed, **params)
            res = cross_gyro_comparison(rec.columns, "gyro_1")
            bound = conditional_variance(covariance(sigma_v, params.get("rho_arw", 0.0), 8))
            rows.append({"correlation": ", ".join(f"{k} = {v}" for k, v in params.items())
                         or "none", "seed": seed, **{k: v for k, v in res.items()
                                                     if k.endswith("mse")},
                         "white-noise bound": bound,
                         "terms (exogenous FOS)": len(res["fos_exog_terms"])})
    frame = pd.DataFrame(rows)
    mean = frame.groupby("correlation", sort=False).mean(numeric_only=True).drop(columns="seed")
    mean["fos_exog / ar"] = mean["fos_exog_mse"] / mean["ar_mse"]
    return mean.reset_index()


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    closed = closed_form_table()
    gains, diff = gain_tables()
    t103 = table_10_3()
    drift, fig = drift_study()
    fos = fos_study()
    typical = ArrayModel.from_noise(8, 100.0)
    typical_gain = pd.DataFrame(steady_state_gain(typical), columns=list(NAMES))
    typical_gain.insert(0, "state", ["omega", *(f"b_{i}" for i in range(1, 9))])
    tables = {"closed_form": closed, "gain_eq_8_8": gains, "gain_agreement": diff,
              "table_10_3": t103, "monte_carlo": drift, "fos_cross_gyro": fos,
              "gain_8_uncorrelated": typical_gain}
    report = ["# Gyro array study", ""]
    for stem, frame in tables.items():
        write_tables(frame, OUT, stem)
        report += [f"## {stem}", "", markdown_table(frame, digits=4), ""]
        print(f"\n{stem}\n{frame.to_string(index=False)}")
    save_figure(fig, OUT, "drift")
    show_figure(OUT / "drift.png", "gyro_array_drift.png")
    write_text(OUT / "report.md", "\n".join([*report, "![drift](drift.png)", ""]))


if __name__ == "__main__":
    main()
