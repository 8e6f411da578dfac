"""Robot and autopilot logs as records: which files are logs, their IMU topics, one read.

Which files are logs, their IMU topics, and one topic read as columns.

ROS 1 and ROS 2 bags (:mod:`fosmodel.io.rosbag`, the ``ros`` extra) and PX4 ULog files
(:mod:`fosmodel.io.ulog`, the ``px4`` extra) hold many topics; :func:`imu_topics` lists
those with IMU messages and :func:`read_topic` reads one, which
:func:`fosmodel.io.loader.load_record` then checks as any record (``topic=`` chooses it).
"""

from __future__ import annotations

from pathlib import Path

from ..core.exceptions import InputError
from .formats import LOGS, LogFormat, described, log_format
from .sensor_log import ImuTopic, SensorLog, TopicError

__all__ = ["ImuTopic", "SensorLog", "TopicError", "imu_topics", "is_sensor_log", "read_topic"]

#: What :func:`read_topic` reads, for messages.
FORMATS = described(LOGS)


def is_sensor_log(path: str | Path) -> bool:
    """Tell whether ``path`` names a log by its suffix, or is a ROS 2 bag directory."""
    return log_format(Path(path)) is not None


def imu_topics(path: str | Path) -> list[ImuTopic]:
    """List the IMU topics of a log: name, message type, number of messages and rate.

    The rate of a bag's topic is that at which the bag recorded its messages; of
    a ULog's, that of its time stamps.  Both read the whole log.

    Parameters
    ----------
    path : str or Path
        A ROS 1 ``.bag``, a ROS 2 bag directory or storage file (``.db3``,
        ``.mcap``), or a PX4 ``.ulg`` file.

    Returns
    -------
    list of ImuTopic
        ``sensor_msgs/msg/Imu`` topics of a bag; ``sensor_combined``,
        ``sensor_gyro``, ``sensor_accel`` and ``vehicle_imu`` instances of a ULog.

    Raises
    ------
    InputError
        A missing, damaged or unknown file, or the reader's extra not installed.
    """
    path, found = _existing(path)
    return found.imu_topics(path)


def read_topic(path: str | Path, topic: str | None = None,
               temperature_topic: str | None = None) -> SensorLog:
    """Read one IMU topic of a log as columns ``time``, ``gx``..``az`` and ``temperature``.

    Parameters
    ----------
    path : str or Path
        As for :func:`imu_topics`.
    topic : str, optional
        The IMU topic; may be left out when the log has one.
    temperature_topic : str, optional
        A topic whose temperature becomes the ``temperature`` column, interpolated
        onto the IMU samples' times; in a bag, its only ``sensor_msgs/msg/Temperature``
        topic by default.  An IMU topic with its own temperature (a ULog's
        ``sensor_gyro``) gives the column without it.

    Returns
    -------
    SensorLog

    Raises
    ------
    TopicError
        Several IMU topics and no ``topic``, or a topic missing or of another type.
    InputError
        No IMU topic, a damaged or unknown file, or the reader's extra not installed.
    """
    path, found = _existing(path)
    return found.read(path, topic, temperature_topic)


def _existing(path: str | Path) -> tuple[Path, LogFormat]:
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such file")
    found = log_format(path)
    if found is None:
        raise InputError(f"{path}: not {FORMATS}")
    return path, found
