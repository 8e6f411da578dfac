"""Temperature-dependent error models of the chamber records (El-Diasty et al. 2007).

For ``temp_chamber_gyro`` (seed 0) and ``temp_chamber_accel`` (seed 1): the plateaus of the
temperature column, the error model per plateau (bias, Allan white-noise coefficient, AR(1)
weight, each with its standard error, as El-Diasty et al. (2007) Tables 1-2), one FOS model with
temperature
fitted across all plateaus, and the leave-one-plateau-out comparison of the per-plateau table
(as a calibration polynomial), the FOS model with temperature and the FOS model without it.
Writes tables (Markdown, CSV, LaTeX) and the figure ``coefficients.png`` to
``studies/results/temperature_chamber/`` and prints the verdict.

Run: ``python studies/temperature_chamber.py`` (about two minutes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from doc_pages import show_figure
from matplotlib.figure import Figure
from numpy.polynomial import Polynomial

from data_synth import make_scenario
from data_synth.scenarios import CC300_ACCEL_VRW, CC300_GYRO_ARW, CC300_TEMPS_C
from fosmodel.io import save_figure, write_tables, write_text
from fosmodel.study import (
    concatenate_plateaus,
    global_models,
    held_out_comparison,
    segment_noise,
    segment_table,
    temperature_inputs,
    temperature_segments,
    term_standard_errors,
)
from fosmodel.typeset import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "temperature_chamber"
#: sensor: scenario, units, Table 1 noise of El-Diasty et al. (2007), seed.  The two scenarios
#: draw their white
#: noise from the same stream name, so one seed would give both the same normalised noise.
RECORDS = {"gyro": ("temp_chamber_gyro", "deg/s", CC300_GYRO_ARW, 0),
           "accel": ("temp_chamber_accel", "m/s^2", CC300_ACCEL_VRW, 1)}
METRICS = {"mse": "one-step MSE", "outage_position_error_m": "30 s outage position error (m)"}


def truth_bias(rec, temp: np.ndarray) -> np.ndarray:
    """The record's temperature polynomial from its truth sidecar."""
    src = next(s for s in rec.truth["sources"] if s["kind"] == "temperature_bias")
    return Polynomial(src["params"]["coefs"])(temp - src["params"]["t_ref_c"])


def plateau_table(rec, sensor: str, units: str, segments, seed_noise) -> pd.DataFrame:
    y, temp = rec.columns[rec.target], rec.columns["temp_c"]
    table = pd.concat([segment_table(y, temp, segments),
                       segment_noise(y, rec.rate, segments, sensor, units)], axis=1)
    table["bias_truth"] = [truth_bias(rec, temp[s]).mean() for s in segments]
    table["noise_truth"] = np.interp(table["temp_c"], CC300_TEMPS_C, seed_noise)
    return table


def global_table(rec, segments) -> pd.DataFrame:
    """The FOS model with temperature fitted on every plateau: terms, standard errors, truth.

    The truth of a temperature term is the polynomial's weight of ``T`` or ``T^2`` (the
    constant of a centred model has no counterpart there).
    """
    y, temp = rec.columns[rec.target], rec.columns["temp_c"]
    fitted = global_models(y, temp, segments)["fos_temp"]
    yy, tt, runs = concatenate_plateaus(y, temp, segments)
    table = term_standard_errors(fitted, yy, temperature_inputs(tt), runs)
    raw = next(s for s in rec.truth["sources"] if s["kind"] == "temperature_bias")["params"]
    truth = {"temp_c_sq": raw["raw_coefs"][2]}
    table["truth"] = [truth.get(t, raw["raw_coefs"][1] if t.startswith("temp_c[") else np.nan)
                      for t in table["term"]]
    return table


def summary(res: pd.DataFrame) -> pd.DataFrame:
    mean = res.groupby("model", sort=False)[list(METRICS)].mean()
    wins = res.pivot(index="held_out", columns="model", values="outage_position_error_m")
    mean["plateaus best (outage)"] = [(wins.idxmin(axis=1) == m).sum() for m in mean.index]
    return mean.reset_index()


