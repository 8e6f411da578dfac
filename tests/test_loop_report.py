"""The wording of the residual loop's report."""

import re

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import cli
from fosmodel.loop.closeloop import LoopConfig, close_loop, worse_metrics
from fosmodel.loop.diagnose import Finding
from fosmodel.loop.loop_report import (
    describe_finding,
    effects_table,
    evaluation_text,
    report_markdown,
)


def _evaluation(judged, origins=None):
    return {"one_step_gain": 0.0012, "one_step_p": 3e-5, "one_step_gain_halves": [0.002, -0.0004],
            "outage_gain": -0.01, "outage_p": 0.4, "outage_gain_halves": [0.01, -0.03],
            "halves_judged": judged, "one_step_gain_origins": origins,
            "outage_gain_origins": origins}


def test_evaluation_text_gives_the_halves_only_where_they_were_judged():
    judged = evaluation_text(_evaluation(True))
    assert judged == ("one-step gain 0.0012 (p 3e-05; halves 0.002, -0.0004), "
                      "outage bias gain -0.01 (p 0.4; halves 0.01, -0.03)")
    assert evaluation_text(_evaluation(False)) == (
        "one-step gain 0.0012 (p 3e-05), outage bias gain -0.01 (p 0.4)")
    assert evaluation_text(_evaluation(False, [None, 0.25, 0.5])) == (
        "one-step gain 0.0012 (p 3e-05; earlier origins -, 0.25), "
        "outage bias gain -0.01 (p 0.4; earlier origins -, 0.25)")


def _metrics(mse, position, bias):
    return {"mse": mse, "outage_mse": mse, "outage_position_error_m": position,
            "bias_rms": {"1": bias, "30": bias}}


def test_worse_names_each_number_beyond_two_percent():
    before = _metrics(1.0, 10.0, 0.1)
    assert worse_metrics(before, _metrics(1.01, 10.1, 0.09)) == []
    assert worse_metrics(before, _metrics(1.0, 15.0, 0.11)) == [
        "outage position error x1.5", "1 s bias RMS x1.1", "30 s bias RMS x1.1"]


def test_report_says_plainly_what_got_worse_and_what_not():
    rng = np.random.default_rng(5)
    n, rate = 60_000, 100.0
    y = (lfilter([1.0], [1.0, -0.6, 0.1], rng.standard_normal(n)) * 0.3
         + np.cumsum(rng.standard_normal(n)) * 0.004)
    res = close_loop(y, {}, LoopConfig(rate=rate, sensor="gyro", units="deg/s"))
    assert res.steps
    text = report_markdown(res, "walk", effects_table(res), effects_table(res))
    assert "On the prediction segment, which chose nothing, the final model" in text
    assert ("Nothing there got worse by more than 2 %." in text) != ("It is WORSE there" in text)
    table = effects_table(res)
    assert table["Worse than the row above"].iloc[0] == ""
    assert all(isinstance(v, str) and v for v in table["Worse than the row above"].iloc[1:])


def test_still_firing_names_the_channel_lag_frequency_or_product():
    def fired(test, evidence):
        return Finding(test, 9.0, 1e-6, 0.01, evidence)

    assert [describe_finding(f) for f in (
        fired("aux", {"channel": "temp_c", "lag": 3, "rho": 0.2, "square": False}),
        fired("periodic", {"freq_hz": 7.31372, "freq_fft_hz": 7.3, "power": 1.0,
                           "amplitude": 0.1}),
        fired("nonlinear", {"products": 10, "max_lag": 4, "strongest": "y[n-1]*y[n-2]"}),
        fired("step", {"time_s": 58.2612, "shift": 0.1, "bic_gain": 3.0}),
        fired("whiteness", {"lags": 20}))] == [
        "aux temp_c (lag 3)", "periodic 7.314 Hz", "nonlinear (y[n-1]*y[n-2])",
        "step at 58.26 s", "whiteness (lags 1-20)"]


@pytest.mark.slow
def test_the_close_loop_console_fits_100_columns_with_many_terms(tmp_path, capsys):
    """Five channels with long names, each explaining part of the residual at its own lag."""
    rng = np.random.default_rng(0)
    n, rate = 20_000, 50.0
    y = lfilter([1.0], [1.0, -0.6, 0.2], rng.standard_normal(n)) * 0.05
    columns = {}
    for k in range(5):
        channel = lfilter([1.0], [1.0, -0.95], rng.standard_normal(n))
        columns[f"board_temperature_sensor_number_{k}_in_degrees_celsius"] = channel
        y += 0.02 * np.r_[np.zeros(k + 1), channel[:-(k + 1)]]
    record = tmp_path / "many.csv"
    pd.DataFrame({"time": np.arange(n) / rate, "gyro_x": y, **columns}).to_csv(record,
                                                                             index=False)
    out = tmp_path / "loop"
    code = cli.main(["close-loop", str(record), "--column", "gyro_x", "--sensor", "gyro",
                     "--units", "deg/s", "--out", str(out)])
    stdout, stderr = capsys.readouterr()
    assert code == 0, stderr
    lines = (stdout + stderr).replace(str(out.resolve()), "OUT").splitlines()
    assert max(len(line) for line in lines) <= 100, max(lines, key=len)
    kept = [line for line in stdout.splitlines() if re.match(r"\s+[1-9]\d*  aux ", line)]
    assert len(kept) >= 3
    counts = [int(line.split("...")[1].split()[0]) for line in kept]
    effects = pd.read_csv(out / "effects.csv")
    assert counts == [len(terms.split(", ")) for terms in effects["Terms added"].iloc[1:]]
    assert sum(counts) > 10  # the report lists them; the console counts them
    for row in range(1, len(kept) + 1):  # each name cut in the table is given whole below it
        assert re.search(rf"^row {row}: aux board_temperature_sensor_number_\d_in_degrees_"
                         "celsius", stdout, re.MULTILINE)
