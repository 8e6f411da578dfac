"""Several axes in one Allan run, and the Kalibr, MATLAB and JSON exports."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.noise.axes import Axis, infer_axis, resolve_axes
from fosmodel.noise.imu_noise import imu_noise

RATE = 100.0
N_SAMPLES = 200_000
#: Per column: white-noise density N (units*sqrt(s)) and rate random walk K (units/sqrt(s)).
TRUTH = {"gx_dps": (0.005, 2e-4), "gy_dps": (0.007, 0.0), "gz_dps": (0.004, 1e-4),
         "ax_g": (1e-4, 4e-6), "ay_g": (1.5e-4, 0.0), "az_g": (1.2e-4, 5e-6)}
DEG = math.pi / 180.0
G = 9.80665


def _axis(n_white: float, k_walk: float, rng: np.random.Generator) -> np.ndarray:
    white = n_white * math.sqrt(RATE) * rng.standard_normal(N_SAMPLES)
    walk = np.cumsum(k_walk / math.sqrt(RATE) * rng.standard_normal(N_SAMPLES))
    return white + walk


@pytest.fixture(scope="module")
def six_axes(tmp_path_factory) -> str:
    rng = np.random.default_rng(7)
    frame = pd.DataFrame({name: _axis(*truth, rng) for name, truth in TRUTH.items()})
    path = tmp_path_factory.mktemp("imu") / "imu.csv"
    frame.to_csv(path, index=False, float_format="%.9g")
    return str(path)


@pytest.fixture(scope="module")
def noise(six_axes):
    frame = pd.read_csv(six_axes)
    axes = resolve_axes(list(TRUTH))
    return imu_noise({c: frame[c].to_numpy() for c in frame}, axes, RATE, six_axes)


@pytest.mark.parametrize(("name", "told"), [
    ("gx_dps", ("gyro", "deg/s")), ("gyro_x", ("gyro", None)), ("gyro_rad[0]", ("gyro", "rad/s")),
    ("wz", ("gyro", None)), ("angular_velocity.y", ("gyro", None)), ("GY_RADS", ("gyro", "rad/s")),
    ("ax_g", ("accel", "g")), ("acc_y_mps2", ("accel", "m/s^2")),
    ("accelerometer_m_s2[2]", ("accel", "m/s^2")), ("linear_acceleration.z", ("accel", None)),
    ("az_mg", ("accel", "mg")), ("temp_c", (None, None)), ("gain", (None, None)),
    ("time", (None, None)), ("axis", (None, None)),
])
def test_the_sensor_and_units_a_name_tells(name, told):
    assert infer_axis(name) == told


def test_axes_given_inferred_and_refused():
    axes = resolve_axes(["gx_rads", "gy", "ax:accel:m/s^2", "acc_z"], {"gyro": "rad/s",
                                                                        "accel": "mg"})
    assert [(a.column, a.sensor, a.units) for a in axes] == [
        ("gx_rads", "gyro", "rad/s"), ("gy", "gyro", "rad/s"), ("ax", "accel", "m/s^2"),
        ("acc_z", "accel", "mg")]
    assert axes[2].told == "given" and axes[1].told == "gyro from the name, units given"
    cases = {
        ("gx",): "column 'gx': a gyro by its name, but the name does not tell its units; give "
                 "them as gx=UNITS (e.g. gx=deg/s)",
        ("temp",): "column 'temp': its name does not tell the sensor; give its units, which do, "
                   "as temp=UNITS (e.g. temp=deg/s for a gyro, temp=m/s^2 for an accelerometer)",
        ("ax:accel",): "expected COLUMN or COLUMN:SENSOR:UNITS (e.g. gx:gyro:deg/s), got "
                       "'ax:accel'",
        ("gx_dps", "gx_dps"): "column 'gx_dps' is named twice in columns=",
    }
    for columns, message in cases.items():
        with pytest.raises(InputError) as err:
            resolve_axes(list(columns))
        assert str(err.value) == message
    with pytest.raises(InputError, match="unknown gyro units 'deg/sec'"):
        resolve_axes(["gx:gyro:deg/sec"])


@pytest.mark.slow
def test_each_axis_recovers_its_white_noise_and_says_what_its_random_walk_is(noise):
    """N within its 95 % interval on every axis; K, where resolved, within its interval, and
    exported as the upper limit where not (recovery over seeds is tested in test_allan_fit)."""
    for a in noise.axes:
        n_true, k_true = TRUTH[a.axis.column]
        fit = a.fit
        lo, hi = fit.interval("N", 0.95)
        assert fit.resolved["N"] and lo <= n_true <= hi, a.axis.column
        if fit.resolved["K"]:
            lo, hi = fit.interval("K", 0.95)
            assert k_true and lo <= k_true <= hi, a.axis.column
        else:
            assert a.value("K") == (fit.limits["K"], "upper limit") and fit.limits["K"] > 0
    resolved = {a.axis.column for a in noise.axes if a.fit.resolved["K"]}
    assert {"gz_dps", "ax_g", "az_g"} <= resolved


def _hand(noise, sensor: str, term: str) -> tuple[float, str]:
    """The largest value over a sensor's axes in SI, computed here from the fits."""
    scale = {"gyro": DEG, "accel": G}[sensor]
    values = {}
    for a in noise.axes:
        if a.axis.sensor == sensor:
            fit = a.fit
            coef = fit.coefficients[term] if fit.resolved[term] else fit.limits[term]
            values[a.axis.column] = coef * scale
    column = max(values, key=values.get)
    return values[column], column


