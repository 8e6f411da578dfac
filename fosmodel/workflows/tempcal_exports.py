r"""A thermal calibration as the firmware loads it: PX4 (QGroundControl and console) and ArduPilot.

Each file holds the firmware-form polynomial of every axis (the powers of the temperature
itself, :attr:`fosmodel.workflows.tempcal.AxisCal.firmware`), in the units, axis order,
variable and sign the firmware's own source applies:

PX4 (``TC_G<i>_*`` for the gyros, ``TC_A<i>_*`` for the accelerometers)
    ``TemperatureCompensation::calc_thermal_offsets_3D`` clips the sensor's temperature to
    ``[TMIN, TMAX]``, takes ``d = T - TREF`` and computes, for axis ``j`` (0, 1, 2 for the
    sensor's x, y, z), ``offset = X0_j + X1_j d + X2_j d^2 + X3_j d^3``; the sensors module
    subtracts it, before the board rotation, from the ``sensor_gyro`` (rad/s) or
    ``sensor_accel`` (m/s^2) sample (``calibration::Gyroscope::Correct``: ``data -
    _thermal_offset - _offset``).  ``TC_G<i>_ID`` names the ``device_id`` the slot applies to
    (``set_sensor_id`` compares it as an unsigned 32-bit number: the file holds the signed
    32-bit integer of the same bits).  ``TC_G_ENABLE``/``TC_A_ENABLE`` turn it on at the next
    boot.  ``X0`` is the mean session's bias at ``TREF`` for a gyro, 0 for an accelerometer
    (a static record cannot tell its offset from gravity; PX4's accelerometer calibration,
    run after the thermal one as PX4's procedure says, sets it).
QGroundControl's ``.params`` file
    ``ParameterManager::readParametersFromStream`` skips lines that begin with ``#``, splits
    the others on tabs and reads those of five fields: the vehicle's system id (which must be
    the connected vehicle's), the component id, the name, the value and the MAVLink type
    (``MAV_PARAM_TYPE_INT32`` 6, ``MAV_PARAM_TYPE_REAL32`` 9), which must match the
    parameter's own: the layout PX4's ``process_sensor_caldata.py`` writes.
PX4's console
    ``param set NAME VALUE``, one per line, for the MAVLink shell or the NuttX console.
ArduPilot (``INS_TCAL<n>_*``)
    ``AP_InertialSensor_TCal::correct_sensor`` clips the temperature and the offsets'
    calibration temperature (``INS_GYR<n>_CALTEMP``, ``INS_ACC<n>_CALTEMP``) to ``[TMIN,
    TMAX]`` and applies ``v -= p(T - 35) - p(T_cal - 35)`` with ``p(d) = (c1 + (c2 + c3 d) d)
    d * 1e-6`` per axis (``polynomial_eval``: no constant, 35 C its fixed ``TEMP_REFERENCE``,
    the coefficients ``ACC1..3`` and ``GYR1..3`` scaled by ``SCALE_FACTOR`` 1e6), to the
    sample in the sensor's frame (after its own orientation, before ``AHRS_ORIENTATION``), in
    rad/s and m/s^2 (``AP_InertialSensor_Backend::_rotate_and_correct_gyro``).  The boot's
    offsets take the level at ``T_cal``: the file holds the shape, re-expanded exactly from
    ``TREF`` to 35 C.  Lines ``NAME,VALUE`` as Mission Planner writes them;
    ``AP_Param::parse_param_line`` splits on ``, =\t`` and skips ``#`` lines, and MAVProxy's
    ``param load`` reads commas as spaces.

The axes are the sensor's own x, y, z, told by each column's name (``gx``, ``acc_y``): a
record's columns must hold the sensor's readings before any board rotation.

References
----------
PX4-Autopilot, ``src/modules/temperature_compensation/TemperatureCompensation.cpp``:
``TemperatureCompensation::initialize_parameter_handles``, ``calc_thermal_offsets_3D``,
``set_sensor_id``; ``TemperatureCompensation.h``: ``SensorCalData3D``;
``temp_comp_params_gyro_0.yaml``, ``temp_comp_params_gyro.yaml`` (``TC_G_ENABLE``,
reboot required); ``src/lib/sensor_calibration/Gyroscope.hpp``: ``Gyroscope::Correct``.
PX4-Autopilot, ``Tools/process_sensor_caldata.py``: the ``.params`` file it writes.
QGroundControl, ``src/FactSystem/ParameterManager.cc``:
``ParameterManager::readParametersFromStream``, ``_mavTypeToFactType``.
ArduPilot, ``libraries/AP_InertialSensor/AP_InertialSensor_tempcal.cpp``:
``AP_InertialSensor_TCal::var_info``, ``polynomial_eval``, ``correct_sensor``,
``SCALE_FACTOR``, ``TEMP_REFERENCE``; ``AP_InertialSensor.cpp``: the ``_TCAL1_`` group;
``AP_InertialSensor_Backend.cpp``: ``_rotate_and_correct_gyro``;
``libraries/AP_Param/AP_Param.cpp``: ``AP_Param::parse_param_line``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import Polynomial

from ..noise.axes import axis_letter
from .tempcal import FIRMWARE_DEGREE, AxisCal, TempcalResult, firmware_offset

#: MAVLink's parameter types as QGroundControl's file gives them.
MAV_PARAM_TYPE_INT32, MAV_PARAM_TYPE_REAL32 = 6, 9
#: PX4's parameter prefixes per sensor, and ArduPilot's coefficient names.
PX4_PREFIX = {"gyro": "TC_G", "accel": "TC_A"}
ARDUPILOT_NAME = {"gyro": "GYR", "accel": "ACC"}
#: ArduPilot's fixed reference temperature and coefficient scale (AP_InertialSensor_tempcal).
ARDUPILOT_TREF_C, ARDUPILOT_SCALE = 35.0, 1e6
#: ArduPilot's range of TMIN and TMAX (their @Range).
ARDUPILOT_RANGE_C = (-70.0, 80.0)


@dataclass(frozen=True)
class Parameter:
    """A firmware parameter: its name, its value and its MAVLink type."""

    name: str
    value: float
    type: int = MAV_PARAM_TYPE_REAL32

    def text(self) -> str:
        """Return the value as written: an integer, or a float32 with every digit it keeps."""
        return str(int(self.value)) if self.type == MAV_PARAM_TYPE_INT32 else f"{self.value:.9g}"


def sensor_axes(result: TempcalResult, sensor: str) -> tuple[dict[int, AxisCal], list[str]]:
    """Return a sensor's calibrated axes by index (0, 1, 2 for x, y, z), and notes.

    The index comes from each column's name; three axes whose names tell none are taken in
    their order, with a note; an axis missing from the record is said.
    """
    cals = [c for c in result.axes if c.axis.sensor == sensor]
    letters = [axis_letter(c.axis.column) for c in cals]
    notes = []
    if None in letters or len(set(letters)) < len(letters):
        if len(cals) != 3:
            return {}, [f"the {sensor} columns' names do not tell their x, y and z axes "
                        f"({', '.join(c.axis.column for c in cals)}): no firmware export"]
        notes.append(f"the {sensor} columns' names do not tell their axes: "
                     f"{', '.join(c.axis.column for c in cals)} taken as x, y, z")
        letters = ["x", "y", "z"]
    by_index = {"xyz".index(str(letter)): c for letter, c in zip(letters, cals)}
    missing = [a for i, a in enumerate("xyz") if i not in by_index]
    if cals and missing:
        notes.append(f"no {sensor} {'/'.join(missing)} axis: its coefficients are 0")
    return by_index, notes


def px4_parameters(result: TempcalResult, instance: int = 0,
                   device_ids: Mapping[str, int | None] | None = None
                   ) -> tuple[list[Parameter], list[str]]:
    """Return PX4's thermal compensation parameters of every sensor calibrated, and notes.

    ``instance`` is the slot (``TC_G0``..``TC_G3``); ``device_ids`` the sensors'
    ``device_id`` where the records do not give it (a ULog's do).
    """
    params, notes = [], []
    for sensor, prefix in PX4_PREFIX.items():
        axes, said = sensor_axes(result, sensor)
        notes += said
        if not axes:
            continue
        first = next(iter(axes.values()))
        device = _device_id(result, sensor, device_ids)
        if not device:
            notes.append(f"{prefix}{instance}_ID is 0: PX4 applies the slot only to the sensor "
                         f"whose device_id it names; give it with {sensor}_id=ID, as the "
                         f"sensor_{sensor} topic of the board's log reads it")
        slot = f"{prefix}{instance}"
        params += [Parameter(f"{prefix}_ENABLE", 1, MAV_PARAM_TYPE_INT32),
                   Parameter(f"{slot}_ID", _int32(device or 0), MAV_PARAM_TYPE_INT32),
                   Parameter(f"{slot}_TMIN", first.firmware.base_range[0]),
                   Parameter(f"{slot}_TMAX", first.firmware.base_range[1]),
                   Parameter(f"{slot}_TREF", first.tref)]
        for k in range(FIRMWARE_DEGREE + 1):
            for j in range(3):
                value = firmware_offset(axes[j])[k] if j in axes else 0.0
                params.append(Parameter(f"{slot}_X{k}_{j}", value))
    return params, notes


def _device_id(result: TempcalResult, sensor: str,
               given: Mapping[str, int | None] | None) -> int | None:
    if given and given.get(sensor):
        return given[sensor]
    groups = {c.group for c in result.axes if c.axis.sensor == sensor}
    ids = {g.device_id for g in result.groups if g.name in groups and g.device_id}
    return ids.pop() if len(ids) == 1 else None


def _int32(value: int) -> int:
    """Return the signed 32-bit integer of an unsigned 32-bit ``device_id``'s bits."""
    return value - 2**32 if value >= 2**31 else value


def qgc_params(params: Sequence[Parameter], header: Sequence[str] = (), system: int = 1,
               component: int = 1) -> str:
    """Return QGroundControl's ``.params`` text: ``#`` comments, then five tab-separated fields.

    ``system`` must be the vehicle's MAVLink system id (QGroundControl refuses a file of
    another), ``component`` the autopilot's (1).
    """
    lines = [f"# {line}" for line in header] + ["#", "# Vehicle-Id Component-Id Name Value Type"]
    lines += [f"{system}\t{component}\t{p.name}\t{p.text()}\t{p.type}" for p in params]
    return "\n".join(lines) + "\n"


def px4_console(params: Sequence[Parameter]) -> str:
    """Return PX4 console commands: ``param set NAME VALUE``, one per parameter."""
    return "".join(f"param set {p.name} {p.text()}\n" for p in params)


def ardupilot_parameters(result: TempcalResult, instance: int = 0
                         ) -> tuple[list[Parameter], list[str]]:
    """Return ArduPilot's ``INS_TCAL<instance+1>_*`` parameters, and notes."""
    name, notes = f"INS_TCAL{instance + 1}", []
    sensors = {}
    for sensor in ARDUPILOT_NAME:
        axes, said = sensor_axes(result, sensor)
        notes += said
        if axes:
            sensors[sensor] = axes
    if not sensors:
        return [], notes
    ranges = [a.firmware.base_range for axes in sensors.values() for a in axes.values()]
    low, high = max(r[0] for r in ranges), min(r[1] for r in ranges)
    if len({tuple(r) for r in ranges}) > 1:
        notes.append(f"{name}: the gyros' and accelerometers' temperatures cover different "
                     f"ranges; TMIN and TMAX hold what both cover ({low:.4g}-{high:.4g} C)")
    if low < ARDUPILOT_RANGE_C[0] or high > ARDUPILOT_RANGE_C[1]:
        notes.append(f"{name}: the range {low:.4g}-{high:.4g} C leaves ArduPilot's "
                     f"{ARDUPILOT_RANGE_C[0]:g} to {ARDUPILOT_RANGE_C[1]:g} C; clipped to it")
        low, high = max(low, ARDUPILOT_RANGE_C[0]), min(high, ARDUPILOT_RANGE_C[1])
    params = [Parameter(f"{name}_ENABLE", 1, MAV_PARAM_TYPE_INT32),
              Parameter(f"{name}_TMIN", low), Parameter(f"{name}_TMAX", high)]
    for sensor, short in ARDUPILOT_NAME.items():
        if sensor not in sensors:
            continue
        shapes = {j: ardupilot_coefficients(cal) for j, cal in sensors[sensor].items()}
        for k in range(1, FIRMWARE_DEGREE + 1):
            params += [Parameter(f"{name}_{short}{k}_{a.upper()}",
                                 shapes[j][k - 1] if j in shapes else 0.0)
                       for j, a in enumerate("xyz")]
    return params, notes


def ardupilot_coefficients(cal: AxisCal) -> tuple[float, ...]:
    """Return ArduPilot's ``c1, c2, c3`` of an axis: its polynomial about 35 C, scaled by 1e6."""
    coefficients = firmware_offset(cal)
    shifted = Polynomial(coefficients)(Polynomial([ARDUPILOT_TREF_C - cal.tref, 1.0]))
    out = np.zeros(FIRMWARE_DEGREE + 1)
    out[: len(shifted.coef)] = shifted.coef
    return tuple(float(ARDUPILOT_SCALE * c) for c in out[1:])


def ardupilot_params(params: Sequence[Parameter], header: Sequence[str] = ()) -> str:
    """Return ArduPilot's parameter file text: ``#`` comments, then ``NAME,VALUE`` lines."""
    return "".join(f"# {line}\n" for line in header) + "".join(
        f"{p.name},{p.text()}\n" for p in params)
