"""The wording of the residual loop's report."""

import re

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import cli
from fosmodel.loop.closeloop import LoopConfig, close_loop
from fosmodel.loop.diagnose import Finding
from fosmodel.loop.judge import Comparison, Judgement
from fosmodel.loop.loop_report import (
    describe_finding,
    effects_table,
    evaluation_text,
    report_markdown,
)


def _judgement(judged, earlier=None):
    halves = ((0.002, -0.0004), (0.01, -0.03)) if judged else (None, None)
    last = (Comparison("one_step", None, 10, 0.0012, halves[0], 0.1, 4.0, 3e-5, 0.99),
            Comparison("outage", 30.0, 40, -0.01, halves[1], -0.2, -0.3, 0.4, 0.3))
    origins = (10.0, 20.0, 30.0)
    found = None if earlier is None else tuple(
        None if g is None else (Comparison("one_step", None, 10, g, None, 0, 0, 1, 1),
                                Comparison("outage", 30.0, 40, g, None, 0, 0, 1, 1))
        for g in earlier)
    return Judgement(last, origins, found, None)


def test_evaluation_text_gives_the_halves_only_where_they_were_judged():
    assert evaluation_text(_judgement(True)) == (
        "one-step gain 0.0012 (p 3e-05; halves 0.002, -0.0004), "
        "30 s outage bias gain -0.01 (p 0.4; halves 0.01, -0.03)")
    assert evaluation_text(_judgement(False)) == (
        "one-step gain 0.0012 (p 3e-05), 30 s outage bias gain -0.01 (p 0.4)")
    assert evaluation_text(_judgement(False, [None, 0.25])) == (
        "one-step gain 0.0012 (p 3e-05; earlier origins -, 0.25), "
        "30 s outage bias gain -0.01 (p 0.4; earlier origins -, 0.25)")


def test_report_says_plainly_what_got_worse_and_what_not():
    rng = np.random.default_rng(5)
    n, rate = 60_000, 100.0
    y = (lfilter([1.0], [1.0, -0.6, 0.1], rng.standard_normal(n)) * 0.3
         + np.cumsum(rng.standard_normal(n)) * 0.004)
    res = close_loop(y, {}, LoopConfig(rate=rate, sensor="gyro", units="deg/s"))
    assert res.steps
    text = report_markdown(res, "walk", effects_table(res), effects_table(res))
    assert "On the prediction segment, which chose nothing, the final model" in text
    assert ("Nothing there is worse beyond its interval." in text) != (
        "It is WORSE there" in text)
    assert "better in one-step MSE x0.916 (0.909-0.924). Nothing there is worse" in text
    assert ("Too close or too few windows to tell: 30 s bias RMS, 30 s outage MSE, 30 s outage "
            "position error.") in text
    table = effects_table(res)
    assert table["Worse than the row above"].iloc[0] == ""
    assert all(isinstance(v, str) and v for v in table["Worse than the row above"].iloc[1:])


def test_a_ratio_says_better_worse_or_undetermined_with_its_interval():
    from fosmodel.loop.intervals import ratio

    rng = np.random.default_rng(0)
    a = rng.standard_normal(400)
    assert ratio("one-step MSE", "mse", a, 0.5 * a + 0.01 * rng.standard_normal(400),
                 0.95).verdict == "better"
    worse = ratio("30 s bias RMS", "b", a, 2 * a, 0.95, power=0.5)
    assert worse.verdict == "worse" and worse.text() == "30 s bias RMS x2 (2-2): worse"
    same = ratio("x", "x", a, a.copy(), 0.95)
    assert same.verdict == "unchanged" and same.text() == "x unchanged"
    close = ratio("x", "x", a, a + 0.05 * rng.standard_normal(400), 0.95)
    assert close.verdict == "undetermined" and close.why == "the 95% interval spans 1"
    few = ratio("1800 s outage position error", "p", a[:6], 0.5 * a[:6], 0.95, power=0.5)
    assert few.text() == ("1800 s outage position error x0.5: undetermined, only 6 windows, "
                          "fewer than the 10 an interval needs")


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
    head = next(line for line in stdout.splitlines() if line.startswith("row  Model"))
    assert re.search(r"  MSE +err\. \d+ s +bias RMS \d+ s$", head), head  # never cut
    kept = [line for line in stdout.splitlines() if re.match(r"\s+[1-9]\d*  driver ", line)]
    for line in kept:  # and every value whole
        assert all(re.fullmatch(r"-|\d\.\d+(e[+-]\d+)?|\d+(\.\d+)?", v)
                   for v in line.split()[-3:]), line
    assert len(kept) >= 3
    counts = [int(line.split("...")[1].split()[0]) for line in kept]
    effects = pd.read_csv(out / "effects.csv")
    assert counts == [len(terms.split(", ")) for terms in effects["Terms added"].iloc[1:]]
    assert sum(counts) > 10  # the report lists them; the console counts them
    for row in range(1, len(kept) + 1):  # each name cut in the table is given whole below it
        assert re.search(rf"^row {row}: driver board_temperature_sensor_number_\d_in_degrees_"
                         "celsius", stdout, re.MULTILINE)
