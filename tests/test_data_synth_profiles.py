"""Temperature and rate profiles (data_synth.profiles)."""

import math

import numpy as np
import pytest

from data_synth.profiles import CHAMBER_LEVELS_C, RoomCycle, StepProfile, Sweep, WarmUp
from data_synth.record import source_rng

RNG = source_rng(0, "profiles")


def test_chamber_levels_are_el_diasty_2007_set_points():
    assert CHAMBER_LEVELS_C == (-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0)


def test_warm_up_reaches_63_percent_after_one_time_constant():
    x = WarmUp(22.0, 12.0, 90.0).generate(30_001, 100.0, RNG)
    assert x[0] == 22.0
    assert x[9000] == pytest.approx(22.0 + 12.0 * (1 - math.exp(-1)))
    assert np.all(np.diff(x) > 0)


def test_step_profile_without_lag_holds_each_level_for_its_dwell():
    src = StepProfile((0.0, 10.0, -10.0))
    x = src.generate(300, 10.0, RNG)  # 30 s: 10 s per level by default
    assert np.all(x[:100] == 0.0) and np.all(x[100:200] == 10.0) and np.all(x[200:] == -10.0)
    x = StepProfile((0.0, 10.0), dwell_s=5.0).generate(200, 10.0, RNG)
    assert np.all(x[50:] == 10.0)  # the last level holds
    assert StepProfile((1.0, 2.0)).truth(10.0, "degC", x)["params"]["dwell_s"] == 10.0


def test_step_profile_lag_is_first_order():
    rate, lag = 100.0, 60.0
    x = StepProfile(CHAMBER_LEVELS_C, lag_s=lag).generate(360_000, rate, RNG)
    assert x[0] == pytest.approx(-30.0, abs=1e-12)
    dwell = 360
    # one time constant after the first step: 63 % of the way from -30 to -20
    k = int((dwell + lag) * rate)
    assert x[k] == pytest.approx(-30 + 10 * (1 - math.exp(-1)), abs=0.01)
    assert x.min() >= -30.0 - 1e-9 and x.max() <= 60.0
    assert x[-1] > 59.5


def test_room_cycle_period():
    x = RoomCycle(2.0, 600.0, mean_c=21.0).generate(120_001, 100.0, RNG)
    assert x[0] == pytest.approx(21.0) and x[15_000] == pytest.approx(23.0)
    assert x[60_000] == pytest.approx(21.0, abs=1e-9) and x[45_000] == pytest.approx(19.0)
    with pytest.raises(ValueError):
        RoomCycle(1.0, 0.0)


def test_sweep_is_linear_between_knots_and_flat_outside_and_on_equal_levels():
    src = Sweep((100.0, 200.0, 400.0), (5.0, 5.0, 25.0))
    x = src.generate(600, 1.0, RNG)
    assert np.all(x[:201] == 5.0) and np.all(x[400:] == 25.0)
    np.testing.assert_allclose(x[200:401], 5.0 + 0.1 * np.arange(201))
    knots = src.truth(1.0, "degC", x)["params"]["knots"]
    assert knots[2] == {"time_s": 400.0, "level": 25.0}
    with pytest.raises(ValueError, match="increasing"):
        Sweep((0.0, 0.0), (1.0, 2.0))
    with pytest.raises(ValueError, match="one level each"):
        Sweep((0.0, 1.0), (1.0,))
