"""Each column's sensor and units: given, told by its units, or read from its name.

A unit belongs to one sensor (:func:`fosmodel.noise.metrics.sensor_of`: deg/s,
rad/s, deg/h are a gyro's, m/s^2, g, mg an accelerometer's), so units given per
column (:class:`UnitsSpec`, ``gx=deg/s,ax=g``) or declared by the file (a ROS
bag's, a ULog's) say everything; a column without them is read from its name
(:func:`infer_axis`): ``gx``, ``gyro_x``, ``wx``,
``angular_velocity.x`` are gyros, ``ax``, ``acc_x``, ``linear_acceleration.x``
accelerometers, and a suffix ``_dps``, ``_rads``, ``_g``, ``_mg``, ``_mps2``
gives the units.  :func:`resolve_axes` puts these together, with a sensor or
units per sensor given for every column, and refuses units given for a column whose name
says others (``gx_dps=rad/s``): one of the two is wrong, and a factor of 57 in the noise
would follow either way.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from ..core.exceptions import InputError
from ..io.column_names import after_prefix as _after_prefix
from ..io.column_names import axis_letter as axis_letter  # re-exported: its users import it here
from ..io.column_names import infer_axis
from .metrics import is_sensor_units, sensor_of, to_si_scale

SENSORS = ("gyro", "accel")
#: Each sensor as the messages name it, and an example of its units.
_NAMED = {"gyro": "a gyro", "accel": "an accelerometer"}
_EXAMPLE_UNITS = {"gyro": "deg/s", "accel": "m/s^2"}
#: Channels that measure the motion itself, by the names they begin with: a magnetometer's
#: axes (``mx``, ``mag_x``) read the heading, the others how the body is turned, moves or
#: where it is.  The one-letter prefixes only right before the axis letter.
_MOTION_AXES = {
    "magnetometer": ("magnetometer", "magnetic_field", "mag", "m"),
    "velocity": ("vel", "v"),
    "position": ("pos",),
}
#: The same, as whole words a name begins with (``roll_deg``, ``q0``, ``alt_m``).
_MOTION_WORDS = {
    "attitude": ("attitude", "orientation", "euler", "quaternion", "quat", "roll", "pitch",
                 "yaw", "heading", "q0", "q1", "q2", "q3", "qw", "qx", "qy", "qz"),
    "velocity": ("velocity",),
    "position": ("position", "latitude", "longitude", "altitude", "lat", "lon", "alt"),
}


@dataclass(frozen=True)
class Axis:
    """A column to analyse: its sensor, its units and where each came from."""

    column: str
    sensor: str
    units: str
    told: str  # "given", "units given", "units from the file", "from the name", ...

    def describe(self) -> str:
        """Say the column's sensor and units and how they were told (``gx: gyro in deg/s``...)."""
        return f"{self.column}: {self.sensor} in {self.units} ({self.told})"


@dataclass(frozen=True)
class UnitsSpec:
    """Units given for the columns: per column, and one for every column not named.

    Parameters
    ----------
    every : str, optional
        Units of every column not in ``columns``.
    columns : mapping of str to str
        Units by column name.

    Examples
    --------
    >>> spec = UnitsSpec.parse("deg/s,ax=g")
    >>> spec.of("ax"), spec.of("gy")
    ('g', 'deg/s')
    """

    every: str | None = None
    columns: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        """Check the units, as :meth:`parse` does.

        Raises
        ------
        InputError
            Units that are not a string or that no sensor reads in (the message lists the
            valid ones), or a column name that is not a string.
        """
        given: list[tuple[object, object]] = list(dict(self.columns).items())
        if self.every is not None:
            given.insert(0, (None, self.every))  # None: every column
        for column, units in given:
            if column is not None and not (isinstance(column, str) and column):
                raise InputError(f"a column name must be a non-empty string, got {column!r}")
            if not isinstance(units, str):
                raise InputError(f"units must be a string such as 'deg/s', got {units!r}")
            sensor_of(units)  # refuses unknown units, listing the valid ones

    @classmethod
    def parse(cls, text: str) -> UnitsSpec:
        """Read ``UNITS`` (every column), ``COLUMN=UNITS,...`` or both, comma-separated.

        Raises
        ------
        InputError
            Not of that form, a column given twice, or unknown units (the message lists them).
        """
        every, columns = None, {}
        for part in text.split(","):
            column, sep, units = (s.strip() for s in part.partition("="))
            if not sep:
                column, units = "", column
            if not units or (sep and not column) or (not sep and every is not None):
                raise InputError(f"expected UNITS or COLUMN=UNITS,... (e.g. deg/s or "
                                 f"gx=deg/s,ax=g), got {text!r}")
            if column in columns:
                raise InputError(f"the units of column {column!r} are given twice in {text!r}")
            sensor_of(units)  # refuses unknown units, listing the valid ones
            if sep:
                columns[column] = units
            else:
                every = units
        return cls(every, columns)

    def of(self, column: str) -> str | None:
        """Return the units given for ``column``, or None."""
        return self.columns.get(column, self.every)


def motion_kind(column: str) -> str | None:
    """Tell what of the motion a column's name says it measures, or None.

    ``"magnetometer"``, ``"attitude"``, ``"velocity"`` or ``"position"``: in use such a
    channel follows the vehicle, so it is no cause of an inertial sensor's error.

    Examples
    --------
    >>> motion_kind("mag_x"), motion_kind("roll_deg"), motion_kind("vbat"), motion_kind("temp")
    ('magnetometer', 'attitude', None, None)
    """
    name = column.strip().lower()
    for kind, prefixes in _MOTION_AXES.items():
        if any(_after_prefix(name, prefix) is not None for prefix in prefixes):
            return kind
    for kind, words in _MOTION_WORDS.items():
        if any(re.match(rf"{word}(?![a-z])", name) for word in words):
            return kind
    return None


