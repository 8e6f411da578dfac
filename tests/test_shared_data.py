"""Every real recording of ../shared/data, through the public loader, against its README.

Skipped as a whole when the folder is absent (a fresh clone has no ../shared).
"""

from pathlib import Path

import numpy as np
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.io.loader import load_record
from fosmodel.io.samples import MPU6050_SCALE, mpu6050_static_path

DATA = Path(__file__).parents[2] / "shared" / "data"
pytestmark = pytest.mark.skipif(
    not DATA.is_dir(), reason=f"the real recordings are not here: {DATA} is absent "
                              "(only a checkout beside the project's shared/ folder has them)")

ADIS_COLUMNS = ["gx_dps", "gy_dps", "gz_dps", "ax_g", "ay_g", "az_g"]
SUNSIDED = {  # session file stem: samples (the 10-min main session per the README, others counted)
    "unmoved-with-x-pointing-forward-10min": 65_067,
    "unmoved-with-x-pointing-forward": 12_243,
    "unmoved-with-z-pointing-front-and-x-up": 13_181,
    "unmoved-with-z-pointing-front-and-y-down": 10_178,
}


def _on_grid(x, step):
    return np.allclose(x / step, np.rint(x / step), rtol=0, atol=1e-3)


@pytest.fixture(scope="module", params=[f"imu{i}" for i in range(1, 7)])
def adis(request):
    """Each ADIS16405 session, loaded once for the module (a few seconds each)."""
    return request.param, load_record(DATA / "adis16405" / f"{request.param}.csv.gz", rate=100,
                                          outliers="keep")


def test_adis16405_sessions(adis):
    name, rec = adis
    assert rec.n_samples == 1_000_000 and rec.rate == 100.0 and rec.time is None
    assert rec.names == ADIS_COLUMNS
    for column in ADIS_COLUMNS[:3]:
        assert _on_grid(rec.column(column), 0.05), column  # 0.05 deg/s LSB
    for column in ADIS_COLUMNS[3:]:
        assert _on_grid(rec.column(column), 0.00333), column  # 3.33 mg LSB
    assert np.median(rec.column("az_g")) == pytest.approx(-1.0, abs=0.03)  # z axis down


def test_adis16405_outliers_are_only_real_disturbances(adis):
    name, rec = adis
    if name == "imu1":  # two knocks in the first seven seconds, seen in az_g only
        assert rec.outliers["az_g"].tolist() == [332, 333, 335, 336, 677, 678]
        assert set(rec.outliers) == {"az_g"}
    elif name == "imu4":  # the README's gyro X spike of ~17 deg/s, and shorter knocks
        _check_imu4_disturbances(rec)
    else:
        assert rec.outliers == {}


def _check_imu4_disturbances(rec):
    gx = rec.column("gx_dps")
    spike = int(np.argmax(np.abs(gx)))
    assert spike == 404_607 and gx[spike] == pytest.approx(-17.0)  # line 404,609 of the file
    assert rec.outliers["gx_dps"].tolist() == [11_711, 404_605, 404_606, 404_607, 404_608,
                                               404_610, 404_611, 404_614, 404_615]
    assert any("column 'gx_dps': 9 outlier(s)" in n and "404607" in n for n in rec.notes)
    assert set(rec.outliers) == set(ADIS_COLUMNS) - {"gz_dps"}
    episodes = (11_700, 11_900), (333_584, 333_585), (404_537, 404_639), (514_588, 514_680)
    for index in rec.outliers.values():
        assert all(any(lo <= i < hi for lo, hi in episodes) for i in index)


@pytest.mark.parametrize("stem", SUNSIDED)
def test_mpu6050_sunsided_sessions(stem):
    path = DATA / "mpu6050_sunsided" / f"{stem}.csv.gz"
    with pytest.raises(InputError, match="bursty receive time.*pass uniform=True"):
        load_record(path)
    rec = load_record(path, uniform=True, outliers="keep")  # the y-down start-up transient
    assert rec.n_samples == SUNSIDED[stem]
    assert rec.rate == pytest.approx(99.3, abs=0.25)  # N / duration, README: ~99.3 Hz
    np.testing.assert_allclose(rec.time, np.arange(rec.n_samples) / rec.rate)
    assert rec.names == ["ax_g", "ay_g", "az_g", "gx_dps", "gy_dps", "gz_dps", "temp_c"]
    accel = np.sqrt(sum(rec.column(c) ** 2 for c in ("ax_g", "ay_g", "az_g")))
    assert np.median(accel) == pytest.approx(1.0, abs=0.05)
    assert np.all(np.abs(np.median([rec.column(c) for c in ("gx_dps", "gy_dps", "gz_dps")],
                                   axis=1)) < 10)  # an uncalibrated bias of several deg/s
    assert set(rec.outliers) <= {"gx_dps"}  # only the y-down session's start-up transient


def test_mpu6050_sunsided_main_session():
    rec = load_record(DATA / "mpu6050_sunsided" / "unmoved-with-x-pointing-forward-10min.csv.gz",
                      uniform=True)
    assert rec.rate == pytest.approx(99.317, abs=0.001)
    temp = rec.column("temp_c")
    assert 25.1 <= temp.min() and temp.max() <= 25.62  # README: 25.1-25.6 C on ~0.09 C steps
    assert rec.outliers == {}
    y_down = DATA / "mpu6050_sunsided" / "unmoved-with-z-pointing-front-and-y-down.csv.gz"
    with pytest.raises(InputError, match=r"column 'gx_dps': 3 outlier\(s\) .* at sample\(s\) "
                                         r"0, 1, 2 .* carry 11 % of its mean square"):
        load_record(y_down, uniform=True)  # by default: the user says what they are
    start = load_record(y_down, uniform=True, outliers="keep")
    assert start.outliers["gx_dps"].tolist() == [0, 1, 2]  # 7.0-7.6 deg/s, settling to 4.5


def test_mpu6050_tomisuarez2():
    path = DATA / "mpu6050_tomisuarez2" / "static_7min.csv"
    raw = load_record(path)
    assert raw.n_samples == 44_930 and raw.rate == 100.0  # from the Fs,100 preamble
    assert any("ax, ay, az, gx, gy, gz hold only integers" in n for n in raw.notes)
    rec = load_record(path, scale=MPU6050_SCALE)
    accel = np.sqrt(sum(rec.column(c) ** 2 for c in ("ax", "ay", "az")))
    assert np.mean(accel) == pytest.approx(1.0, abs=0.1)  # uncalibrated: 0.918 g
    assert rec.outliers == {}
    assert path.read_bytes() == mpu6050_static_path().read_bytes()  # the bundled copy


def test_mtig_contaminated():
    path = DATA / "mtig_contaminated" / "gyro_x.csv.gz"
    with pytest.raises(InputError, match=r"column 'gyro_x': 1954 outlier\(s\) .* carry 17 %"):
        load_record(path, rate=100)  # by default: they carry too much to be kept unsaid
    rec = load_record(path, rate=100, outliers="keep")
    assert rec.n_samples == 500_000 and rec.rate == 100.0 and rec.names == ["gyro_x"]
    flagged = rec.outliers["gyro_x"]
    assert 1_000 < flagged.size < 5_000  # 1,954 with k = 10
    assert int(np.argmax(np.abs(rec.column("gyro_x")))) in flagged  # sample 312,386
    clipped = load_record(path, rate=100, outliers="clip").column("gyro_x")
    assert np.abs(clipped).max() < 0.021 and np.abs(rec.column("gyro_x")).max() > 0.25
