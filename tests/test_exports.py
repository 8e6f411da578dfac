"""The VIO and autopilot exports: each file parsed back against a hand computation."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest
import yaml

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.noise.axes import resolve_axes
from fosmodel.noise.exports import (
    ARDUPILOT_DT_S,
    PX4_PREDICT_S,
    export_files,
    exports_dict,
    px4_parameters,
)
from fosmodel.noise.imu_noise import imu_noise

RATE = 100.0
#: Per column: white-noise density N (units*sqrt(s)) and rate random walk K (units/sqrt(s)).
TRUTH = {"gx_dps": (0.006, 3e-4), "gy_dps": (0.004, 2e-4), "gz_dps": (0.005, 1e-4),
         "ax_g": (1.2e-4, 5e-6), "ay_g": (1e-4, 4e-6), "az_g": (1.5e-4, 6e-6)}
DEG, G = math.pi / 180.0, 9.80665


@pytest.fixture(scope="module")
def columns():
    rng = np.random.default_rng(11)
    n = 120_000
    return {c: nw * math.sqrt(RATE) * rng.standard_normal(n)
            + np.cumsum(k / math.sqrt(RATE) * rng.standard_normal(n))
            for c, (nw, k) in TRUTH.items()}


@pytest.fixture(scope="module")
def noise(columns):
    return imu_noise(columns, resolve_axes(list(TRUTH)), RATE, "/data/imu.csv")


def _expected(noise, sensor, term):
    """The hand computation: the largest exported value over a sensor's axes, in SI."""
    scale = DEG if sensor == "gyro" else G
    return max(a.fit.conservative(term)[0] * scale for a in noise.of(sensor))


def _opencv_yaml(text):
    """An OpenCV FileStorage file: ``%YAML:1.0`` first (which PyYAML refuses), then YAML."""
    first, rest = text.split("\n", 1)
    assert first == "%YAML:1.0"
    return yaml.safe_load(rest)


def _pairs(text, prefix=""):
    """``NAME VALUE`` lines (after ``prefix``), comments skipped."""
    out = {}
    for line in text.splitlines():
        if line and not line.startswith("#"):
            assert line.startswith(prefix), line
            name, value = line[len(prefix):].split()
            out[name] = float(value)
    return out


def test_openvins_takes_the_continuous_densities(noise):
    chain = _opencv_yaml(export_files(noise.export())["openvins_kalibr_imu_chain.yaml"])
    imu0 = chain["imu0"]
    assert imu0["gyroscope_noise_density"] == pytest.approx(_expected(noise, "gyro", "N"),
                                                            rel=1e-6)
    assert imu0["gyroscope_random_walk"] == pytest.approx(_expected(noise, "gyro", "K"),
                                                          rel=1e-6)
    assert imu0["accelerometer_noise_density"] == pytest.approx(_expected(noise, "accel", "N"),
                                                                rel=1e-6)
    assert imu0["accelerometer_random_walk"] == pytest.approx(_expected(noise, "accel", "K"),
                                                              rel=1e-6)
    assert imu0["update_rate"] == RATE and imu0["model"] == "kalibr"
    assert np.array_equal(imu0["Tw"], np.eye(3)) and np.array_equal(imu0["Tg"], np.zeros((3, 3)))


def test_orbslam3_takes_the_continuous_densities_and_a_real_frequency(noise):
    text = export_files(noise.export())["orbslam3_imu.yaml"]
    settings = _opencv_yaml(text)
    assert settings["IMU.NoiseGyro"] == pytest.approx(_expected(noise, "gyro", "N"), rel=1e-6)
    assert settings["IMU.NoiseAcc"] == pytest.approx(_expected(noise, "accel", "N"), rel=1e-6)
    assert settings["IMU.GyroWalk"] == pytest.approx(_expected(noise, "gyro", "K"), rel=1e-6)
    assert settings["IMU.AccWalk"] == pytest.approx(_expected(noise, "accel", "K"), rel=1e-6)
    assert "IMU.Frequency: 100.0  #" in text  # ORB-SLAM3 refuses an integer (isReal)


def test_vins_takes_per_sample_deviations(noise):
    params = _opencv_yaml(export_files(noise.export())["vins_imu.yaml"])
    assert params["gyr_n"] == pytest.approx(_expected(noise, "gyro", "N") * math.sqrt(2 * RATE),
                                            rel=1e-6)
    assert params["acc_n"] == pytest.approx(_expected(noise, "accel", "N") * math.sqrt(2 * RATE),
                                            rel=1e-6)
    assert params["gyr_w"] == pytest.approx(_expected(noise, "gyro", "K") * math.sqrt(RATE),
                                            rel=1e-6)
    assert params["acc_w"] == pytest.approx(_expected(noise, "accel", "K") * math.sqrt(RATE),
                                            rel=1e-6)


def test_vins_midpoint_propagation_of_the_export_grows_as_the_allan_model():
    """integration_base.h's covariance step, rebuilt for one angle and one bias axis: over T
    seconds the angle's variance is N^2 T and the bias's K^2 T, as the Allan model says."""
    n_density, k_density, rate, steps = 3e-4, 2e-5, 200.0, 2000
    dt = 1.0 / rate
    gyr_n, gyr_w = n_density * math.sqrt(2 * rate), k_density * math.sqrt(rate)
    v = np.array([[0.5 * dt, 0.5 * dt, 0.0], [0.0, 0.0, dt]])  # rows: angle, bias
    noise = np.diag([gyr_n**2, gyr_n**2, gyr_w**2])  # n_g0, n_g1, n_bg
    p = np.zeros((2, 2))
    for _ in range(steps):  # F = identity for a constant bias and no rotation
        p = p + v @ noise @ v.T
    assert p[0, 0] == pytest.approx(n_density**2 * steps * dt, rel=1e-9)
    assert p[1, 1] == pytest.approx(k_density**2 * steps * dt, rel=1e-9)


