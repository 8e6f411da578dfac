"""Real sensor recordings shipped with fosmodel (see ``fosmodel/data/README.md``)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .loader import Record, load_record

#: Raw counts to g (accelerometer, +-2 g) and to deg/s (gyroscope, +-250 deg/s).
MPU6050_SCALE = {**{f"a{axis}": 1 / 16384 for axis in "xyz"},
                 **{f"g{axis}": 1 / 131 for axis in "xyz"}}


def mpu6050_static_path() -> Path:
    """Path of the bundled MPU-6050 static recording (raw counts, ``Fs,100`` preamble)."""
    return Path(str(resources.files("fosmodel") / "data" / "static_7min.csv"))


def load_mpu6050_static() -> Record:
    """Load the bundled MPU-6050 static recording: accelerations in g, rates in deg/s, 100 Hz.

    Returns
    -------
    Record
        44,930 samples of columns ``ax, ay, az`` (g) and ``gx, gy, gz`` (deg/s);
        the rate comes from the file's ``Fs,100`` preamble.
    """
    return load_record(mpu6050_static_path(), scale=MPU6050_SCALE)
