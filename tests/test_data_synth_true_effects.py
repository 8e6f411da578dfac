"""The truth of each loop scenario as fosmodel effects (data_synth.true_effects)."""

import pytest

from data_synth import make_scenario
from data_synth.true_effects import true_effects


@pytest.mark.parametrize("name, expected", [
    ("clean", []),
    ("unrelated_temperature", []),
    ("undeclared_temperature", [("driver temp_c, fast part (lags 0-2)", True)]),
    ("undeclared_vibration", [("periodic 7.3137 Hz", False)]),
    ("undeclared_nonlinear", [("nonlinear (cross-products of degree 2)", False)]),
    ("undeclared_drift", [("drift (trend and warm-up, tau 60 s)", True)]),
    ("undeclared_aux_lag", [("driver accel_x, fast part (lags 0-5)", False)]),
    ("undeclared_step", [("step at 105 s", True)]),
    ("temperature_and_vibration", [("driver temp_c, fast part (lags 0-2)", True),
                                   ("periodic 7.3137 Hz", False)]),
    ("slow_clean", []),
    ("slow_random_walk", [("local level", True)]),
    ("slow_warmup", [("drift (trend and warm-up, tau 60 s)", True)]),
    ("slow_steps", [("step at 150 s", True), ("step at 350 s", True)]),
    ("slow_random_walk_temperature", [("local level", True),
                                      ("driver temp_c, fast part (lags 0-3)", True)]),
    ("slow_warmup_drift_temperature", [("drift (trend and warm-up, tau 300 s)", True),
                                       ("driver temp_c, fast part (lags 0-3)", True)]),
])
def test_true_effects(name, expected):
    truth = make_scenario(name, seed=0).truth
    assert [(e.describe(), slow) for e, slow in true_effects(truth)] == expected


def test_input_lags_follow_the_exact_model():
    """The aux lags offered cover every lag of the input in the record's exact equation."""
    truth = make_scenario("undeclared_aux_lag", seed=0, duration=30).truth
    ((effect, _),) = true_effects(truth)
    model_lags = [int(t["term"].split("[n-")[1].rstrip("]")) for t in truth["model"]["terms"]
                  if t["term"].startswith("accel_x")]
    assert max(model_lags) == effect.max_lag == 5
