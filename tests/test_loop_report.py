"""The wording of the residual loop's report."""

import numpy as np
from scipy.signal import lfilter

from fosmodel.loop.closeloop import LoopConfig, close_loop, worse_metrics
from fosmodel.loop.loop_report import effects_table, evaluation_text, report_markdown


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
