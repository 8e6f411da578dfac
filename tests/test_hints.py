"""Hints on records whose numbers look wrong for what they claim: units, decimation."""

from pathlib import Path

import numpy as np
import pytest

from fosmodel import cli
from fosmodel.io.loader import load_record
from fosmodel.noise.axes import Axis, resolve_axes
from fosmodel.noise.hints import decimation_hint, record_hints, units_hint

SHARED = Path(__file__).parents[2] / "shared" / "data"
NO_SHARED = "../shared/data is not here (a fresh clone has no ../shared)"
GX = Axis("gx", "gyro", "deg/s", "given")


def test_a_gyro_in_rad_s_declared_deg_s_is_told():
    rads = np.random.default_rng(1).normal(0, 1.7e-3, 60_000)  # 100 Hz: 0.58 deg/sqrt(h)
    hint = units_hint(rads, GX, 100.0)
    assert hint == ("gx: values look like rad/s, not deg/s: its ARW 0.01 deg/sqrt(h) would be "
                    "better than a tactical-grade gyro's, 0.58 in rad/s a MEMS gyro's; if so, "
                    "give its units as gx=rad/s")
    assert units_hint(rads * 180 / np.pi, GX, 100.0) is None  # the same gyro in deg/s
    assert units_hint(rads, Axis("gx", "gyro", "rad/s", "given"), 100.0) is None
    assert units_hint(rads * 1e-3, GX, 100.0) is None  # too quiet for a MEMS gyro either way


def test_a_gyro_subsampled_without_averaging_is_told_an_averaged_one_not():
    fast = np.random.default_rng(2).normal(0, 0.3, 500_000)  # deg/s at 100 Hz: 1.8 deg/sqrt(h)
    hint = decimation_hint({"gx": fast[::25]}, [GX], 4.0)
    assert hint is not None and hint.startswith("at 4 Hz the samples are uncorrelated and their "
                                                "white noise large (gx -0.")
    assert hint.endswith("average (or low-pass) before decimating")
    assert decimation_hint({"gx": fast.reshape(-1, 25).mean(axis=1)}, [GX], 4.0) is None
    assert decimation_hint({"gx": fast}, [GX], 100.0) is None  # a fast record: no question
    smooth = np.convolve(fast, np.ones(50) / 50, "valid")[::25] * 5  # filtered: correlated
    assert decimation_hint({"gx": smooth}, [GX], 4.0) is None


def test_allan_prints_the_units_hint_in_one_line(tmp_path, capsys):
    path = tmp_path / "r.csv"
    gx = np.random.default_rng(3).normal(0, 1.7e-3, 30_000)
    path.write_text("Fs,100\ngx_dps\n" + "".join(f"{v:.7f}\n" for v in gx))
    assert cli.main(["allan", str(path), "--column", "gx_dps", "--out",
                     str(tmp_path / "o")]) == 0
    hints = [line for line in capsys.readouterr().err.splitlines() if "hint:" in line]
    assert hints == ["fosmodel: hint: gx_dps: values look like rad/s, not deg/s: its ARW "
                     "0.0099 deg/sqrt(h) would be better than a tactical-grade gyro's, 0.57 in "
                     "rad/s a MEMS gyro's; if so, give its units as gx_dps=rad/s"]


@pytest.mark.skipif(not SHARED.exists(), reason=NO_SHARED)
@pytest.mark.parametrize(("name", "rate"), [
    ("adis16405/imu1.csv.gz", 100.0),
    ("mpu6050_sunsided/unmoved-with-x-pointing-forward-10min.csv.gz", None)])
def test_no_hint_on_the_real_records(name, rate):
    rec = load_record(SHARED / name, rate=rate, uniform=rate is None, outliers="keep")
    axes = resolve_axes([c for c in rec.names if c != "temp_c"], declared=rec.units)
    assert {a.units for a in axes} == {"deg/s", "g"}
    assert record_hints({a.column: rec.column(a.column) for a in axes}, axes,
                        rec.require_rate()) == []
