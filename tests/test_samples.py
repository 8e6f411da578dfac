"""The real recording bundled with the package (fosmodel.io.samples)."""

import numpy as np
import pytest

from fosmodel.io import samples


def test_bundled_mpu6050_recording():
    path = samples.mpu6050_static_path()
    assert path.is_file() and (path.parent / "LICENSE-MIT.txt").is_file()
    rec = samples.load_mpu6050_static()
    assert rec.n_samples == 44_930 and rec.rate == 100.0
    assert rec.names == ["ax", "ay", "az", "gx", "gy", "gz"]
    norm = np.sqrt(rec.column("ax") ** 2 + rec.column("ay") ** 2 + rec.column("az") ** 2)
    assert np.mean(norm) == pytest.approx(1.0, abs=0.1)  # an uncalibrated MPU-6050: 0.918 g
    assert np.all(np.abs(np.mean([rec.column(f"g{a}") for a in "xyz"], axis=1)) < 5)  # deg/s
    assert rec.metadata == {"Logging Type": "1", "Initialization time": "-1",
                            "Waiting time": "-1"}
    assert rec.outliers == {}
