"""ROS 1 and ROS 2 bags: one ``sensor_msgs/msg/Imu`` topic as columns, read with rosbags.

Formats
-------
A ROS 1 ``.bag`` file; a ROS 2 bag, the directory holding ``metadata.yaml`` and its
``.db3`` (sqlite3) or ``.mcap`` storage files; or one such storage file alone.  All
are read by ``rosbags.highlevel.AnyReader`` (the ``ros`` extra).

Columns
-------
Each message of the IMU topic is a sample: ``gx``, ``gy``, ``gz`` its
``angular_velocity`` (rad/s), ``ax``, ``ay``, ``az`` its ``linear_acceleration``
(m/s^2), and ``time`` its ``header.stamp`` in seconds from the first message's
(counted in integer nanoseconds, then divided by 1e9: a Unix time in float64 would
round stamps to 0.24 us; the first stamp is ``metadata["time zero"]``).  When every
stamp is zero (a driver that does not stamp), the times at which the bag recorded
the messages serve instead.  A vector whose covariance starts with -1 in every
message is, by the message's definition, not measured: its columns are left out.

A ``sensor_msgs/msg/Temperature`` topic (the one asked for, or the bag's only one)
adds a ``temperature`` column (degC): its values, stamped the same way, are
interpolated linearly onto the IMU samples' times (see
:func:`fosmodel.io.sensor_log.align_temperature`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..core.exceptions import InputError, error_line
from .sensor_log import (
    ACCEL_COLUMNS,
    GYRO_COLUMNS,
    ImuTopic,
    SensorLog,
    align_temperature,
    choose_topic,
    describe_columns,
    import_extra,
    no_imu_topic,
)

IMU_TYPE = "sensor_msgs/msg/Imu"
TEMPERATURE_TYPE = "sensor_msgs/msg/Temperature"
#: What a bag's storage file is, by its suffix (rosbags reads them by it, case included).
SUFFIXES = {".bag": "ROS 1 bag", ".db3": "ROS 2 bag file (sqlite3)", ".mcap": "MCAP file"}


def is_bag(path: Path) -> bool:
    """Tell whether ``path`` names a bag: by its suffix, or a directory with metadata.yaml."""
    return path.suffix in SUFFIXES or (path / "metadata.yaml").is_file()


def bag_imu_topics(path: Path) -> list[ImuTopic]:
    """List the bag's IMU topics, their rates from the times the bag recorded the messages."""
    topics = _topics_of_type(_topics(path), IMU_TYPE)
    times = _read(path, {t.name: _no_row for t in topics})
    return [ImuTopic(t.name, t.type, t.count, _rate(times[t.name][0])) for t in topics]


def read_bag(path: Path, topic: str | None = None,
             temperature_topic: str | None = None) -> SensorLog:
    """Read one IMU topic of a bag, and a temperature topic aligned onto it, as columns.

    Raises
    ------
    InputError
        No IMU topic, several and none chosen, a topic missing or of another type
        (:class:`~fosmodel.io.sensor_log.TopicError`), a damaged bag, or rosbags
        not installed.
    """
    src, found = str(path), _topics(path)
    others = {name: kind for name, (kind, _) in found.items()}
    imus = _topics_of_type(found, IMU_TYPE)
    if not imus:
        raise no_imu_topic(src, IMU_TYPE, others)
    imu = choose_topic(src, imus, topic, others)
    assert imu is not None  # there are IMU topics: one is chosen or TopicError raised
    notes: list[str] = []
    temperature = _temperature_topic(src, found, temperature_topic, notes)
    extractors = {imu.name: _imu_row}
    if temperature is not None:
        extractors[temperature.name] = _temperature_row
    read = _read(path, extractors)
    rows = np.asarray(read[imu.name][1], dtype=float).reshape(-1, 10)
    if not len(rows):
        raise InputError(f"{src}: topic {imu.name} has no messages")
    stamps, said = _stamps(read[imu.name][0], rows)
    columns = {"time": (stamps - stamps[0]) / 1e9, **_vectors(rows, notes)}
    zero = f"{stamps[0] // 10**9}.{stamps[0] % 10**9:09d}"
    notes.insert(0, f"{_format(path)}, topic {imu.name} ({IMU_TYPE}, {len(rows)} messages): "
                    f"{describe_columns(columns)}; time from {said}, in seconds from the first "
                    f"message's ({zero} s)")
    metadata = {"format": _format(path), "topic": imu.name, "message type": IMU_TYPE,
                "time zero": zero}
    if temperature is not None:
        readings = np.asarray(read[temperature.name][1], dtype=float).reshape(-1, 3)
        at = (_stamps(read[temperature.name][0], readings)[0] - stamps[0]) / 1e9
        columns["temperature"], note = align_temperature(columns["time"], at, readings[:, 2],
                                                         src, temperature.name)
        notes.append(note)
        metadata["temperature topic"] = temperature.name
    return SensorLog(columns, notes, metadata)


