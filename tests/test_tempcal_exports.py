"""The firmware's files of a thermal calibration, read back as the firmware reads them.

Each file is parsed as its consumer's own source parses it (QGroundControl's
ParameterManager::readParametersFromStream, PX4's ``param set``, ArduPilot's
AP_Param::parse_param_line) and its values put through the firmware's formula by hand
(PX4's TemperatureCompensation::calc_thermal_offsets_3D, ArduPilot's
AP_InertialSensor_TCal::correct_sensor) at three temperatures: inside the range, and
beyond each end, where the firmware clips.
"""

import math
import re

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from fosmodel.workflows.tempcal import run_tempcal
from fosmodel.workflows.tempcal_exports import (
    ardupilot_parameters,
    ardupilot_params,
    px4_console,
    px4_parameters,
    qgc_params,
)

#: The axes in an order their names must undo: the firmware's index is the name's letter.
COLUMNS = ["gz_dps", "gx_dps", "gy_dps", "ay_mps2", "ax_mps2", "az_mps2"]
SENSORS = {"gyro": ("TC_G0", "GYR"), "accel": ("TC_A0", "ACC")}


@pytest.fixture(scope="module")
def calibrated(thermal_group):
    group, truth = thermal_group(0, columns=COLUMNS)
    return run_tempcal([group]), truth


def _read_qgc(text):
    """QGroundControl's reader: '#' lines skipped, tab-split, five fields or ignored."""
    out, ignored = {}, []
    for line in text.split("\n"):
        if line.startswith("#"):
            continue
        fields = line.split("\t")
        if len(fields) != 5:
            ignored.append(line)
            continue
        system, component, name, value, kind = fields
        out[name] = (int(system), int(component), float(value), int(kind))
    return out, ignored


def _px4_offset(p, slot, axis, temperature):
    """calc_thermal_offsets_3D by hand, in float32 as the firmware holds its parameters."""
    f = {k: np.float32(v) for k, v in p.items()}
    t = np.float32(temperature)
    if t > f[f"{slot}_TMAX"]:
        d = f[f"{slot}_TMAX"] - f[f"{slot}_TREF"]
    elif t < f[f"{slot}_TMIN"]:
        d = f[f"{slot}_TMIN"] - f[f"{slot}_TREF"]
    else:
        d = t - f[f"{slot}_TREF"]
    x = [f[f"{slot}_X{k}_{axis}"] for k in range(4)]
    return float(x[0] + x[1] * d + x[2] * d * d + x[3] * d * d * d)


def _cal(result, column):
    return next(c for c in result.axes if c.axis.column == column)


def _expected(cal, temperature):
    """What the offset should be: the axis's firmware polynomial (clipped) and its constant."""
    constant = np.mean(cal.constants["firmware"]) if cal.axis.sensor == "gyro" else 0.0
    return cal.si_scale * (constant + float(cal.firmware.bias(np.array([temperature]), 1.0)[0]))


def test_the_qgroundcontrol_file_has_five_tab_separated_fields_of_the_right_types(calibrated):
    result, _ = calibrated
    params, notes = px4_parameters(result, 0, {"gyro": 2424842, "accel": 2424843})
    read, ignored = _read_qgc(qgc_params(params, ["a header"]))
    assert ignored == [""]  # the file's last newline, nothing else
    names = {f"{slot}_{n}" for slot, _ in SENSORS.values()
             for n in ["ID", "TMIN", "TMAX", "TREF"] + [f"X{k}_{j}" for k in range(4)
                                                        for j in range(3)]}
    assert set(read) == names | {"TC_G_ENABLE", "TC_A_ENABLE"}
    for name, (system, component, _, kind) in read.items():
        assert (system, component) == (1, 1)
        assert kind == (6 if name.endswith(("_ID", "_ENABLE")) else 9), name
    assert read["TC_G0_ID"][2] == 2424842 and read["TC_A_ENABLE"][2] == 1
    assert notes == []


@pytest.mark.parametrize("sensor", ["gyro", "accel"])
def test_px4_s_formula_on_the_file_gives_each_axis_s_bias_at_three_temperatures(calibrated,
                                                                                 sensor):
    result, truth = calibrated
    params, _ = px4_parameters(result, 0, {"gyro": 1, "accel": 2})
    read = {name: value for name, (_, _, value, _) in _read_qgc(qgc_params(params))[0].items()}
    slot = SENSORS[sensor][0]
    tmin, tmax = read[f"{slot}_TMIN"], read[f"{slot}_TMAX"]
    assert (tmin, tmax, read[f"{slot}_TREF"]) == pytest.approx((0.0, 50.0, 25.0), abs=0.2)
    for j, axis in enumerate("xyz"):
        column = next(c for c in COLUMNS if c.startswith(("g" if sensor == "gyro" else "a") + axis))
        cal = _cal(result, column)
        offsets = [_px4_offset(read, slot, j, t) for t in (12.3, tmin - 7.0, tmax + 9.0)]
        expected = [_expected(cal, t) for t in (12.3, tmin, tmax)]
        scale = max(abs(e) for e in expected)
        np.testing.assert_allclose(offsets, expected, atol=2e-6 * scale)
        # the firmware takes off the true bias's change over the range
        true = Polynomial(truth["coefs"][column])
        change = cal.si_scale * (true(tmax - 25.0) - true(12.3 - 25.0))
        assert offsets[2] - offsets[0] == pytest.approx(change, rel=0.02), column


