"""PX4 ULog files: one IMU topic as columns, read with pyulog.

Topics
------
``sensor_combined``
    ``gyro_rad[0..2]`` -> ``gx``, ``gy``, ``gz``; ``accelerometer_m_s2[0..2]`` ->
    ``ax``, ``ay``, ``az``; time its ``timestamp``, the gyro's sample (the
    accelerometer's is ``accelerometer_timestamp_relative`` from it).
``sensor_gyro``, ``sensor_accel``
    ``x``, ``y``, ``z`` -> ``gx``, ``gy``, ``gz`` or ``ax``, ``ay``, ``az``, and
    ``temperature`` (degC, the sensor's own); time ``timestamp_sample``, the
    measurement's; the sensor's ``device_id`` (the median over the messages, as PX4's
    thermal calibration reads it) in the metadata as ``device id``.
``vehicle_imu``
    ``delta_angle[i] / delta_angle_dt`` -> ``gx``, ``gy``, ``gz`` and
    ``delta_velocity[i] / delta_velocity_dt`` -> ``ax``, ``ay``, ``az``: the increments
    over their integration intervals (microseconds) as mean rates over them; time
    ``timestamp_sample``, the end of the interval.

Units are rad/s and m/s^2 as PX4 logs them; times, microseconds since boot, become
seconds (``/ 1e6``).  A topic logged in several instances (``multi_id``, one per
sensor) is named ``NAME:ID`` (``sensor_gyro:1``), one logged once by its name alone
(``sensor_combined``, or ``sensor_combined:0``).  ``temperature_topic`` names any
topic with a ``temperature`` field (``sensor_accel:0`` beside ``sensor_combined``,
say); its temperatures are interpolated onto the IMU samples' times as in a ROS bag
(:func:`fosmodel.io.sensor_log.align_temperature`).  A log cut short reads up to the
cut, as pyulog does; what pyulog prints about a damaged log becomes a note.
"""

from __future__ import annotations

import contextlib
import io
from collections import Counter
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..core.exceptions import InputError, error_line
from .sensor_log import (
    ACCEL_COLUMNS,
    GYRO_COLUMNS,
    ImuTopic,
    SensorLog,
    TopicError,
    align_temperature,
    choose_topic,
    describe_columns,
    import_extra,
    no_imu_topic,
)

SUFFIX = ".ulg"
#: Each IMU topic's columns: (field, the field of its integration interval in us, if any).
FIELDS: dict[str, dict[str, tuple[str, str | None]]] = {
    "sensor_combined": {**{c: (f"gyro_rad[{i}]", None) for i, c in enumerate(GYRO_COLUMNS)},
                        **{c: (f"accelerometer_m_s2[{i}]", None)
                           for i, c in enumerate(ACCEL_COLUMNS)}},
    "sensor_gyro": {**{c: (axis, None) for c, axis in zip(GYRO_COLUMNS, "xyz")},
                    "temperature": ("temperature", None)},
    "sensor_accel": {**{c: (axis, None) for c, axis in zip(ACCEL_COLUMNS, "xyz")},
                     "temperature": ("temperature", None)},
    "vehicle_imu": {**{c: (f"delta_angle[{i}]", "delta_angle_dt")
                       for i, c in enumerate(GYRO_COLUMNS)},
                    **{c: (f"delta_velocity[{i}]", "delta_velocity_dt")
                       for i, c in enumerate(ACCEL_COLUMNS)}},
}


def is_ulog(path: Path) -> bool:
    """Tell whether ``path`` names a ULog file, by its suffix (of any case)."""
    return path.suffix.lower() == SUFFIX


def ulog_imu_topics(path: Path) -> list[ImuTopic]:
    """List the log's IMU topics, their rates from their time stamps."""
    named = _named(_load(path, FIELDS)[0])
    return [_topic(name, data) for name, data in named.items() if data.name in FIELDS]


