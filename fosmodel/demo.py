"""``fosmodel demo``: FOS against Burg on seeded, paper-like synthetic records.

Two one-hour 200 Hz records shaped like the FOS paper's (accelerometer-Y and
gyro-Y, from :mod:`data_synth`) are split as in the paper: the first 3 minutes
train, the rest is novel data.  FOS (L = 10, CP = 1, Korenberg's stop) and
statsmodels' Burg AR(10) are fit on the same training samples; both predict
every novel sample one step ahead from the true past.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pandas as pd
from statsmodels.regression.linear_model import burg

from .model import FOSModel
from .output import write_text

SEED = 2013
ORDER = 10
TRAIN_S = 180.0
SCENARIOS = {"accelerometer": "paper_accel_y", "gyroscope": "paper_gyro_y"}


def _ar_one_step(phi: np.ndarray, mu: float, y: np.ndarray, start: int) -> np.ndarray:
    """One-step predictions of ``y[start:]`` by the AR model ``y - mu`` with weights ``phi``."""
    order = len(phi)
    lags = np.lib.stride_tricks.sliding_window_view(y - mu, order)[:-1][:, ::-1]
    return mu + lags[start - order :] @ phi


def run_demo(out_dir: Path) -> pd.DataFrame:
    """Run the comparison, print it, write its files into ``out_dir``; return the table."""
    from data_synth import make_scenario

    out_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for sensor, scenario in SCENARIOS.items():
        rec = make_scenario(scenario, seed=SEED)
        y = rec.columns[rec.target]
        units = rec.truth["units"]
        start = int(TRAIN_S * rec.rate)
        train = y[:start]
        print(f"\n{sensor}: {scenario}, {len(y)} samples at {rec.rate:g} Hz ({units}); "
              f"training on the first {TRAIN_S:g} s, predicting the other {len(y) - start}")
        t0 = time.perf_counter()
        model = FOSModel(max_lag=ORDER, degree=1).fit(pd.Series(train, name=rec.target))
        t_fos = time.perf_counter() - t0
        t0 = time.perf_counter()
        phi, _ = burg(train, ORDER)  # demeans internally
        t_burg = time.perf_counter() - t0
        burg_pred = _ar_one_step(phi, float(train.mean()), y, start)
        print(model.summary())
        fos_err = y[start:] - model.predict(y)[start:]
        burg_err = y[start:] - burg_pred
        for method, err, runtime, terms in (
            (f"FOS (L={ORDER}, CP=1)", fos_err, t_fos, len(model.terms_)),
            (f"Burg AR({ORDER})", burg_err, t_burg, ORDER),
        ):
            rows.append({"sensor": sensor, "method": method, "units": units,
                         "one_step_mse": float(np.mean(err**2)), "terms": terms,
                         "fit_time_s": runtime})
        model_path = out_dir / f"{sensor}_fos_model.json"
        write_text(model_path, json.dumps(model.to_dict(
            {"scenario": scenario, "seed": SEED, "rate_hz": rec.rate, "units": units}),
            indent=2) + "\n")
        write_text(out_dir / f"{sensor}_fos_summary.txt", f"{model.summary()}\n")
    table = pd.DataFrame(rows)
    print("\nOne-step prediction MSE on the novel data (same training samples for both):")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    write_text(out_dir / "comparison.csv", table.to_csv(index=False))
    print(f"\noutputs written to {out_dir.resolve()}/")
    return table
