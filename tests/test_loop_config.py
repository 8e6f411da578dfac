"""The loop's settings and the channels' roles: every option checked, messages in the
library's own terms."""

import ast
from pathlib import Path

import pytest

from fosmodel.core.exceptions import InputError, OptionError
from fosmodel.loop.config import HORIZONS_S, LoopConfig
from fosmodel.loop.roles import channel_roles
from fosmodel.noise.axes import motion_kind


@pytest.mark.parametrize("options, message", [
    (dict(rate=0.0), "rate must be a finite number > 0, got 0.0"),
    (dict(sensor="gyro"), "give both the sensor (accel or gyro) and its units, or neither"),
    (dict(train=0.6, evaluate=0.4), "the split 0.6 / 0.4 must leave part of the record to "
                                    "predict: train and evaluate add up to 1 or more"),
    (dict(train=1.5), "train must lie between 0 and 1, got 1.5"),
    (dict(max_lag=3.0), "max_lag must be an integer >= 1, got 3.0"),
    (dict(max_lag=True), "max_lag must be an integer >= 1, got True"),
    (dict(max_effects=-1), "max_effects must be an integer >= 0, got -1"),
    (dict(n_starts=1), "n_starts must be an integer >= 2, got 1"),
    (dict(origins=2.0), "origins must be an integer >= 1, got 2.0"),
    (dict(aux_max_lag=-2), "aux_max_lag must be an integer >= 0, got -2"),
    (dict(nonlinear_lags=0), "nonlinear_lags must be an integer >= 1, got 0"),
    (dict(alpha=1.0), "alpha must lie between 0 and 1, got 1.0"),
    (dict(accept_alpha=0), "accept_alpha must be a finite number > 0, got 0"),
    (dict(confidence=float("nan")), "confidence must be a finite number > 0, got nan"),
    (dict(horizons_s=()), "horizons_s must be a sequence of durations in seconds, got ()"),
    (dict(horizons_s="30"), "horizons_s must be a sequence of durations in seconds, got '30'"),
    (dict(horizons_s=(30, -5)), "horizons_s must be a finite number > 0, got -5"),
    (dict(horizons_s=(30, 30.0)), "horizons_s repeats a duration: (30, 30.0)"),
    (dict(horizons_s=(0.001,)), "horizons_s: 0.001 s is shorter than one sample at 100 Hz"),
    (dict(eval_horizon_s=0), "eval_horizon_s must be a finite number > 0, got 0"),
    (dict(slow_s=float("inf")), "slow_s must be a finite number > 0, got inf"),
    (dict(head_s=-1), "head_s must be a finite number > 0, got -1"),
    (dict(fos_stop="aicc"), "fos_stop must be one of korenberg, max_terms, variance, "
                            "mean_square, aic, bic, fpe, mdl, got 'aicc'"),
    (dict(level_taus=(5, 5)), "level_taus repeats a duration: (5, 5)"),
    (dict(companions="gx"), "companions must be a sequence of column names, got 'gx'"),
    (dict(aux=("",)), "aux must be a sequence of column names, got ('',)"),
])
def test_every_option_is_checked_in_its_own_name(options, message):
    with pytest.raises(OptionError) as exc:
        LoopConfig(**{"rate": 100.0, **options})
    assert str(exc.value) == message


def test_options_are_held_as_tuples_and_the_flag_is_the_command_line_s():
    config = LoopConfig(rate=10.0, horizons_s=[300, 30], level_taus=[10, 1], aux=["gz"])
    assert config.horizons_s == (30.0, 300.0) and config.level_taus == (1.0, 10.0)
    assert config.aux == ("gz",) and LoopConfig(rate=1.0).horizons_s == HORIZONS_S
    with pytest.raises(OptionError) as exc:
        LoopConfig(rate=10.0, horizons_s=(30, 30))
    assert exc.value.with_flag({"horizons_s": "--horizons"}) == (
        "--horizons repeats a duration: (30, 30)")
    assert exc.value.with_flag() == "--horizons-s repeats a duration: (30, 30)"


def test_the_loop_s_messages_name_no_command_line_flag():
    """Every string a module of the loop raises with names options in the library's terms."""
    root = Path(__file__).resolve().parents[1] / "fosmodel" / "loop"
    found = []
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Raise) and node.exc is not None:
                for text in ast.walk(node.exc):
                    if isinstance(text, ast.Constant) and isinstance(text.value, str) \
                            and " --" in f" {text.value}":
                        found.append(f"{path.name}:{node.lineno}: {text.value}")
    assert not found