def read_ulog(path: Path, topic: str | None = None,
              temperature_topic: str | None = None) -> SensorLog:
    """Read one IMU topic of a ULog, and a temperature topic aligned onto it, as columns.

    Raises
    ------
    InputError
        No IMU topic, several and none chosen, a topic missing or of another kind
        (:class:`~fosmodel.io.sensor_log.TopicError`), a field missing from the
        topic, a damaged log, or pyulog not installed.
    """
    src = str(path)
    asked = {name.partition(":")[0] for name in (topic, temperature_topic) if name}
    datasets, notes = _load(path, {*FIELDS, *asked})
    named = _named(datasets)
    imus = [_topic(name, data) for name, data in named.items() if data.name in FIELDS]
    if not imus:
        raise no_imu_topic(src, ", ".join(FIELDS))
    others = {name: data.name for name, data in named.items() if data.name not in FIELDS}
    imu = choose_topic(src, imus, _canonical(src, topic, named, "topic"), others)
    assert imu is not None  # there are IMU topics: one is chosen or TopicError raised
    data = named[imu.name]
    time, field = _time(data)
    columns = {"time": time, **_columns(src, imu.name, data)}
    notes.insert(0, f"PX4 ULog, topic {imu.name} ({len(time)} messages): "
                    f"{describe_columns(columns)}; time from {field} (us)")
    metadata = {"format": "PX4 ULog", "topic": imu.name, "message type": data.name}
    if "device_id" in data.data:  # PX4's thermal calibration takes its median, so do we
        metadata["device id"] = str(int(np.median(data.data["device_id"])))
    if temperature_topic is not None:
        with_temperature = [_topic(n, d) for n, d in named.items() if "temperature" in d.data]
        keyword = "temperature_topic"
        chosen = choose_topic(src, with_temperature,
                              _canonical(src, temperature_topic, named, keyword),
                              {n: d.name for n, d in named.items() if "temperature" not in d.data},
                              "temperature", keyword)
        assert chosen is not None  # a topic asked for is found or TopicError raised
        source = named[chosen.name]
        columns["temperature"], note = align_temperature(
            time, _time(source)[0], source.data["temperature"].astype(float), src, chosen.name)
        notes.append(note)
        metadata["temperature topic"] = chosen.name
    return SensorLog(columns, notes, metadata)


def _columns(src: str, name: str, data: Any) -> dict[str, np.ndarray]:
    """Return the topic's columns as float64; a ``temperature`` field it lacks is left out."""
    out = {}
    for column, (field, interval) in FIELDS[data.name].items():
        missing = [f for f in (field, interval) if f and f not in data.data]
        if missing and column == "temperature":
            continue
        if missing:
            raise InputError(f"{src}: topic {name} has no field {missing[0]!r} (this reader "
                             f"knows PX4's layout of {data.name}); its fields: "
                             f"{', '.join(data.data)}")
        values = data.data[field].astype(float)
        if interval:
            with np.errstate(divide="ignore", invalid="ignore"):  # the loader names a 0 interval
                values = values / (data.data[interval] / 1e6)
        out[column] = values
    return out


def _time(data: Any) -> tuple[np.ndarray, str]:
    """Return the messages' times in seconds (their samples' where said), and the field."""
    field = "timestamp_sample" if "timestamp_sample" in data.data else "timestamp"
    return data.data[field] / 1e6, field


def _topic(name: str, data: Any) -> ImuTopic:
    time = _time(data)[0]
    span = float(time[-1] - time[0]) if len(time) > 1 else 0.0
    return ImuTopic(name, data.name, len(time), (len(time) - 1) / span if span > 0 else None)


def _named(datasets: Iterable[Any]) -> dict[str, Any]:
    """Name each logged topic: ``NAME``, or ``NAME:ID`` for one of several instances."""
    datasets = list(datasets)
    instances = Counter(data.name for data in datasets)
    return {data.name if instances[data.name] == 1 and data.multi_id == 0
            else f"{data.name}:{data.multi_id}": data for data in datasets}


def _canonical(src: str, name: str | None, named: Mapping[str, Any], keyword: str) -> str | None:
    """Return the topic ``name`` stands for.

    ``NAME:0`` of a topic logged once is ``NAME``; ``NAME`` of one logged in several
    instances is an error that lists them.
    """
    base, _, instance = (name or "").partition(":")
    if name in named or name is None:
        return name
    if instance == "0" and base in named:
        return base
    instances = [_topic(n, d) for n, d in named.items() if d.name == name]
    if instances:
        raise TopicError(f"{src}: topic {name!r} is logged in {len(instances)} instances, choose "
                         f"one with {{option}}: {', '.join(t.describe() for t in instances)}",
                         keyword)
    return name


def _load(path: Path, names: Iterable[str]) -> tuple[list[Any], list[str]]:
    """Read the log's datasets of the topics ``names``; return them and pyulog's prints."""
    pyulog = import_extra("pyulog", "px4", "PX4 ULog files", str(path))
    printed = io.StringIO()
    try:
        # an open file, closed here: pyulog leaves a file it opened itself open on an error
        with open(path, "rb") as fh, contextlib.redirect_stdout(printed):
            log = pyulog.ULog(fh, sorted(names))
    except Exception as exc:  # noqa: BLE001 - pyulog raises many types for a damaged log
        raise InputError(f"{path}: not a readable PX4 ULog file ({error_line(exc)})") from None
    notes = [f"pyulog: {line}" for line in printed.getvalue().splitlines() if line.strip()]
    return log.data_list, notes