def test_the_console_lines_set_the_same_values(calibrated):
    result, _ = calibrated
    params, _ = px4_parameters(result)
    qgc = {n: v for n, (_, _, v, _) in _read_qgc(qgc_params(params))[0].items()}
    lines = px4_console(params).splitlines()
    assert len(lines) == len(qgc)
    for line in lines:
        m = re.fullmatch(r"param set (\w+) (\S+)", line)
        assert m, line
        assert float(m.group(2)) == qgc[m.group(1)]


def test_a_device_id_beyond_int32_is_written_as_its_bits(calibrated):
    result, _ = calibrated
    params, notes = px4_parameters(result, 2, {"gyro": 3_000_000_000})
    value = next(p.value for p in params if p.name == "TC_G2_ID")
    assert value == 3_000_000_000 - 2**32
    assert int(np.array(value, dtype=np.int32).view(np.uint32)) == 3_000_000_000
    assert notes == ["TC_A2_ID is 0: PX4 applies the slot only to the sensor whose device_id it "
                     "names; give it with accel_id=ID, as the sensor_accel topic of the "
                     "board's log reads it"]


def _read_ardupilot(text):
    """AP_Param::parse_param_line: '#' lines skipped, the name and value split on ', =\\t'."""
    out = {}
    for line in text.splitlines():
        if line.startswith("#"):
            continue
        name, value = re.split(r"[, =\t\r\n]+", line.strip())[:2]
        assert len(name) <= 16, name  # AP_MAX_NAME_SIZE
        out[name] = float(value)
    return out


def _ardupilot_change(p, short, axis, temperature, cal_temp):
    """correct_sensor by hand: what it takes off, p(T - 35) - p(T_cal - 35), both clipped."""
    f = {k: np.float32(v) for k, v in p.items()}
    c = [f[f"INS_TCAL1_{short}{k}_{axis}"] for k in (1, 2, 3)]

    def poly(d):
        d = np.float32(d)
        return (c[0] + (c[1] + c[2] * d) * d) * d * np.float32(1e-6)

    low, high = f["INS_TCAL1_TMIN"], f["INS_TCAL1_TMAX"]
    t = min(max(np.float32(temperature), low), high)
    tc = min(max(np.float32(cal_temp), low), high)
    return float(poly(t - np.float32(35.0)) - poly(tc - np.float32(35.0)))


@pytest.mark.parametrize("sensor", ["gyro", "accel"])
def test_ardupilot_s_formula_on_the_file_takes_off_each_axis_s_change(calibrated, sensor):
    result, _ = calibrated
    params, notes = ardupilot_parameters(result)
    read = _read_ardupilot(ardupilot_params(params, ["a header"]))
    assert read["INS_TCAL1_ENABLE"] == 1 and notes == []
    short = SENSORS[sensor][1]
    cal_temp = 21.0  # INS_GYR1_CALTEMP: the boot's offsets hold the bias there
    for axis in "xyz":
        column = next(c for c in COLUMNS if c.startswith(("g" if sensor == "gyro" else "a") + axis))
        cal = _cal(result, column)
        for t, clipped in ((33.3, 33.3), (-10.0, read["INS_TCAL1_TMIN"]),
                           (70.0, read["INS_TCAL1_TMAX"])):
            taken = _ardupilot_change(read, short, axis.upper(), t, cal_temp)
            expected = _expected(cal, clipped) - _expected(cal, cal_temp)
            assert taken == pytest.approx(expected, rel=1e-5, abs=1e-9), (column, t)


def test_axes_whose_names_tell_none_are_taken_in_order_with_a_note(thermal_group):
    group, _ = thermal_group(0, columns=["gx_dps"])
    result = run_tempcal([group])
    params, notes = px4_parameters(result, 0, {"gyro": 5})
    assert notes == ["no gyro y/z axis: its coefficients are 0"]
    assert {p.name: p.value for p in params}["TC_G0_X1_1"] == 0.0
    assert math.isclose({p.name: p.value for p in params}["TC_G0_X1_0"],
                        _cal(result, "gx_dps").si_scale * _cal(result, "gx_dps").firmware.powers[1])
