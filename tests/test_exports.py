"""The VIO and autopilot exports: each file parsed back against a hand computation."""

from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
import yaml

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.noise.allan_fit import gauss_markov_avar
from fosmodel.noise.axes import resolve_axes
from fosmodel.noise.exports import (
    ARDUPILOT_DT_S,
    GM_WHITE_MAX_TC_S,
    PX4_PREDICT_S,
    Density,
    NoiseExport,
    clamp_notes,
    export_files,
    exports_dict,
    px4_parameters,
)
from fosmodel.noise.imu_noise import imu_noise

cv2 = pytest.importorskip("cv2", reason="OpenCV (opencv-python-headless) reads the VIO exports")
mavparm = pytest.importorskip("pymavlink.mavparm", reason="pymavlink reads ArduPilot's files")

RATE = 100.0
#: Per column: white-noise density N (units*sqrt(s)) and rate random walk K (units/sqrt(s)).
TRUTH = {"gx_dps": (0.006, 3e-4), "gy_dps": (0.004, 2e-4), "gz_dps": (0.005, 1e-4),
         "ax_g": (1.2e-4, 5e-6), "ay_g": (1e-4, 4e-6), "az_g": (1.5e-4, 6e-6)}
DEG, G = math.pi / 180.0, 9.80665
#: The accelerometers' mean at rest, in g: gravity on a tilted triad, a little off 1 g.
MEAN_G = {"ax_g": 0.03, "ay_g": -0.02, "az_g": 1.004}
GRAVITY_HERE = math.sqrt(sum(v * v for v in MEAN_G.values()))


@pytest.fixture(scope="module")
def columns():
    rng = np.random.default_rng(11)
    n = 120_000
    return {c: MEAN_G.get(c, 0.0) + nw * math.sqrt(RATE) * rng.standard_normal(n)
            + np.cumsum(k / math.sqrt(RATE) * rng.standard_normal(n))
            for c, (nw, k) in TRUTH.items()}


@pytest.fixture(scope="module")
def noise(columns):
    return imu_noise(columns, resolve_axes(list(TRUTH)), RATE, "/data/imu.csv")


def _expected(noise, sensor, term):
    """The hand computation: the largest exported value over a sensor's axes, in SI."""
    scale = DEG if sensor == "gyro" else G
    return max(a.fit.conservative(term)[0] * scale for a in noise.of(sensor))


def _storage(text):
    """The file as OpenCV's ``cv::FileStorage`` reads it (VINS, ORB-SLAM3 and OpenVINS do)."""
    assert text.startswith("%YAML:1.0\n")
    return cv2.FileStorage(text, cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY)


def _real(node):
    """``node.real()`` where the C++ checks ``isReal()`` first, as every consumer here does."""
    assert node.isReal(), node.type()
    return node.real()


def _rows(node):
    """A matrix as OpenVINS's YAML parser reads it: ``node[r][c]`` of a list of rows."""
    return np.array([[node.at(r).at(c).real() for c in range(node.at(r).size())]
                     for r in range(node.size())])


def _pairs(text, prefix=""):
    """``NAME VALUE`` lines (after ``prefix``), comments skipped."""
    out = {}
    for line in text.splitlines():
        if line and not line.startswith("#"):
            assert line.startswith(prefix), line
            name, value = line[len(prefix):].split()
            out[name] = float(value)
    return out


def _qgroundcontrol(text):
    """Parameters as QGroundControl's ParameterManager loads a file: ``#`` lines skipped, then
    tab-separated vehicle id, component id, name, value, type; any other line is dropped."""
    out = {}
    for line in text.splitlines():
        if line.startswith("#"):
            continue
        fields = line.split("\t")
        if len(fields) != 5:
            continue  # QGroundControl skips it without a word
        vehicle, component, name, value, kind = fields
        assert (int(vehicle), int(component), int(kind)) == (1, 1, 9), line  # REAL32
        out[name] = float(value)
    return out


def _pymavlink(text, tmp_path):
    """Parameters as pymavlink's MAVParmDict.load reads an ArduPilot ``.parm`` file."""
    path = tmp_path / "ek3.parm"
    path.write_text(text)
    params = mavparm.MAVParmDict()
    assert params.load(str(path), use_excludes=False)
    return dict(params)


