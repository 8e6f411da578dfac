"""Records in and results out: reading and checking records, writing results atomically.

The formats a record is read from (one table, :mod:`fosmodel.io.formats`) and a reader for
each (CSV, .npy, Parquet, ROS bags, PX4 ULog), the checks and repairs of its values, time base
and outliers, the bundled sample record, fitted models as files, and the atomic writer every
output goes through (tables and figures included).

Imports :mod:`fosmodel.core`, :mod:`fosmodel.typeset` and :mod:`fosmodel.models` only.  Its
public names are imported on first use (:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .figures import tidy
    from .formats import FORMATS
    from .loader import load_record, parse_scales
    from .model_file import write_model
    from .output import atomic_write, save_figure, write_tables, write_text
    from .record import Record
    from .samples import load_mpu6050_static, mpu6050_static_path
    from .sensor_log import ImuTopic, TopicError
    from .split import Split, SplitSpec
    from .topics import imu_topics, read_topic
else:
    __getattr__, __dir__ = attach(__name__, {
        "figures": ("tidy",),
        "formats": ("FORMATS",),
        "loader": ("load_record", "parse_scales"),
        "model_file": ("write_model",),
        "output": ("atomic_write", "save_figure", "write_tables", "write_text"),
        "record": ("Record",),
        "samples": ("load_mpu6050_static", "mpu6050_static_path"),
        "sensor_log": ("ImuTopic", "TopicError"),
        "split": ("Split", "SplitSpec"),
        "topics": ("imu_topics", "read_topic"),
    })

__all__ = [
    "FORMATS", "ImuTopic", "Record", "Split", "SplitSpec", "TopicError", "atomic_write",
    "imu_topics", "load_mpu6050_static", "load_record", "mpu6050_static_path", "parse_scales",
    "read_topic", "save_figure", "tidy", "write_model", "write_tables", "write_text",
]
