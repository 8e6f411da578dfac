"""The six-axis report's choices and notes: the best model, one name per metric, warnings."""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pandas as pd

from fosmodel.noise.axes import resolve_axes
from fosmodel.noise.metrics import metric_definitions
from fosmodel.workflows.imu import loop_row, study_columns, study_row
from fosmodel.workflows.imu_report import driver_notes


def _study(rows):
    frame = pd.DataFrame(rows, columns=["protocol", "method", "label", "order", "evaluate_mse",
                                        "outage_position_error_m", "bias_rms_30s", "stable"])
    return SimpleNamespace(rows=frame, config=SimpleNamespace(protocols=("fair",),
                                                              horizon_s=30.0))


AXIS = resolve_axes(["gx_dps"])[0]


def test_an_unstable_model_is_never_the_best():
    study = _study([("fair", "fos_level", "FOS + level", 9, 1e-6, np.nan, 1e-5, False),
                    ("fair", "fos", "FOS", 3, 2e-6, 0.4, 2e-5, True),
                    ("fair", "burg", "Burg", 2, 3e-6, 0.5, 3e-5, True)])
    row = study_row(AXIS, study)
    outage, bias = study_columns(30.0)
    assert row["FOS"] == "FOS L=3" and row[f"FOS {outage}"] == 0.4
    assert row["best baseline"] == "Burg L=2"
    unstable = _study([("fair", "fos_level", "FOS + level", 9, 1e-6, np.nan, 1e-5, False),
                       ("fair", "burg", "Burg", 2, 3e-6, 0.5, 3e-5, True)])
    row = study_row(AXIS, unstable)
    assert row["FOS"] == "none stable" and np.isnan(row[f"FOS {outage}"])


def test_the_one_step_and_the_free_run_bias_have_different_names():
    study = study_row(AXIS, _study([("fair", "fos", "FOS", 3, 2e-6, 0.4, 2e-5, True),
                                    ("fair", "burg", "Burg", 2, 3e-6, 0.5, 3e-5, True)]))
    scores = {"outage_position_error_m": {"30": 1.0}, "bias_rms": {"30": 2.0}}
    loop = loop_row(AXIS, SimpleNamespace(before=scores, after=scores, cross_axis=[], steps=[],
                                          unexplained=[], worse=lambda: []))
    study_names = {k for k in study if "bias" in k}
    loop_names = {k for k in loop if "bias" in k}
    assert study_names == {"FOS one-step bias RMS 30 s", "baseline one-step bias RMS 30 s"}
    assert loop_names == {"30 s free-run bias RMS before", "30 s free-run bias RMS after"}
    defined = metric_definitions("deg/s", 30.0, 10, "the prediction segment")
    assert defined["bias_rms"].startswith("One-step bias RMS tau s (deg/s): the RMS of the "
                                          "means of the one-step residual")
    assert defined["free_run_bias_rms"].startswith("Free-run bias RMS tau s (deg/s): the RMS "
                                                   "over the outages")


def _loop(*kept):
    return SimpleNamespace(steps=[SimpleNamespace(effect=SimpleNamespace(describe=lambda d=d: d))
                                  for d in kept])


def test_the_report_says_which_channel_served_as_a_driver():
    result = SimpleNamespace(
        aux=["temp_c"],
        axes=[SimpleNamespace(axis=resolve_axes(["gx_dps"])[0],
                              loop=_loop("driver temp_c, slow part pow(lowpass(temp_c))")),
              SimpleNamespace(axis=resolve_axes(["gy_dps"])[0], loop=_loop("level"))])
    assert driver_notes(result) == [
        "temp_c served as a driver: each axis's loop was offered it as a measured cause (its "
        "slow and fast parts), judged on data the model was not fitted on; kept on gx_dps.", ""]
    assert driver_notes(SimpleNamespace(aux=[], axes=result.axes)) == []


def test_a_fit_that_misses_is_warned_on_the_page_and_in_the_summary():
    from dataclasses import replace

    from fosmodel.noise.imu_noise import imu_noise
    from fosmodel.workflows.imu_report import _noise_warnings

    x = 0.01 * np.random.default_rng(2).standard_normal(60_000)
    noise = imu_noise({"gx_dps": x}, [AXIS], 100.0, "x.csv")
    assert noise.fit_warnings() == [] and _noise_warnings(noise) == []
    a = noise.axes[0]
    off = replace(a, fit=replace(a.fit, coefficients={**a.fit.coefficients,
                                                      "N": 3 * a.fit.coefficients["N"]}))
    noise = replace(noise, axes=(off,))
    (line,) = noise.fit_warnings()
    assert line.startswith("gx_dps: the IEEE Std 952 fit misses the measured Allan deviation "
                           "beyond its 95 % interval at ")
    assert re.search(r"\(fit/data 2\.9\d at tau = 0\.01 s first\)", line), line
    assert _noise_warnings(noise) == [f"- WARNING: {line} (`noise/axes/gx_dps/`).", ""]
    assert f"WARNING: {line}." in noise.summary().notes


def test_the_horizon_and_min_tau_take_durations_with_units():
    import argparse

    import pytest

    from fosmodel.cli.arguments import duration
    from fosmodel.cli.parser import build_parser

    assert (duration("30s"), duration("2min"), duration("0.5h"), duration("45")) == (
        30.0, 120.0, 1800.0, 45.0)
    with pytest.raises(argparse.ArgumentTypeError) as err:
        duration("30 sec")
    assert str(err.value) == ("expected a duration like 30s, 5min or 1h (a bare number is in "
                              "seconds), got '30 sec'")
    args = build_parser().parse_args(["imu", "rec.csv", "--horizon", "1min", "--min-tau",
                                      "0.2s", "--out", "x"])
    assert (args.horizon, args.min_tau) == (60.0, 0.2)