def test_openvins_reads_the_chain_under_its_own_name(noise):
    files = export_files(noise.export())
    fs = _storage(files["kalibr_imu_chain.yaml"])  # estimator_config.yaml names this file
    imu0 = fs.getNode("imu0")
    assert _real(imu0.getNode("gyroscope_noise_density")) == pytest.approx(
        _expected(noise, "gyro", "N"), rel=1e-6)
    assert _real(imu0.getNode("gyroscope_random_walk")) == pytest.approx(
        _expected(noise, "gyro", "K"), rel=1e-6)
    assert _real(imu0.getNode("accelerometer_noise_density")) == pytest.approx(
        _expected(noise, "accel", "N"), rel=1e-6)
    assert _real(imu0.getNode("accelerometer_random_walk")) == pytest.approx(
        _expected(noise, "accel", "K"), rel=1e-6)
    assert imu0.getNode("rostopic").string() == "/imu0"  # unquoted, it takes the comment
    assert imu0.getNode("model").string() == "kalibr"
    assert np.array_equal(_rows(imu0.getNode("Tw")), np.eye(3))
    assert np.array_equal(_rows(imu0.getNode("Tg")), np.zeros((3, 3)))
    assert np.array_equal(_rows(imu0.getNode("T_i_b")), np.eye(4))
    assert '"maybe 10-20x"' in files["kalibr_imu_chain.yaml"]
    assert yaml.safe_load(files["imu.yaml"])["rostopic"] == "/imu0"


def test_orbslam3_settings_parser_reads_every_imu_node(noise):
    fs = _storage(export_files(noise.export())["orbslam3_imu.yaml"])
    # System.cc: File.version "1.0" selects Settings, whose readParameter<float> wants isReal
    assert fs.getNode("File.version").isString() and fs.getNode("File.version").string() == "1.0"
    assert _real(fs.getNode("IMU.NoiseGyro")) == pytest.approx(_expected(noise, "gyro", "N"),
                                                                rel=1e-6)
    assert _real(fs.getNode("IMU.NoiseAcc")) == pytest.approx(_expected(noise, "accel", "N"),
                                                               rel=1e-6)
    assert _real(fs.getNode("IMU.GyroWalk")) == pytest.approx(_expected(noise, "gyro", "K"),
                                                               rel=1e-6)
    assert _real(fs.getNode("IMU.AccWalk")) == pytest.approx(_expected(noise, "accel", "K"),
                                                              rel=1e-6)
    assert _real(fs.getNode("IMU.Frequency")) == RATE
    assert np.array_equal(fs.getNode("IMU.T_b_c1").mat(), np.eye(4))  # readParameter<cv::Mat>


def test_vins_reads_its_imu_nodes_and_the_records_gravity(noise):
    fs = _storage(export_files(noise.export())["vins_imu.yaml"])
    assert fs.getNode("imu").isInt() and int(fs.getNode("imu").real()) == 1
    assert fs.getNode("imu_topic").string() == "/imu0"
    assert _real(fs.getNode("gyr_n")) == pytest.approx(
        _expected(noise, "gyro", "N") * math.sqrt(2 * RATE), rel=1e-6)
    assert _real(fs.getNode("acc_n")) == pytest.approx(
        _expected(noise, "accel", "N") * math.sqrt(2 * RATE), rel=1e-6)
    assert _real(fs.getNode("gyr_w")) == pytest.approx(
        _expected(noise, "gyro", "K") * math.sqrt(RATE), rel=1e-6)
    assert _real(fs.getNode("acc_w")) == pytest.approx(
        _expected(noise, "accel", "K") * math.sqrt(RATE), rel=1e-6)
    assert _real(fs.getNode("g_norm")) == pytest.approx(GRAVITY_HERE * G, rel=1e-5)


def test_vins_takes_standard_gravity_when_the_record_has_none(columns):
    flat = {c: v - np.mean(v) if c.startswith("a") else v for c, v in columns.items()}
    text = export_files(imu_noise(flat, resolve_axes(list(TRUTH)), RATE, "x.csv").export())[
        "vins_imu.yaml"]
    assert _real(_storage(text).getNode("g_norm")) == pytest.approx(G, rel=1e-6)
    assert "m/s^2, standard gravity" in text


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


def test_px4_and_ardupilot_take_deviations_per_ekf_step(noise, tmp_path):
    files = export_files(noise.export())
    px4, ardupilot = _qgroundcontrol(files["px4_ekf2.params"]), _pymavlink(
        files["ardupilot_ek3.parm"], tmp_path)
    assert _pairs(files["px4_ekf2_console.txt"], "param set ") == px4
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
    for name in ("imu.yaml", "kalibr_imu_chain.yaml", "vins_imu.yaml", "orbslam3_imu.yaml",
                 "px4_ekf2.params", "px4_ekf2_console.txt", "ardupilot_ek3.parm",
                 "imu_params.m"):
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