def test_px4_and_ardupilot_take_deviations_per_ekf_step(noise):
    files = export_files(noise.export())
    px4, ardupilot = _pairs(files["px4_ekf2.params"], "param set "), _pairs(
        files["ardupilot_ek3.parm"])
    for names, dt, got in (
            (("EKF2_GYR_NOISE", "EKF2_ACC_NOISE", "EKF2_GYR_B_NOISE", "EKF2_ACC_B_NOISE"),
             PX4_PREDICT_S, px4),
            (("EK3_GYRO_P_NSE", "EK3_ACC_P_NSE", "EK3_GBIAS_P_NSE", "EK3_ABIAS_P_NSE"),
             ARDUPILOT_DT_S, ardupilot)):
        assert list(got) == list(names)
        for name, (sensor, term) in zip(names, (("gyro", "N"), ("accel", "N"), ("gyro", "K"),
                                                 ("accel", "K"))):
            assert got[name] == pytest.approx(_expected(noise, sensor, term) / math.sqrt(dt),
                                              rel=1e-5), name
    # (dt * EKF2_GYR_NOISE)^2 per step: N^2 T over T = 100 steps of dt, as the Allan model
    gyr = px4["EKF2_GYR_NOISE"]
    assert 100 * (PX4_PREDICT_S * gyr) ** 2 == pytest.approx(
        _expected(noise, "gyro", "N") ** 2 * 100 * PX4_PREDICT_S, rel=1e-5)


def test_inflation_multiplies_every_value_and_every_file_says_so(noise):
    plain, inflated = noise.export(), noise.export(4.0)
    for name, text in export_files(inflated).items():
        assert "inflated 4x for a moving platform: every value" in text, name
    for name, text in export_files(plain).items():
        assert "not inflated: the static record's values" in text, name
    for a, b in zip(px4_parameters(plain), px4_parameters(inflated)):
        assert b.value == pytest.approx(4.0 * a.value, rel=1e-12)
    assert "Inflated 4x" in noise.matlab_script(4.0)
    assert yaml.safe_load(noise.kalibr_yaml(inflate=4.0))["gyroscope_noise_density"] == \
        pytest.approx(4.0 * _expected(noise, "gyro", "N"), rel=1e-6)
    data = exports_dict(inflated)
    assert data["inflate"] == 4.0 and data["vins"]["gyr_w"]["value"] == pytest.approx(
        4.0 * _expected(noise, "gyro", "K") * math.sqrt(RATE))
    assert data["measured"]["gyro_N"]["value"] == pytest.approx(_expected(noise, "gyro", "N"))


def test_an_upper_limit_is_named_beside_its_value(noise):
    text = export_files(noise.export())["vins_imu.yaml"]
    limits = [a.axis.column for a in noise.axes if a.value("K")[1] == "upper limit"]
    for line in text.splitlines():
        if line.startswith(("gyr_w", "acc_w")):
            axis = line.split("# ")[1].split(", ")[1]
            assert ("upper limit" in line) == (axis in limits), line


def test_inflation_below_one_and_one_sensor_are_refused(noise):
    with pytest.raises(InputError) as err:
        noise.export(0.5)
    assert str(err.value) == ("the inflation factor must be at least 1 (a moving platform is "
                              "noisier than a static one), got 0.5")
    gyros = type(noise)(tuple(noise.of("gyro")), noise.rate, noise.source)
    with pytest.raises(InputError) as err:
        gyros.export()
    assert str(err.value) == ("each VIO and autopilot export needs gyro and accelerometer axes; "
                              "there is no accel column")


@pytest.fixture(scope="module")
def record(columns, tmp_path_factory):
    path = tmp_path_factory.mktemp("exports") / "imu.csv"
    pd.DataFrame(columns).to_csv(path, index=False, float_format="%.9g")
    return path


@pytest.mark.slow
def test_the_command_writes_every_export_inflated(record, tmp_path, capsys):
    out = tmp_path / "noise"
    code = cli.main(["allan", str(record), "--rate", "100", "--columns", ",".join(TRUTH),
                     "--inflate", "3", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    for name in ("imu.yaml", "openvins_kalibr_imu_chain.yaml", "vins_imu.yaml",
                 "orbslam3_imu.yaml", "px4_ekf2.params", "ardupilot_ek3.parm", "imu_params.m"):
        assert re.search(r"[Ii]nflated 3x", (out / name).read_text()), name


def test_the_command_refuses_a_deflating_factor_in_its_usage(record, tmp_path, capsys):
    out = tmp_path / "noise"
    with pytest.raises(SystemExit) as stop:
        cli.main(["allan", str(record), "--rate", "100", "--columns", "gx_dps,ax_g", "--inflate",
                  "0.5", "--out", str(out)])
    assert stop.value.code == 2 and not out.exists()
    assert capsys.readouterr().err == (
        "fosmodel: error: argument --inflate: expected a factor of at least 1 (a moving platform "
        "is noisier than a static one), got '0.5' (fosmodel allan --help shows the usage)\n")


def test_the_command_refuses_a_factor_with_nothing_to_inflate(record, tmp_path, capsys):
    out = tmp_path / "noise"
    code = cli.main(["allan", str(record), "--rate", "100", "--column", "gx_dps", "--inflate",
                     "2", "--out", str(out)])
    assert code == 2 and not out.exists()
    assert capsys.readouterr().err == (
        "fosmodel: error: --inflate scales the exports of --columns (Kalibr, OpenVINS, VINS, "
        "ORB-SLAM3, PX4, ArduPilot); one --column has none\n")
