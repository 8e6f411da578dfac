"""The formats a record is read from: one row each, with its reader, its extra and its help.

Every place that names or recognises the formats reads this table: the loader's choice of a
reader (:func:`table_format`), the logs of :mod:`fosmodel.io.topics` (:func:`log_format`),
the names a fleet gives its records (:data:`SUFFIXES`) and the command line's help
(:func:`described`).  A new format is a row here and a reader module.

A table (CSV, ``.npy``, Parquet) is recognised by the last suffix of its name (any case), a
file of any other name being read as CSV; its reader gives the header and then blocks of
rows, which :func:`fosmodel.io.loader.load_record` converts and checks.  A log (a ROS bag, a
PX4 ULog) is recognised by its reader (a ROS 2 bag is a directory); one IMU topic of it is
read into columns, which go through the same checks.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from . import csv_reader, npy_reader, parquet_reader
from .csv_reader import Preamble
from .rosbag import SUFFIXES as BAG_SUFFIXES
from .rosbag import bag_imu_topics, is_bag, read_bag
from .sensor_log import ImuTopic, SensorLog
from .ulog import SUFFIX as ULOG_SUFFIX
from .ulog import is_ulog, read_ulog, ulog_imu_topics
from .values import Block


@dataclass(frozen=True)
class TableFormat:
    """A file of columns: how it is named, what reads it, the extra that reader needs.

    ``read_header(path)`` gives the column names, the file line of the first row (0 when
    rows are counted, not lines) and the preamble; ``read_blocks(path, skip, names, keep,
    chunk_rows)`` the kept columns ``chunk_rows`` rows at a time, and the row count if known.
    """

    name: str
    help: str
    suffixes: tuple[str, ...]
    extra: str | None
    read_header: Callable[[Path], tuple[list[str], int, Preamble]]
    read_blocks: Callable[[Path, int, list[str], list[str] | None, int],
                          tuple[Iterator[Block], int | None]]


@dataclass(frozen=True)
class LogFormat:
    """A log of topics: how it is recognised, what reads it, the extra that reader needs.

    ``read(path, topic, temperature_topic)`` reads one IMU topic as columns;
    ``imu_topics(path)`` lists the IMU topics.
    """

    name: str
    help: str
    suffixes: tuple[str, ...]
    extra: str | None
    recognises: Callable[[Path], bool]
    read: Callable[[Path, str | None, str | None], SensorLog]
    imu_topics: Callable[[Path], list[ImuTopic]]


CSV = TableFormat("CSV", "CSV", (".csv", ".txt"), None, csv_reader.read_header,
                  csv_reader.read_blocks)
#: Tables, in the order the help names them; a name none of them ends in is read as CSV.
TABLES = (
    CSV,
    TableFormat(".npy", ".npy", (".npy",), None, npy_reader.read_header, npy_reader.read_blocks),
    TableFormat("Parquet", ".parquet", (".parquet",), "parquet", parquet_reader.read_header,
                parquet_reader.read_blocks),
)
#: Logs, in the order the help and the messages name them.
LOGS = (
    LogFormat("ROS bag", "a ROS bag (.bag, a ROS 2 bag directory, .db3, .mcap)",
              tuple(BAG_SUFFIXES), "ros", is_bag, read_bag, bag_imu_topics),
    LogFormat("PX4 ULog", "a PX4 ULog file (.ulg)", (ULOG_SUFFIX,), "px4", is_ulog, read_ulog,
              ulog_imu_topics),
)
FORMATS = (*TABLES, *LOGS)
#: Suffixes of a compressed CSV: ``.gz``, ``.bz2`` and ``.xz`` are read through the capped
#: stream of :mod:`fosmodel.io.compression`, ``.zip`` and ``.zst`` by pandas.
COMPRESSED = (".gz", ".bz2", ".xz", ".zip", ".zst")
#: Every suffix a record's name may end in: its format's, and a compression's.
SUFFIXES = frozenset({*(s for f in FORMATS for s in f.suffixes), *COMPRESSED})


def table_format(path: Path) -> TableFormat:
    """Return the format of a table by the last suffix of its name; CSV for any other."""
    suffix = "".join(path.suffixes[-2:]).lower()
    return next((f for f in TABLES if suffix.endswith(f.suffixes)), CSV)


def log_format(path: Path) -> LogFormat | None:
    """Return the format of a log, or None if ``path`` is no log."""
    return next((f for f in LOGS if f.recognises(path)), None)


def described(formats: Iterable[TableFormat | LogFormat]) -> str:
    """Name formats in a sentence: ``"CSV, .npy or a PX4 ULog file (.ulg)"``."""
    helps: Sequence[str] = [f.help for f in formats]
    return helps[0] if len(helps) == 1 else f"{', '.join(helps[:-1])} or {helps[-1]}"