def column_sensor(column: str, declared: Mapping[str, str] | None = None) -> str | None:
    """Return the sensor a column's units (as its file ``declared`` them) or its name tell.

    None if neither does; a temperature's ``degC`` tells none.
    """
    unit = (declared or {}).get(column, "")
    if is_sensor_units(unit):
        return sensor_of(unit)
    return infer_axis(column)[0]


def resolve_axes(columns: Sequence[str], units: Mapping[str, str] | None = None, *,
                 given: UnitsSpec | None = None, declared: Mapping[str, str] | None = None,
                 sensor: str | None = None, optional: bool = False) -> list[Axis]:
    """Each column's sensor and units.

    In this order: given with the column as ``name:sensor:units``; the units ``given`` for it,
    then those its file ``declared`` (either tells its sensor); else its sensor is ``sensor`` or
    the one its name tells, and its units those of ``units`` (per sensor) or the ones its name
    tells.

    Parameters
    ----------
    columns : sequence of str
        Column names, each optionally as ``name:sensor:units``.
    units : mapping of str to str, optional
        Units per sensor (``{"gyro": "deg/s"}``), for the columns ``given`` says nothing of.
    given : UnitsSpec, optional
        Units per column and for every column.
    declared : mapping of str to str, optional
        Units per column that the record's file says (``Record.units`` of a ROS bag or a ULog).
    sensor : {"gyro", "accel"}, optional
        The sensor of every column: a column whose units tell another is refused.
    optional : bool
        Return no axes, rather than refuse, when nothing tells any (no ``units``, ``given``,
        ``sensor``, sensor units ``declared``, and a name that does not tell them all).

    Raises
    ------
    InputError
        A column whose sensor or units cannot be told (the message says how to give them),
        units of another sensor than ``sensor``, an unknown sensor or units, a column named
        twice, or units given for a column that is not among ``columns``.
    """
    named = all(None not in infer_axis(c) for c in columns)
    if optional and not (sensor or given or units or named or any(
            is_sensor_units((declared or {}).get(c, "")) for c in columns)):
        return []
    units, given = dict(units or {}), given or UnitsSpec()
    if sensor is not None and sensor not in SENSORS:
        raise InputError(f"unknown sensor {sensor!r}; valid sensors: {', '.join(SENSORS)}")
    names = [spec.split(":")[0] for spec in columns]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise InputError(f"column {twice[0]!r} is named twice in columns=")
    if not names:
        raise InputError("no columns to analyse")
    stray = [c for c in given.columns if c not in names]
    if stray:
        raise InputError(f"units are given for column {stray[0]!r}, which is not among the "
                         f"columns: {', '.join(names)}")
    declared = {c: u for c, u in (declared or {}).items() if is_sensor_units(u)}  # not degC
    return [_resolve(spec, units, given, declared, sensor) for spec in columns]


def _resolve(spec: str, units: Mapping[str, str], given: UnitsSpec, declared: Mapping[str, str],
             sensor: str | None) -> Axis:
    column, *inline = spec.split(":")
    if inline:
        if len(inline) != 2 or not all(inline):
            raise InputError(f"expected COLUMN or COLUMN:SENSOR:UNITS (e.g. gx:gyro:deg/s), "
                             f"got {spec!r}")
        to_si_scale(inline[0], inline[1])  # refuses unknown sensors and units, listing them
        return _agrees(_checked(Axis(column, inline[0], inline[1], "given"), sensor))
    told = given.of(column)
    if told is not None:
        return _agrees(_checked(Axis(column, sensor_of(told), told, "units given"), sensor))
    if column in declared and declared[column] != infer_axis(column)[1]:  # not the name's
        told = declared[column]
        return _checked(Axis(column, sensor_of(told), told, "units from the file"), sensor)
    named_sensor, named_units = infer_axis(column)
    if sensor and named_sensor and named_sensor != sensor:
        raise InputError(f"column {column!r}: its name tells {_NAMED[named_sensor]}, not "
                         f"{_NAMED[sensor]}; if it is one, give its units as {column}=UNITS")
    kind = sensor or named_sensor
    if kind is None:
        raise InputError(f"column {column!r}: its name does not tell the sensor; give its "
                         f"units, which do, as {column}=UNITS (e.g. {column}=deg/s for a gyro, "
                         f"{column}=m/s^2 for an accelerometer)")
    if kind in units:
        to_si_scale(kind, units[kind])
        how = "given" if sensor else f"{kind} from the name, units given"
        return _agrees(Axis(column, kind, units[kind], how))
    if named_units is None:
        by = "" if sensor else " by its name"
        raise InputError(f"column {column!r}: {_NAMED[kind]}{by}, but the name does not tell "
                         f"its units; give them as {column}=UNITS (e.g. "
                         f"{column}={_EXAMPLE_UNITS[kind]})")
    return Axis(column, kind, named_units, "from the name")


def _checked(axis: Axis, sensor: str | None) -> Axis:
    """``axis``, unless its units are of another sensor than ``sensor``."""
    if sensor is not None and axis.sensor != sensor:
        raise InputError(f"column {axis.column!r}: {axis.units} is a unit of "
                         f"{_NAMED[axis.sensor]}, not of {_NAMED[sensor]}")
    return axis


def _agrees(axis: Axis) -> Axis:
    """``axis``, unless its name spells units (``gx_dps``) other than those given for it."""
    named = infer_axis(axis.column)[1]
    if named is not None and named != axis.units:
        raise InputError(f"column {axis.column!r}: its name says {named}, but the units given "
                         f"for it are {axis.units}; correct the units or rename the column")
    return axis
