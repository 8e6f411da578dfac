"""Unit conversions of data_synth.units."""

import math

import numpy as np
import pytest

from data_synth import units


def test_arw_deg_per_sqrt_h_to_density():
    # 1 deg/sqrt(h) = 1 deg / (60 sqrt(s)) = 1/60 (deg/s)/sqrt(Hz) = 60 (deg/h)/sqrt(Hz)
    assert units.arw_to_density(1.0, "deg/s") == pytest.approx(1 / 60)
    assert units.arw_to_density(1.0, "deg/h") == pytest.approx(60.0)
    assert units.arw_to_density(0.068, "deg/s", per="sqrt(s)") == pytest.approx(0.068)


def test_arw_round_trip_and_per_sample_sigma():
    for u in ("deg/s", "deg/h"):
        assert units.density_to_arw(units.arw_to_density(2.89, u), u) == pytest.approx(2.89)
    # ARW 2.89 deg/sqrt(h) at 200 Hz: 2.89 * 60 * sqrt(200) deg/h per sample
    d = units.arw_to_density(2.89, "deg/h")
    assert units.white_sigma(d, 200.0) == pytest.approx(2.89 * 60 * math.sqrt(200))
    # Koldbæk and Totu (2011) eq. 4.10: sigma = ARW_c / sqrt(Ts)
    assert units.white_sigma(0.068, 102.4) == pytest.approx(0.068 / math.sqrt(1 / 102.4))


def test_vrw_and_rrw_conversions():
    assert units.vrw_to_density(0.28) == pytest.approx(0.28 / 60)
    assert units.density_to_vrw(units.vrw_to_density(0.28)) == pytest.approx(0.28)
    assert units.rrw_to_density(0.00029) == pytest.approx(0.00029)
    assert units.rrw_to_density(0.00029, "deg/h") == pytest.approx(0.00029 * 3600)
    # 1 deg/h/sqrt(h) = 1/(3600*60) deg/s/sqrt(s)
    assert units.rrw_to_density(216000.0, per="h/sqrt(h)") == pytest.approx(1.0)
    assert units.random_walk_step(0.00029, 102.4) == pytest.approx(0.00029 / math.sqrt(102.4))


def test_gravity_and_allan_formulas():
    assert units.mg_to_mps2(1000.0) == pytest.approx(9.80665)
    assert units.adev_white(0.5, 4.0) == pytest.approx(0.25)
    assert units.adev_random_walk(0.3, 3.0) == pytest.approx(0.3)
    assert units.adev_flicker_floor(1.0) == pytest.approx(0.6643, abs=1e-4)
    np.testing.assert_allclose(units.adev_white(1.0, np.array([1.0, 100.0])), [1.0, 0.1])


@pytest.mark.parametrize(
    "call",
    [
        lambda: units.rate_factor("m/s^2"),
        lambda: units.arw_to_density(1.0, per="h"),
        lambda: units.rrw_to_density(1.0, per="s"),
    ],
)
def test_bad_units_raise(call):
    with pytest.raises(ValueError):
        call()
