"""What a column's name tells: its sensor, its axis and its units.

A gyro's name begins ``gx``, ``gyro_x``, ``wx``, ``angular_velocity.x``, an accelerometer's
``ax``, ``acc_x``, ``linear_acceleration.x``; a suffix after the axis gives the units
(``gx_dps`` deg/s, ``gx_rads`` rad/s, ``ax_g`` g, ``ax_mg`` mg, ``ax_mps2`` m/s^2), as a
temperature's does (``temp_c``, ``die_temp_degc``: degC, the unit a log's temperature is
read in).  The loader fills ``Record.units`` from them (:func:`units_from_name`);
:mod:`fosmodel.noise.axes` reads the sensor and units of each axis from them.
"""

from __future__ import annotations

import re

#: A temperature named with its units: ``temp_c``, ``temperature_degc``, ``die_temp_c``.
_TEMPERATURE_IN_C = re.compile(r"^(die_?)?temp(erature)?_?(c|degc|deg_c)$", re.IGNORECASE)


#: Name prefixes before the axis letter (``gx``, ``gyro_x``, ``angular_velocity.x``); the
#: one-letter ones only right before it.
_PREFIXES = {
    "gyro": ("gyroscope", "gyro", "gyr", "angular_velocity", "ang_vel", "omega", "g", "w"),
    "accel": ("accelerometer", "linear_acceleration", "accel", "acc", "a"),
}
#: Units spelled in a name after the sensor and axis (``gx_dps``, ``gyro_rad[0]``, ``ax_g``).
_UNIT_WORDS = {
    "gyro": {"dps": "deg/s", "degs": "deg/s", "deg_s": "deg/s", "deg": "deg/s",
             "rads": "rad/s", "rad_s": "rad/s", "radps": "rad/s", "rps": "rad/s",
             "rad": "rad/s", "dph": "deg/h", "deg_h": "deg/h"},
    "accel": {"g": "g", "mg": "mg", "mps2": "m/s^2", "ms2": "m/s^2", "m_s2": "m/s^2",
              "m_s_2": "m/s^2"},
}



def infer_axis(column: str) -> tuple[str | None, str | None]:
    """Tell the sensor (``"gyro"``/``"accel"``) and units a column's name gives, or None each.

    Examples
    --------
    >>> infer_axis("gx_dps"), infer_axis("acc_y"), infer_axis("temp")
    (('gyro', 'deg/s'), ('accel', None), (None, None))
    """
    name = column.strip().lower()
    for sensor, prefixes in _PREFIXES.items():
        for prefix in prefixes:
            rest = after_prefix(name, prefix)
            if rest is not None:
                return sensor, _units_in(sensor, rest)
    return None, None


def axis_letter(column: str) -> str | None:
    """Tell which axis (``"x"``, ``"y"``, ``"z"``) a gyro's or accelerometer's name gives, or None.

    The letter right after the sensor's prefix (``gx_dps``, ``acc_y``), or an index
    ``[0]``..``[2]`` after a longer prefix (``gyro_rad[1]``).

    Examples
    --------
    >>> axis_letter("gx_dps"), axis_letter("acc_y"), axis_letter("gyro_rad[2]"), axis_letter("t")
    ('x', 'y', 'z', None)
    """
    name = column.strip().lower()
    for prefixes in _PREFIXES.values():
        for prefix in prefixes:
            rest = after_prefix(name, prefix)
            if rest is None:
                continue
            found = re.match(r"[._\- ]?([xyz])(?![a-z])", name[len(prefix):])
            index = re.search(r"\[([012])\]", rest)
            if found:
                return found.group(1)
            return "xyz"[int(index.group(1))] if index else None
    return None




def after_prefix(name: str, prefix: str) -> str | None:
    """Return what follows ``prefix`` and the axis in ``name``, or None if it is not of it.

    A one-letter prefix must be followed by the axis letter (``gx``, not ``gain``); a longer one
    by a separator or the axis letter (``gyro_x``, ``gyrox``, ``gyro_rad[0]``).
    """
    if not name.startswith(prefix):
        return None
    rest = name[len(prefix):]
    axis = re.match(r"[xyz](?![a-z])", rest)
    if axis:
        return rest[axis.end():]
    if len(prefix) > 1 and rest[:1] in ("_", ".", "-", " ", "[", "("):
        return rest
    return None


def _units_in(sensor: str, rest: str) -> str | None:
    """Units named in the rest of a column name: its words, joined by underscores."""
    words = [w for w in re.split(r"[^a-z0-9]+", rest) if w and w not in ("x", "y", "z")
             and not w.isdigit()]
    joined = "_".join(words)
    for spelled, units in _UNIT_WORDS[sensor].items():
        if joined == spelled or spelled in words:
            return units
    return None


def units_from_name(column: str) -> str | None:
    """Return the units a column's name spells (a gyro's, an accelerometer's, degC), or None.

    Examples
    --------
    >>> units_from_name("gx_rads"), units_from_name("ax_mps2"), units_from_name("temp_c")
    ('rad/s', 'm/s^2', 'degC')
    >>> units_from_name("gx"), units_from_name("temp")
    (None, None)
    """
    if _TEMPERATURE_IN_C.match(column.strip()):
        return "degC"
    return infer_axis(column)[1]
