"""The wording of the residual loop's report."""

from fosmodel.loop_report import evaluation_text


def _evaluation(judged):
    return {"one_step_gain": 0.0012, "one_step_p": 3e-5, "one_step_gain_halves": [0.002, -0.0004],
            "outage_gain": -0.01, "outage_p": 0.4, "outage_gain_halves": [0.01, -0.03],
            "halves_judged": judged}


def test_evaluation_text_gives_the_halves_only_where_they_were_judged():
    judged = evaluation_text(_evaluation(True))
    assert judged == ("one-step gain 0.0012 (p 3e-05; halves 0.002, -0.0004), "
                      "outage gain -0.01 (p 0.4; halves 0.01, -0.03)")
    assert evaluation_text(_evaluation(False)) == (
        "one-step gain 0.0012 (p 3e-05), outage gain -0.01 (p 0.4)")