def verdict(sensor: str, mean: pd.DataFrame) -> str:
    m = mean.set_index("model")
    parts = []
    for col, label in METRICS.items():
        ratio = m[col] / m.loc["fos_temp", col]
        parts.append(f"{label}: best {m[col].idxmin()}; table/fos_temp {ratio['table']:.4f}, "
                     f"fos/fos_temp {ratio['fos']:.4f}")
    return f"{sensor}: " + "; ".join(parts)


def figure(tables: dict[str, pd.DataFrame]) -> Figure:
    fig = Figure(figsize=(12, 6.5), layout="constrained")
    axes = fig.subplots(2, 3)
    for row, (sensor, table) in zip(axes, tables.items()):
        t = table["temp_c"]
        grid = np.linspace(t.min(), t.max(), 200)
        row[0].errorbar(t, table["bias"], 2 * table["bias_se"], fmt="o", capsize=3,
                        label="per plateau, 2 SE")
        row[0].plot(t, table["bias_truth"], "k--", lw=1, label="truth (polynomial)")
        row[0].plot(grid, Polynomial.fit(t, table["bias"], 2, w=1 / table["bias_se"])(grid),
                    lw=1, label="table model (WLS quadratic)")
        row[0].set_ylabel(f"{sensor} bias ({RECORDS[sensor][1]})")
        row[1].errorbar(t, table["noise"], 2 * table["noise_se"], fmt="o", capsize=3)
        row[1].plot(CC300_TEMPS_C, RECORDS[sensor][2], "ks", mfc="none",
                    label="El-Diasty et al. (2007) Table 1 (the truth)")
        row[1].set_ylabel(f"white noise ({table['noise_units'].iloc[0]})")
        row[2].errorbar(t, table["coef y[n-1]"], 2 * table["se y[n-1]"], fmt="o", capsize=3)
        row[2].axhline(0.0, color="k", lw=0.8)
        row[2].set_ylabel("AR(1) weight (El-Diasty et al. 2007, Table 2's C_AR)")
        for ax in row:
            ax.set_xlabel("plateau temperature (C)")
            ax.grid(alpha=0.3)
        row[0].legend(fontsize="small")
        row[1].legend(fontsize="small")
    fig.suptitle("Chamber records (data_synth): per-plateau error model, 2 SE bars")
    return fig


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    tables, lines, report = {}, [], ["# Temperature chamber study", ""]
    for sensor, (name, units, seed_noise, seed) in RECORDS.items():
        rec = make_scenario(name, seed=seed)
        y, temp = rec.columns[rec.target], rec.columns["temp_c"]
        segments = temperature_segments(temp, rec.rate)
        tables[sensor] = plateau_table(rec, sensor, units, segments, seed_noise)
        glob = global_table(rec, segments)
        res = held_out_comparison(y, temp, rec.rate, segments, sensor=sensor, units=units)
        mean = summary(res)
        write_tables(tables[sensor].drop(columns=["start", "stop"]), OUT, f"plateaus_{sensor}")
        write_tables(glob, OUT, f"global_model_{sensor}")
        write_tables(res, OUT, f"held_out_{sensor}")
        write_tables(mean, OUT, f"held_out_summary_{sensor}")
        lines.append(verdict(sensor, mean))
        report += [f"## {name} ({units}, seed {seed})", "", f"{len(segments)} plateaus.", "",
                   markdown_table(tables[sensor].drop(columns=["start", "stop"]), digits=4), "",
                   "FOS with temperature on all plateaus:", "", markdown_table(glob, digits=4),
                   "", "Leave one plateau out (means over the held-out plateaus):", "",
                   markdown_table(mean, digits=4), "", lines[-1], ""]
    save_figure(figure(tables), OUT, "coefficients")
    show_figure(OUT / "coefficients.png", "temperature_coefficients.png")
    report += ["![per-plateau coefficients](coefficients.png)", ""]
    write_text(OUT / "report.md", "\n".join(report))
    for table in tables.values():
        print(table.drop(columns=["start", "stop"]).to_string(index=False))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
