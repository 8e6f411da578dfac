"""Units per column (UnitsSpec) and what they tell: the sensor of each unit, and each column's
sensor and units from the units given, a sensor given, the units per sensor or the name."""

import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.noise.axes import UnitsSpec, resolve_axes
from fosmodel.noise.metrics import sensor_of

VALID = "valid units: m/s^2, g, mg (accel); rad/s, deg/s, deg/h (gyro)"


@pytest.mark.parametrize(("units", "sensor"), [
    ("rad/s", "gyro"), ("deg/s", "gyro"), ("deg/h", "gyro"), ("m/s^2", "accel"), ("g", "accel"),
    ("mg", "accel")])
def test_each_unit_tells_its_sensor(units, sensor):
    assert sensor_of(units) == sensor


@pytest.mark.parametrize(("units", "message"), [
    ("deg", f"unknown units 'deg' (did you mean 'deg/s'?); {VALID}"),
    ("dps", f"unknown units 'dps'; {VALID}"),
])
def test_unknown_units_are_refused_with_the_valid_ones(units, message):
    with pytest.raises(InputError) as err:
        sensor_of(units)
    assert str(err.value) == message


@pytest.mark.parametrize(("text", "every", "columns"), [
    ("deg/s", "deg/s", {}),
    ("gx=deg/s,ax=g", None, {"gx": "deg/s", "ax": "g"}),
    (" deg/h , ax = mg ", "deg/h", {"ax": "mg"}),
])
def test_units_for_every_column_or_per_column(text, every, columns):
    spec = UnitsSpec.parse(text)
    assert (spec.every, dict(spec.columns)) == (every, columns)
    assert spec.of("ax") == columns.get("ax", every) and spec.of("other") == every


@pytest.mark.parametrize(("text", "message"), [
    ("gx=", "expected UNITS or COLUMN=UNITS,... (e.g. deg/s or gx=deg/s,ax=g), got 'gx='"),
    ("=deg/s", "expected UNITS or COLUMN=UNITS,... (e.g. deg/s or gx=deg/s,ax=g), got '=deg/s'"),
    ("deg/s,g", "expected UNITS or COLUMN=UNITS,... (e.g. deg/s or gx=deg/s,ax=g), got "
                "'deg/s,g'"),
    ("", "expected UNITS or COLUMN=UNITS,... (e.g. deg/s or gx=deg/s,ax=g), got ''"),
    ("gx=deg/s,gx=rad/s", "the units of column 'gx' are given twice in 'gx=deg/s,gx=rad/s'"),
    ("gx=deg", f"unknown units 'deg' (did you mean 'deg/s'?); {VALID}"),
])
def test_units_of_another_form_are_refused(text, message):
    with pytest.raises(InputError) as err:
        UnitsSpec.parse(text)
    assert str(err.value) == message


def _told(axes):
    return [(a.column, a.sensor, a.units, a.told) for a in axes]


def test_the_units_given_tell_the_sensor_whatever_the_name():
    axes = resolve_axes(["s1", "s2", "ax"], given=UnitsSpec.parse("s1=deg/h,s2=mg,ax=rad/s"))
    assert _told(axes) == [("s1", "gyro", "deg/h", "units given"),
                           ("s2", "accel", "mg", "units given"),
                           ("ax", "gyro", "rad/s", "units given")]


def test_which_wins_inline_then_per_column_then_every_then_per_sensor_then_the_name():
    given = UnitsSpec.parse("m/s^2,gy=rad/s")
    axes = resolve_axes(["gx:gyro:deg/h", "gy", "ax", "gz"], {"gyro": "deg/s"}, given=given)
    assert _told(axes) == [("gx", "gyro", "deg/h", "given"),
                           ("gy", "gyro", "rad/s", "units given"),
                           ("ax", "accel", "m/s^2", "units given"),
                           ("gz", "accel", "m/s^2", "units given")]
    axes = resolve_axes(["gz", "ax_g", "gx_rads"], {"gyro": "rad/s"})
    assert _told(axes) == [("gz", "gyro", "rad/s", "gyro from the name, units given"),
                           ("ax_g", "accel", "g", "from the name"),
                           ("gx_rads", "gyro", "rad/s", "gyro from the name, units given")]