def test_the_kalibr_file_parses_and_holds_the_hand_computed_values(noise):
    text = noise.kalibr_yaml()
    data = yaml.safe_load(text)
    assert set(data) == {"accelerometer_noise_density", "accelerometer_random_walk",
                         "gyroscope_noise_density", "gyroscope_random_walk", "rostopic",
                         "update_rate"}
    assert data["update_rate"] == RATE and data["rostopic"] == "/imu0"
    for key, sensor, term in (("gyroscope_noise_density", "gyro", "N"),
                              ("gyroscope_random_walk", "gyro", "K"),
                              ("accelerometer_noise_density", "accel", "N"),
                              ("accelerometer_random_walk", "accel", "K")):
        value, column = _hand(noise, sensor, term)
        assert data[key] == pytest.approx(value, rel=1e-6)
        assert data[key] > 0
        line = next(ln for ln in text.splitlines() if ln.startswith(key))
        assert f", {column}" in line and ("sqrt(Hz)" in line)
    # The largest white noise is the worst axis's (gy 0.007 deg/s*sqrt(s), ay 1.5e-4
    # g*sqrt(s)), converted; within 5 %: the fit gives the long taus a say (MODEL_ALLOWANCE),
    # and on 2000 s of gy their scatter pulls N 4.5 % low, inside its interval.
    assert data["gyroscope_noise_density"] == pytest.approx(0.007 * DEG, rel=0.05)
    assert data["accelerometer_noise_density"] == pytest.approx(1.5e-4 * G, rel=0.05)
    assert re.search(r"gyroscope_noise_density: \S+  # rad/s/sqrt\(Hz\)", text)
    assert re.search(r"accelerometer_random_walk: \S+  # m/s\^3/sqrt\(Hz\)", text)


def test_the_matlab_parameters_are_the_axes_in_si(noise):
    text = noise.matlab_script()
    for sensor, maker in (("gyro", "gyroparams"), ("accel", "accelparams")):
        block = re.search(rf"{sensor} = {maker}\((.*?)\);", text, re.S).group(1)
        for prop, term in (("NoiseDensity", "N"), ("BiasInstability", "B"),
                           ("RandomWalk", "K")):
            values = re.search(rf"'{prop}', \[([^\]]*)\]", block).group(1).split()
            expected = [a.si(term) for a in noise.of(sensor)]
            assert [float(v) for v in values] == pytest.approx(expected, rel=1e-6)
    assert ("imu = imuSensor('accel-gyro', 'SampleRate', 100, 'Gyroscope', gyro, "
            "'Accelerometer', accel);") in text


def test_the_json_one_numbers_match_the_kalibr_file(noise):
    data = json.loads(json.dumps(noise.to_dict()))
    kalibr = yaml.safe_load(noise.kalibr_yaml())
    for key, entry in data["one_number"].items():
        assert entry["value"] == pytest.approx(kalibr[key], rel=1e-6)
    first = data["axes"][0]
    assert first["column"] == "gx_dps" and first["noise_density"]["units"] == "rad/s/sqrt(Hz)"
    assert first["noise_density"]["value"] == pytest.approx(
        first["fit"]["coefficients"]["N"] * DEG)


def test_one_sensor_type_has_no_kalibr_file_and_no_imu_sensor(noise):
    gyros = type(noise)(tuple(noise.of("gyro")), noise.rate, noise.source)
    with pytest.raises(InputError, match="needs gyro and accelerometer axes; there is no "
                                         "accel column"):
        gyros.kalibr_yaml()
    assert "imuSensor" not in gyros.matlab_script() and "gyroparams" in gyros.matlab_script()


def _run(args, capsys):
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.slow
def test_the_command_writes_one_report_for_all_axes(six_axes, noise, tmp_path, capsys):
    out, js = tmp_path / "report", tmp_path / "noise.json"
    code, stdout, err = _run(["allan", six_axes, "--rate", RATE, "--columns", ",".join(TRUTH),
                              "--out", out, "--json", js], capsys)
    assert code == 0, err
    assert "fosmodel: gx_dps: gyro in deg/s (from the name)" in err
    assert "Allan noise parameters per axis" in stdout
    names = {p.name for p in out.iterdir()}
    assert {"imu.yaml", "imu_params.m", "imu_noise.json", "noise.md", "noise_si.csv",
            "allan_gyro.png", "allan_accel.png", "axes"} <= names
    assert sorted(p.name for p in (out / "axes").iterdir()) == sorted(TRUTH)
    assert yaml.safe_load((out / "imu.yaml").read_text()) == yaml.safe_load(noise.kalibr_yaml())
    assert json.loads(js.read_text())["one_number"] == noise.to_dict()["one_number"]


