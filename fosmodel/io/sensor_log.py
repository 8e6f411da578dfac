"""What the readers of robot and autopilot logs share: topics, columns, choices.

The topics they list, the columns they return, how a topic is chosen and how a temperature
is set beside the IMU samples.

A log (a ROS bag, a PX4 ULog) holds many topics; :mod:`fosmodel.io.rosbag` and
:mod:`fosmodel.io.ulog` read one IMU topic of it into a :class:`SensorLog`, the
columns ``time`` (s), ``gx``, ``gy``, ``gz`` (rad/s), ``ax``, ``ay``, ``az``
(m/s^2) and ``temperature`` (degC) that it has, which the loader then checks as it
checks any record.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from ..core.exceptions import InputError
from ..core.validation import did_you_mean

GYRO_COLUMNS = ("gx", "gy", "gz")
ACCEL_COLUMNS = ("ax", "ay", "az")
#: The units of every column a log reader returns.
UNITS = {**dict.fromkeys(GYRO_COLUMNS, "rad/s"), **dict.fromkeys(ACCEL_COLUMNS, "m/s^2"),
         "temperature": "degC"}


@dataclass(frozen=True)
class ImuTopic:
    """A topic of IMU messages in a log.

    Attributes
    ----------
    name : str
        As the readers' ``topic`` takes it: ``/imu0`` (ROS), ``sensor_gyro:1`` (ULog).
    type : str
        Its message type: ``sensor_msgs/msg/Imu``, or a ULog's format (``sensor_gyro``).
    count : int
        Number of messages.
    rate : float or None
        Messages per second over the topic's span, (count - 1) / span, when measured.
    """

    name: str
    type: str
    count: int
    rate: float | None = None

    def describe(self) -> str:
        """Return the topic in words: ``"/imu0 (sensor_msgs/msg/Imu, 12000 messages, 200 Hz)"``."""
        rate = f", {self.rate:.4g} Hz" if self.rate is not None else ""
        return f"{self.name} ({self.type}, {self.count} messages{rate})"


@dataclass
class SensorLog:
    """One IMU topic of a log as columns, before the loader's checks.

    Attributes
    ----------
    columns : dict of str to ndarray
        ``time`` in seconds, then those of ``gx``, ``gy``, ``gz``, ``ax``, ``ay``, ``az``,
        ``temperature`` that the topic has, one value per message.
    notes : list of str
        What the reader did: the topic, where the time comes from, the columns and units.
    metadata : dict of str to str
        The log's format and the topic read.
    """

    columns: dict[str, np.ndarray]
    notes: list[str] = field(default_factory=list)
    metadata: dict[str, str] = field(default_factory=dict)

    @property
    def units(self) -> dict[str, str]:
        """The units of the data columns (the time is in seconds)."""
        return {name: UNITS[name] for name in self.columns if name in UNITS}


class TopicError(InputError):
    """A topic to choose, or one chosen wrongly.

    The message says how to choose with the reader's keyword (``topic=``);
    :meth:`with_flag` says it with the command line's flag (``--topic``).
    """

    def __init__(self, template: str, keyword: str = "topic") -> None:
        super().__init__(template.replace("{option}", f"{keyword}="))
        self.template, self.keyword = template, keyword

    def with_flag(self) -> str:
        """Return the message with the keyword's command-line flag, ``--topic`` for ``topic``."""
        return self.template.replace("{option}", "--" + self.keyword.replace("_", "-"))


def import_extra(module: str, extra: str, what: str, src: str) -> ModuleType:
    """Import ``module``, or raise a one-line error saying which extra installs it.

    Raises
    ------
    InputError
        When ``module`` cannot be imported.
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        raise InputError(f"{src}: reading {what} needs the {extra!r} extra: pip install "
                         f"'fosmodel[{extra}]'") from None


def choose_topic(src: str, topics: Sequence[ImuTopic], wanted: str | None,
                 others: Mapping[str, str], kind: str = "IMU",
                 keyword: str = "topic") -> ImuTopic | None:
    """Return the topic to read among ``topics``: ``wanted``, else the only one.

    Parameters
    ----------
    src : str
        The log, for the messages.
    topics : sequence of ImuTopic
        The log's topics of the ``kind`` asked for.
    wanted : str or None
        The topic asked for.
    others : mapping of str to str
        The log's other topics, name to message type: a ``wanted`` among them is of
        another type, not missing.
    kind : str, default "IMU"
        What the topics hold, for the messages.
    keyword : str, default "topic"
        The reader's keyword that chooses, for the messages.

    Returns
    -------
    ImuTopic or None
        None when ``wanted`` is None and the log has no topic of the kind.

    Raises
    ------
    TopicError
        Several topics and none asked for, or ``wanted`` missing or of another type.
    """
    listing = ", ".join(t.describe() for t in topics) or "none"
    if wanted is None:
        if len(topics) > 1:
            raise TopicError(f"{src}: {len(topics)} {kind} topics, choose one with {{option}}: "
                             f"{listing}", keyword)
        return topics[0] if topics else None
    chosen = next((t for t in topics if t.name == wanted), None)
    if chosen is not None:
        return chosen
    if wanted in others:
        raise TopicError(f"{src}: topic {wanted!r} holds {others[wanted]} messages, not {kind} "
                         f"data; {kind} topics (choose with {{option}}): {listing}", keyword)
    known = [t.name for t in topics] + list(others)
    raise TopicError(f"{src}: no topic {wanted!r}{did_you_mean(wanted, known)}; {kind} topics "
                     f"(choose with {{option}}): {listing}", keyword)


def no_imu_topic(src: str, types: str, others: Mapping[str, str] | None = None) -> InputError:
    """Return the error for a log without IMU topics (of ``types``), listing its ``others``."""
    listing = "" if others is None else "; its topics: " + (
        ", ".join(f"{name} ({kind})" for name, kind in others.items()) or "none")
    return InputError(f"{src}: no IMU topic ({types}){listing}")


def align_temperature(imu_time: np.ndarray, time: np.ndarray, temperature: np.ndarray,
                      src: str, topic: str) -> tuple[np.ndarray, str]:
    """Interpolate a temperature topic onto the IMU samples' times; return it and a note.

    The temperature is interpolated linearly between its messages (a die
    temperature changes slowly next to an IMU's sample interval, so a straight
    line between two readings is as good as a reading); an IMU sample before
    the first or after the last temperature message takes that message's value.

    Raises
    ------
    InputError
        A temperature topic without messages or whose time goes backwards.
    """
    if not len(time):
        raise InputError(f"{src}: temperature topic {topic!r} has no messages")
    back = np.flatnonzero(np.diff(time) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise InputError(f"{src}: temperature topic {topic!r}, message {i}: time goes backwards "
                         f"({float(time[i - 1])!r} then {float(time[i])!r})")
    outside = int(np.count_nonzero((imu_time < time[0]) | (imu_time > time[-1])))
    held = (f"; {outside} IMU sample(s) outside its span take its first or last value"
            if outside else "")
    return np.interp(imu_time, time, temperature), (
        f"column temperature (degC) from topic {topic} ({len(time)} messages), linearly "
        f"interpolated onto the IMU samples' times{held}")


def describe_columns(columns: Mapping[str, np.ndarray]) -> str:
    """Return the data columns present with their units: ``"gx, gy, gz in rad/s, ..."``."""
    groups = [(names, UNITS[names[0]]) for names in (GYRO_COLUMNS, ACCEL_COLUMNS,
                                                     ("temperature",)) if names[0] in columns]
    return ", ".join(f"{', '.join(names)} in {units}" for names, units in groups)