@pytest.mark.parametrize(("columns", "units", "given"), [
    (["gx_dps"], None, "gx_dps=rad/s"),  # per column
    (["gx_dps", "gy_dps"], None, "rad/s"),  # for every column
    (["gx_dps:gyro:rad/s"], None, None),  # inline
    (["gx_dps"], {"gyro": "rad/s"}, None),  # per sensor
])
def test_units_given_against_the_units_a_name_spells_are_refused(columns, units, given):
    with pytest.raises(InputError) as err:
        resolve_axes(columns, units, given=UnitsSpec.parse(given) if given else None)
    assert str(err.value) == ("column 'gx_dps': its name says deg/s, but the units given for it "
                              "are rad/s; correct the units or rename the column")


def test_units_given_that_agree_with_the_name_pass():
    axes = resolve_axes(["gx_dps", "az_g"], given=UnitsSpec.parse("gx_dps=deg/s,az_g=g"))
    assert _told(axes) == [("gx_dps", "gyro", "deg/s", "units given"),
                           ("az_g", "accel", "g", "units given")]


def test_units_the_file_declares_come_after_those_given():
    declared = {"gx": "rad/s", "gy": "rad/s", "ax": "m/s^2"}
    axes = resolve_axes(["gx", "gy", "ax", "az_g"], given=UnitsSpec.parse("gy=deg/s"),
                        declared=declared)
    assert _told(axes) == [("gx", "gyro", "rad/s", "units from the file"),
                           ("gy", "gyro", "deg/s", "units given"),
                           ("ax", "accel", "m/s^2", "units from the file"),
                           ("az_g", "accel", "g", "from the name")]
    with pytest.raises(InputError) as err:
        resolve_axes(["gx"], declared=declared, sensor="accel")
    assert str(err.value) == "column 'gx': rad/s is a unit of a gyro, not of an accelerometer"


def test_a_sensor_given_for_every_column():
    axes = resolve_axes(["gyro", "rate_dps"], given=UnitsSpec.parse("deg/s"), sensor="gyro")
    assert _told(axes) == [("gyro", "gyro", "deg/s", "units given"),
                           ("rate_dps", "gyro", "deg/s", "units given")]
    assert _told(resolve_axes(["s1"], {"accel": "g"}, sensor="accel")) == [
        ("s1", "accel", "g", "given")]


@pytest.mark.parametrize(("columns", "kwargs", "message"), [
    (["gx"], {"given": UnitsSpec.parse("deg/s"), "sensor": "accel"},
     "column 'gx': deg/s is a unit of a gyro, not of an accelerometer"),
    (["gx:gyro:deg/s"], {"sensor": "accel"},
     "column 'gx': deg/s is a unit of a gyro, not of an accelerometer"),
    (["ax_g"], {"sensor": "gyro"},
     "column 'ax_g': its name tells an accelerometer, not a gyro; if it is one, give its units "
     "as ax_g=UNITS"),
    (["gyro"], {"sensor": "gyro"},
     "column 'gyro': a gyro, but the name does not tell its units; give them as gyro=UNITS "
     "(e.g. gyro=deg/s)"),
    (["acc_y"], {},
     "column 'acc_y': an accelerometer by its name, but the name does not tell its units; give "
     "them as acc_y=UNITS (e.g. acc_y=m/s^2)"),
    (["gx", "gy"], {"given": UnitsSpec.parse("gx=deg/s,gz=deg/s")},
     "units are given for column 'gz', which is not among the columns: gx, gy"),
    (["gx"], {"sensor": "magnetometer"},
     "unknown sensor 'magnetometer'; valid sensors: gyro, accel"),
    ([], {}, "no columns to analyse"),
])
def test_what_cannot_be_told_or_disagrees_is_refused(columns, kwargs, message):
    with pytest.raises(InputError) as err:
        resolve_axes(columns, **kwargs)
    assert str(err.value) == message