@pytest.mark.parametrize(("extra", "message"), [
    (["--columns", "gx_dps,ax_g", "--sensor", "gyro"],
     "fosmodel: error: column 'ax_g': its name tells an accelerometer, not a gyro; if it is one, "
     "give its units as ax_g=UNITS"),
    (["--columns", "gx_dps,ax_g", "--units", "ax_g=deg/s", "--sensor", "accel"],
     "fosmodel: error: column 'gx_dps': its name tells a gyro, not an accelerometer; if it is "
     "one, give its units as gx_dps=UNITS"),
    (["--columns", "gx_dps,ax_g", "--units", "gx_dps=deg/s,ax=g"],
     "fosmodel: error: units are given for column 'ax', which is not among the columns: "
     "gx_dps, ax_g"),
    (["--columns", "ax_g", "--units", "deg/s", "--sensor", "accel"],
     "fosmodel: error: column 'ax_g': deg/s is a unit of a gyro, not of an accelerometer"),
])
def test_the_command_refuses_mixed_or_untold_axes(six_axes, tmp_path, capsys, extra, message):
    out = tmp_path / "report"
    code, _, err = _run(["allan", six_axes, "--rate", RATE, *extra, "--out", out], capsys)
    assert code == 2 and err.strip() == message and not out.exists()


def test_axis_describes_where_its_units_came_from():
    axis = Axis("gx", "gyro", "deg/s", "given")
    assert axis.describe() == "gx: gyro in deg/s (given)"


def test_the_static_imu_scenario_gives_back_its_white_noise_on_every_axis():
    from data_synth import make_scenario

    rec = make_scenario("static_imu", duration=1800.0, seed=3)
    truth = {s["name"]: s["params"] for s in rec.truth["sources"]}
    axes = resolve_axes(list(rec.columns))
    assert [a.sensor for a in axes] == ["gyro"] * 3 + ["accel"] * 3
    noise = imu_noise(rec.columns, axes, rec.rate, "static_imu")
    for a in noise.axes:
        lo, hi = a.fit.interval("N", 0.95)
        assert lo <= truth[f"{a.axis.column}_white"]["density"] <= hi, a.axis.column
    kalibr = yaml.safe_load(noise.kalibr_yaml())
    assert kalibr["gyroscope_noise_density"] == pytest.approx(
        truth["gy_dps_white"]["density"] * DEG, rel=0.05)  # gy has the largest ARW


def test_the_command_writes_nothing_over_its_record_and_nothing_on_a_bad_column(
        six_axes, tmp_path, capsys):
    before = Path(six_axes).read_bytes()
    out = tmp_path / "report"
    common = ["allan", six_axes, "--rate", RATE, "--out", out]
    for extra, message in ((["--columns", "gx_dps,ax_g", "--json", six_axes], "--json"),
                           (["--columns", "gx_dps,gq_dps"], "'gq_dps'")):
        code, _, err = _run([*common, *extra], capsys)
        assert code == 2 and len(err.strip().splitlines()) == 1, err
        assert err.startswith("fosmodel: error: ") and message in err
        assert not out.exists() and Path(six_axes).read_bytes() == before


def test_each_axis_sets_every_convention_side_by_side(noise):
    """The table's fitted values (a limit as '< value'), read-offs and datasheet minimum come
    from NoiseFit.conventions, in navigation units."""
    table = noise.table()
    for a, (_, row) in zip(noise.axes, table.iterrows()):
        fit = a.fit
        for term in ("N", "K"):
            value, kind = fit.conservative(term)
            nav, units = fit.navigation(term, value)
            expected = f"{'< ' if kind == 'upper limit' else ''}{nav:.3g} {units}"
            assert row[f"{term} fitted"] == fit.conventions()[f"{term} fitted"] == expected
        minimum = fit.readoff["min_adev"]
        assert row["in-run bias stability (min)"] == (
            "-" if not math.isfinite(minimum) else
            f"{fit.navigation('B', minimum)[0]:.3g} {fit.navigation('B', minimum)[1]} at "
            f"{fit.readoff['min_tau_s']:.3g} s")


def test_the_json_may_go_into_the_report_directory_the_command_makes(six_axes, tmp_path,
                                                                      capsys):
    out = tmp_path / "out1"
    code, _, err = _run(["allan", six_axes, "--rate", RATE, "--column", "gx_dps", "--out", out,
                         "--json", out / "x.json"], capsys)
    assert code == 0, err
    assert json.loads((out / "x.json").read_text())["column"] == "gx_dps"
    assert (out / "report.md").exists() or any(out.iterdir())
    code, _, err = _run(["allan", six_axes, "--rate", RATE, "--column", "gx_dps", "--out",
                         tmp_path / "out2", "--json", tmp_path / "elsewhere" / "x.json"], capsys)
    assert code == 2 and not (tmp_path / "out2").exists()
    assert err.strip() == (f"fosmodel: error: cannot write {tmp_path / 'elsewhere' / 'x.json'}: "
                           f"directory {tmp_path / 'elsewhere'} does not exist")
