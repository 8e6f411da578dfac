"""A static IMU's attitude: gravity and earth rate on its axes (data_synth.orientation)."""

import math

import numpy as np
import pytest

from data_synth.orientation import EARTH_RATE_DPS, Orientation
from data_synth.units import STANDARD_GRAVITY


def test_gravity_sits_on_the_up_axis_with_its_sign():
    np.testing.assert_array_equal(Orientation("+z", "+x").specific_force(),
                                  [0, 0, STANDARD_GRAVITY])
    np.testing.assert_array_equal(Orientation.parse("-y/+z").specific_force(),
                                  [0, -STANDARD_GRAVITY, 0])


def test_earth_rate_splits_between_north_and_up_by_latitude():
    assert EARTH_RATE_DPS == pytest.approx(15.041 / 3600, rel=1e-4)  # 15.04 deg/h
    w = Orientation("+x", "+y", latitude_deg=30.0).earth_rate()
    np.testing.assert_allclose(w, [EARTH_RATE_DPS / 2, EARTH_RATE_DPS * math.sqrt(3) / 2, 0],
                               rtol=1e-12)
    assert np.linalg.norm(Orientation("-z", "-x").earth_rate(3600.0)) == pytest.approx(
        EARTH_RATE_DPS * 3600)  # in deg/h
    assert Orientation().to_dict()["up"] == "+z"


@pytest.mark.parametrize("args, match", [
    (("+z", "-z"), "perpendicular"),
    (("z", "+x"), "written"),
    (("+z", "+x", 91.0), "latitude"),
])
def test_bad_orientations(args, match):
    with pytest.raises(ValueError, match=match):
        Orientation(*args)
    with pytest.raises(ValueError, match="UP/NORTH"):
        Orientation.parse("+z")