def _vectors(rows: np.ndarray, notes: list[str]) -> dict[str, np.ndarray]:
    """Return the columns of the IMU rows' two vectors, but of one marked as not measured."""
    columns: dict[str, np.ndarray] = {}
    for names, first, covariance, vector in ((GYRO_COLUMNS, 2, 8, "angular_velocity"),
                                             (ACCEL_COLUMNS, 5, 9, "linear_acceleration")):
        if np.all(rows[:, covariance] == -1):
            notes.append(f"{', '.join(names)} left out: {vector}_covariance[0] is -1 in every "
                         f"message, which says the {vector} is not measured")
        else:
            columns.update(zip(names, rows[:, first:first + 3].T))
    return columns


def _temperature_topic(src: str, found: Mapping[str, tuple[str, int]], wanted: str | None,
                       notes: list[str]) -> ImuTopic | None:
    """Choose the temperature topic asked for, else the only one (of several: a note, none)."""
    temperatures = _topics_of_type(found, TEMPERATURE_TYPE)
    if wanted is None and len(temperatures) > 1:
        notes.append(f"{len(temperatures)} temperature topics "
                     f"({', '.join(t.name for t in temperatures)}): none read; choose one to add "
                     "a temperature column")
        return None
    return choose_topic(src, temperatures, wanted, {n: kind for n, (kind, _) in found.items()},
                        "temperature", "temperature_topic")


def _imu_row(msg: Any) -> tuple:
    """Take the stamp, the two vectors and the first element of their covariances."""
    stamp, w, a = msg.header.stamp, msg.angular_velocity, msg.linear_acceleration
    return (stamp.sec, stamp.nanosec, w.x, w.y, w.z, a.x, a.y, a.z,
            msg.angular_velocity_covariance[0], msg.linear_acceleration_covariance[0])


def _temperature_row(msg: Any) -> tuple:
    """Take the stamp and the temperature."""
    return (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.temperature)


def _no_row(msg: Any) -> tuple:
    return ()


def _stamps(log_times: list[int], rows: np.ndarray) -> tuple[np.ndarray, str]:
    """Return the messages' times in ns, and where they come from.

    The times are the stamps (``sec``, ``nanosec``) that begin ``rows``, or when every stamp
    is zero the times the bag recorded the messages.
    """
    if rows[:, :2].any() or not len(rows):
        return rows[:, 0].astype(np.int64) * 10**9 + rows[:, 1].astype(np.int64), "header.stamp"
    return (np.asarray(log_times, dtype=np.int64),
            "the times the bag recorded the messages (every header.stamp is zero)")


def _rate(log_times: list[int]) -> float | None:
    """Return the messages per second over the times (ns) the bag recorded them."""
    span = (log_times[-1] - log_times[0]) * 1e-9 if log_times else 0.0
    return (len(log_times) - 1) / span if span > 0 else None


def _format(path: Path) -> str:
    return SUFFIXES.get(path.suffix, "ROS 2 bag")


def _topics_of_type(found: Mapping[str, tuple[str, int]], kind: str) -> list[ImuTopic]:
    return [ImuTopic(name, kind, count) for name, (msgtype, count) in found.items()
            if msgtype == kind]


def _topics(path: Path) -> dict[str, tuple[str, int]]:
    """Return every topic of the bag with its message type and number of messages."""
    with _open(path) as reader:
        return {name: (info.msgtype or "mixed", info.msgcount)
                for name, info in reader.topics.items()}


def _read(path: Path, extractors: Mapping[str, Callable[[Any], tuple]]
          ) -> dict[str, tuple[list[int], list[tuple]]]:
    """Read each topic of ``extractors``: its messages' times (ns) and what is taken of each.

    The times are those the bag recorded the messages at; the extractor takes what is kept
    of each message (kept small: a bag may hold millions).
    """
    out: dict[str, tuple[list[int], list[tuple]]] = {name: ([], []) for name in extractors}
    with _open(path) as reader:
        connections = [c for c in reader.connections if c.topic in extractors]
        for connection, log_time, raw in reader.messages(connections=connections):
            times, rows = out[connection.topic]
            times.append(log_time)
            rows.append(extractors[connection.topic](reader.deserialize(raw,
                                                                        connection.msgtype)))
    return out


@contextlib.contextmanager
def _open(path: Path) -> Iterator[Any]:
    """Open the bag in an ``AnyReader``; any failure of rosbags is an :class:`InputError`."""
    highlevel = import_extra("rosbags.highlevel", "ros", "ROS bags", str(path))
    typesys = import_extra("rosbags.typesys", "ros", "ROS bags", str(path))
    try:
        # bags from ROS 2 before Iron carry no message definitions: the standard ones serve
        with highlevel.AnyReader([path], default_typestore=typesys.get_typestore(
                typesys.Stores.LATEST)) as reader:
            yield reader
    except InputError:
        raise
    except Exception as exc:  # noqa: BLE001 - rosbags and its storages raise many types
        raise InputError(f"{path}: not a readable {_format(path)} ({error_line(exc)})") from None
