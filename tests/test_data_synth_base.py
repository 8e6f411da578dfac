"""The Source protocol (data_synth.base)."""

from dataclasses import FrozenInstanceError

import numpy as np
import pytest

from data_synth.base import Source, as_float_tuple, check_column_name
from data_synth.sources import WhiteNoise


@pytest.mark.parametrize("name", ["gyro_y", "temp_c", "_x", "gyro_1", "A9"])
def test_good_column_names(name):
    assert check_column_name(name) == name


@pytest.mark.parametrize("name", ["y", "time", "1gyro", "gyro-y", "gyro y", "", "t[n-1]"])
def test_bad_column_names(name):
    with pytest.raises(ValueError):
        check_column_name(name)


def test_as_float_tuple():
    assert as_float_tuple(1, "x") == (1.0,)
    assert as_float_tuple([1, 2.5], "x") == (1.0, 2.5)
    with pytest.raises(ValueError):
        as_float_tuple([1.0, np.nan], "x")


def test_common_fields_and_label():
    src = WhiteNoise(0.1)
    assert src.label == "white_noise" and src.declared and src.channel is None
    named = WhiteNoise(0.1, name="hf", channel="temp_c", declared=False)
    assert named.label == "hf" and named.outputs("gyro_y") == ("temp_c",)
    assert src.outputs("gyro_y") == ("gyro_y",) and src.requires == ()
    with pytest.raises(FrozenInstanceError):
        src.density = 0.2


def test_truth_layout():
    x = np.array([0.1, -0.1, 0.3])
    t = WhiteNoise(0.1, declared=False).truth(100.0, "deg/s", x)
    assert set(t) == {
        "kind",
        "name",
        "declared",
        "params",
        "terms",
        "innovation_std",
        "component_std",
    }
    assert t["declared"] is False and t["component_std"] == pytest.approx(x.std())
    assert "units" in t["params"]


def test_base_class_is_abstract():
    with pytest.raises(NotImplementedError):
        Source().generate(3, 1.0, np.random.default_rng(0))