@pytest.mark.parametrize("sensor, expected", [
    ("gyro", (("temp_c", "ax_g", "ay_g", "vbat"), ("gy_dps", "gz_dps"))),
    # an accelerometer's gyros measure the motion too: companions, never its drivers
    ("accel", (("temp_c", "vbat"), ("ax_g", "ay_g", "gy_dps", "gz_dps"))),
    (None, (("temp_c", "vbat"), ("gy_dps", "gz_dps", "ax_g", "ay_g"))),
])
def test_the_other_axes_of_the_same_kind_are_companions(sensor, expected):
    channels = ["temp_c", "gy_dps", "gz_dps", "ax_g", "ay_g", "vbat"]
    roles = channel_roles(channels, sensor)
    assert (roles.drivers, roles.companions) == expected and roles.opted_in == ()
    assert roles.inputs == roles.drivers and roles.slow == ("temp_c", "vbat")


@pytest.mark.parametrize("name, kind", [
    ("mx", "magnetometer"), ("mag_x", "magnetometer"), ("Mag Y", "magnetometer"),
    ("magnetic_field.z", "magnetometer"), ("roll_deg", "attitude"), ("heading", "attitude"),
    ("q0", "attitude"), ("quat_w", "attitude"), ("vx", "velocity"), ("vel_n", "velocity"),
    ("pos_x", "position"), ("lat", "position"), ("alt_m", "position"),
    ("temp_c", None), ("vbat", None), ("voltage", None), ("max", None), ("mode", None),
    ("alternator", None), ("pressure", None), ("gx_dps", None),
])
def test_names_that_say_a_channel_measures_the_motion(name, kind):
    assert motion_kind(name) == kind


def test_channels_that_measure_the_motion_are_companions_however_the_others_are_told():
    names = ["temp_c", "gy_dps", "ax_g", "mag_x", "mag_y", "roll", "vbat"]
    named = channel_roles(names, "gyro")
    assert named.drivers == ("temp_c", "ax_g", "vbat")
    assert named.companions == ("gy_dps", "mag_x", "mag_y", "roll")
    assert named.told == ("the other gyro axes, recognised by their names; mag_x, mag_y, roll "
                          "measure the motion, as named")
    given = channel_roles(names, "gyro", companions=["gy_dps"], aux=["mag_x"])
    assert given.companions == ("gy_dps", "mag_x", "mag_y", "roll")
    assert given.inputs == ("temp_c", "ax_g", "vbat", "mag_x")
    unknown = channel_roles(["temp_c", "gx", "mx"], None)
    assert unknown.drivers == ("temp_c",) and unknown.companions == ("gx", "mx")
    assert unknown.told.endswith("; mx measures the motion, as named")


def test_companions_given_or_told_by_the_file_and_taken_in_only_when_asked():
    names = ["temp", "w1", "w2", "f1"]
    told = channel_roles(names, "gyro", sensors={"w1": "gyro", "w2": "gyro", "f1": "accel"})
    assert told.companions == ("w1", "w2") and told.drivers == ("temp", "f1")
    assert told.motion == ("f1",) and told.slow == ("temp",)  # an accelerometer: g-sensitivity
    given = channel_roles(names, "gyro", companions=["w2"], aux=["w2"])
    assert given.companions == ("w2",) and given.opted_in == ("w2",) and given.told == "as given"
    assert given.inputs == ("temp", "w1", "f1", "w2") and given.role("w2") == "companion"
    with pytest.raises(OptionError, match=r"^aux: 'temp' is not a companion of the modelled axis "
                                          r"\(companions: w2\); a driver is offered as an input "
                                          r"already$"):
        channel_roles(names, "gyro", companions=["w2"], aux=["temp"])
    with pytest.raises(OptionError, match=r"^companions: no channel 'w22' among the other "
                                          r"columns \(did you mean 'w2'\?\)$"):
        channel_roles(names, "gyro", companions=["w22"])
    assert issubclass(OptionError, InputError)
    accel = channel_roles(names, "accel", companions=["f1"],
                          sensors={"w1": "gyro", "w2": "gyro", "f1": "accel"})
    assert accel.companions == ("f1", "w1", "w2") and accel.drivers == ("temp",)
    assert accel.told == "as given (and the gyros, which measure the motion)"