def _export(accel_k, gyro_n=1e-4, gm=(0.0, None)):
    """A NoiseExport with chosen densities (SI), to reach the autopilots' documented limits."""
    return NoiseExport({("gyro", "N"): Density(gyro_n, "gx", "fitted", *gm),
                        ("gyro", "K"): Density(1e-5, "gx", "fitted"),
                        ("accel", "N"): Density(2e-3, "ax", "fitted"),
                        ("accel", "K"): Density(accel_k, "ax", "fitted")},
                       RATE, "x.csv", ("gx", "ax"))


def test_a_value_beyond_its_documented_range_is_clamped_and_said(tmp_path):
    e = _export(accel_k=1.26e-4 * 10)  # EKF2_ACC_B_NOISE 0.0126 at dt 0.01 s; PX4's max 0.01
    files = export_files(e)
    px4 = _qgroundcontrol(files["px4_ekf2.params"])
    assert px4["EKF2_ACC_B_NOISE"] == 0.01
    assert "# EKF2_ACC_B_NOISE: m/s^3, ax; CLAMPED: 0.0126 is outside the documented range " \
           "0-0.01, written as 0.01" in files["px4_ekf2.params"]
    assert _pairs(files["px4_ekf2_console.txt"], "param set ")["EKF2_ACC_B_NOISE"] == 0.01
    assert _pymavlink(files["ardupilot_ek3.parm"], tmp_path)["EK3_ABIAS_P_NSE"] == \
        pytest.approx(1.26e-3 / math.sqrt(ARDUPILOT_DT_S), rel=1e-5)  # within 0-0.02
    assert clamp_notes(e) == [
        "PX4 EKF2_ACC_B_NOISE 0.0126 m/s^3 is above its documented range 0-0.01: written as "
        "its maximum 0.01, so the filter trusts this sensor more than the record says"]
    assert exports_dict(e)["px4_ekf2"]["EKF2_ACC_B_NOISE"] == {
        "value": 0.01, "units": "m/s^3", "clamped_from": pytest.approx(0.0126)}
    low = _export(accel_k=1e-5, gyro_n=1e-6)  # EKF2_GYR_NOISE 1e-5, below PX4's 1e-4
    assert _qgroundcontrol(export_files(low)["px4_ekf2.params"])["EKF2_GYR_NOISE"] == 1e-4
    assert clamp_notes(low)[0].startswith("PX4 EKF2_GYR_NOISE 1e-05 rad/s is below its "
                                          "documented range 0.0001-0.1: written as its minimum")


def test_the_console_says_what_was_clamped(record, tmp_path, capsys):
    out = tmp_path / "noise"
    code = cli.main(["allan", str(record), "--rate", "100", "--columns", ",".join(TRUTH),
                     "--inflate", "20", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    clamped = [p.name for p in px4_parameters(imu_noise(
        {c: pd.read_csv(record)[c].to_numpy() for c in TRUTH}, resolve_axes(list(TRUTH)), RATE,
        str(record)).export(20.0)) if p.clamped_from is not None]
    assert clamped  # 20x lifts the accelerometer bias noise above PX4's 0.01
    for name in clamped:
        assert re.search(rf"^warning: PX4 {name} \S+ \S+ is above its documented range", err,
                         re.M), err
        assert "CLAMPED" in (out / "px4_ekf2.params").read_text()


def test_a_short_gauss_markov_term_joins_the_white_noise(noise):
    """N with G sqrt(2 Tc): the GM term's Allan variance tends to 2 G^2 Tc / tau, white noise's
    N^2 / tau, well beyond Tc."""
    tc = 5.0
    assert gauss_markov_avar(np.array([1e4 * tc]), tc)[0] * 1e4 * tc == pytest.approx(
        2 * tc, rel=1e-3)
    axis = noise.of("gyro")[0]
    n = axis.fit.coefficients["N"]
    fit = replace(axis.fit, terms=(*axis.fit.terms, "G"), gm_tc=tc,
                  coefficients={**axis.fit.coefficients, "G": 2.0 * n})
    gm_axis = replace(axis, fit=fit)
    white = 2.0 * n * math.sqrt(2 * tc) * DEG
    assert gm_axis.gm_white_si() == pytest.approx(white)
    e = replace(noise, axes=(gm_axis, *noise.axes[1:])).export()
    assert e.value("gyro", "N") == pytest.approx(math.hypot(axis.si("N"), white))
    text = export_files(e)["imu.yaml"]
    assert "# White noise = sqrt(N^2 + 2 G^2 Tc): Allan N with the white-like part" in text
    assert f"with a Gauss-Markov term's white-like {white:.3e} (Tc 5 s)" in text
    slow = replace(axis, fit=replace(fit, gm_tc=GM_WHITE_MAX_TC_S * 2))
    assert slow.gm_white_si() == 0.0  # a slow bias, not noise, to a filter
