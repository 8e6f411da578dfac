"""PX4 ULog files through load_record: the logs of ../shared/data/px4_ulog (pyulog's test logs)
read sample for sample against pyulog itself, multi-instance topics, vehicle_imu's increments
as rates, the loader's checks on real autopilot time stamps, and bad input in one exact line.

The tests of real logs are skipped when ../shared is absent; those of bad input write their
own files."""

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.io.loader import load_record
from fosmodel.io.topics import ImuTopic, TopicError, imu_topics

pyulog = pytest.importorskip("pyulog", reason="reading PX4 ULog files needs the 'px4' extra")

LOGS = Path(__file__).parents[2] / "shared" / "data" / "px4_ulog"
SAMPLE, SMALL = LOGS / "sample.ulg", LOGS / "sample_log_small.ulg"
needs_logs = pytest.mark.skipif(
    not LOGS.is_dir(), reason=f"the PX4 logs are not here: {LOGS} is absent (only a checkout "
                              "beside the project's shared/ folder has them)")
COLUMNS = ["gx", "gy", "gz", "ax", "ay", "az"]


def _pyulog(path, name, instance=0):
    """The topic's fields as pyulog reads them."""
    with open(path, "rb") as fh:
        log = pyulog.ULog(fh, [name])
    return log.get_dataset(name, instance).data


def _message(call):
    with pytest.raises(InputError) as err:
        call()
    assert "\n" not in str(err.value)
    return str(err.value)


@needs_logs
def test_sensor_combined_sample_for_sample():
    assert imu_topics(SAMPLE) == [ImuTopic("sensor_combined", "sensor_combined", 17070,
                                           pytest.approx(247.81, abs=0.01))]
    rec = load_record(SAMPLE, gaps="segments")  # the log has gaps: kept, nothing interpolated
    fields = _pyulog(SAMPLE, "sensor_combined")
    assert rec.names == COLUMNS and rec.n_samples == 17070
    for i in range(3):
        np.testing.assert_array_equal(rec.column(COLUMNS[i]), fields[f"gyro_rad[{i}]"])
        np.testing.assert_array_equal(rec.column(COLUMNS[3 + i]),
                                      fields[f"accelerometer_m_s2[{i}]"])
    np.testing.assert_array_equal(rec.time, fields["timestamp"] / 1e6)
    assert rec.rate == pytest.approx(250.0)  # the median interval, 4 ms
    assert rec.units == {**dict.fromkeys(COLUMNS[:3], "rad/s"),
                         **dict.fromkeys(COLUMNS[3:], "m/s^2")}
    assert rec.metadata == {"format": "PX4 ULog", "topic": "sensor_combined",
                            "message type": "sensor_combined"}
    assert rec.notes[0] == ("PX4 ULog, topic sensor_combined (17070 messages): gx, gy, gz in "
                            "rad/s, ax, ay, az in m/s^2; time from timestamp (us)")
    assert len(rec.segments) == 9


@needs_logs
def test_the_logs_gaps_are_refused_as_in_any_record():
    assert _message(lambda: load_record(SAMPLE)) == (
        f"{SAMPLE}: column 'time', row 1: a gap of 0.036 s where the sample interval is 0.004 s "
        "(8 gap(s) in the record); pass gaps='fill' to interpolate across them or "
        "gaps='segments' to fit on the pieces")
    filled = load_record(SAMPLE, gaps="fill", columns=["gz"])
    assert filled.names == ["gz"] and filled.n_samples == 17221  # 151 samples filled in


@needs_logs
def test_multi_instance_sensor_gyro_with_its_temperature():
    rec = load_record(SMALL, topic="sensor_gyro:1")
    fields = _pyulog(SMALL, "sensor_gyro", 1)
    assert rec.names == ["gx", "gy", "gz", "temperature"] and rec.n_samples == 6
    for column, field in zip(rec.names, ("x", "y", "z", "temperature")):
        np.testing.assert_array_equal(rec.column(column), fields[field])
    np.testing.assert_array_equal(rec.time, fields["timestamp_sample"] / 1e6)
    assert rec.rate == pytest.approx(1.0, abs=1e-3)
    assert 28 < rec.column("temperature").mean() < 29  # instance 1's die, not instance 0's
    assert rec.units["temperature"] == "degC"
    assert load_record(SMALL, topic="sensor_gyro:0").column("temperature").mean() > 40


@needs_logs
def test_the_topics_of_a_log_with_several_instances():
    topics = imu_topics(SMALL)
    assert [t.name for t in topics] == [
        "sensor_accel:0", "sensor_accel:1", "sensor_accel:2", "sensor_combined",
        "sensor_gyro:0", "sensor_gyro:1", "sensor_gyro:2", "vehicle_imu:0", "vehicle_imu:1",
        "vehicle_imu:2"]
    assert [t.count for t in topics] == [6, 6, 6, 1298, 6, 6, 6, 12, 12, 12]
    with pytest.raises(TopicError) as err:
        load_record(SMALL)
    assert str(err.value) == (f"{SMALL}: 10 IMU topics, choose one with topic=: "
                              + ", ".join(t.describe() for t in topics))
    gyros = ", ".join(t.describe() for t in topics if t.type == "sensor_gyro")
    assert _message(lambda: load_record(SMALL, topic="sensor_gyro")) == (
        f"{SMALL}: topic 'sensor_gyro' is logged in 3 instances, choose one with topic=: {gyros}")
    # a topic logged once answers to NAME:0 too
    assert load_record(SMALL, topic="sensor_combined:0", gaps="fill").metadata["topic"] == (
        "sensor_combined")


@needs_logs
def test_vehicle_imu_increments_become_rates():
    rec = load_record(SMALL, topic="vehicle_imu:2")
    fields = _pyulog(SMALL, "vehicle_imu", 2)
    for i in range(3):
        np.testing.assert_array_equal(
            rec.column(COLUMNS[i]),
            fields[f"delta_angle[{i}]"].astype(float) / (fields["delta_angle_dt"] / 1e6))
        np.testing.assert_array_equal(
            rec.column(COLUMNS[3 + i]),
            fields[f"delta_velocity[{i}]"].astype(float) / (fields["delta_velocity_dt"] / 1e6))
    assert rec.column("az").mean() == pytest.approx(-9.6, abs=0.1)  # gravity, at rest


@needs_logs
def test_a_temperature_topic_beside_sensor_combined():
    rec = load_record(SMALL, topic="sensor_combined", temperature_topic="sensor_accel:2",
                      gaps="segments")
    accel = _pyulog(SMALL, "sensor_accel", 2)
    expected = np.interp(rec.time, accel["timestamp_sample"] / 1e6,
                         accel["temperature"].astype(float))
    np.testing.assert_array_equal(rec.column("temperature"), expected)
    assert rec.metadata["temperature topic"] == "sensor_accel:2"
    assert rec.notes[1] == ("column temperature (degC) from topic sensor_accel:2 (6 messages), "
                            "linearly interpolated onto the IMU samples' times; 275 IMU "
                            "sample(s) outside its span take its first or last value")


@needs_logs
def test_a_topic_of_another_kind_or_missing():
    listing = ", ".join(t.describe() for t in imu_topics(SMALL))
    assert _message(lambda: load_record(SMALL, topic="sensor_baro:0")) == (
        f"{SMALL}: topic 'sensor_baro:0' holds sensor_baro messages, not IMU data; IMU topics "
        f"(choose with topic=): {listing}")
    assert _message(lambda: load_record(SMALL, topic="sensor_combine")) == (
        f"{SMALL}: no topic 'sensor_combine' (did you mean 'sensor_combined'?); IMU topics "
        f"(choose with topic=): {listing}")


@needs_logs
def test_a_log_cut_short_reads_up_to_the_cut(tmp_path):
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(SAMPLE.read_bytes()[:2_000_000])
    rec = load_record(cut, gaps="segments")
    assert 0 < rec.n_samples < 17070
    np.testing.assert_array_equal(rec.column("gx"),
                                  _pyulog(SAMPLE, "sensor_combined")["gyro_rad[0]"][
                                      :rec.n_samples])


def test_a_truncated_or_foreign_file(tmp_path):
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(b"ULog\x01\x12")
    assert _message(lambda: load_record(cut)) == (
        f"{cut}: not a readable PX4 ULog file (Invalid file format (Header too short))")
    text = tmp_path / "text.ulg"
    text.write_text("time,gx\n0,1\n" * 10)
    assert _message(lambda: load_record(text)) == (
        f"{text}: not a readable PX4 ULog file (Invalid file format (Failed to parse header))")


def test_without_the_px4_extra(tmp_path, monkeypatch):
    path = tmp_path / "flight.ulg"
    path.write_bytes(b"ULog" + bytes(20))
    monkeypatch.setitem(sys.modules, "pyulog", None)  # import fails
    assert _message(lambda: load_record(path)) == (
        f"{path}: reading PX4 ULog files needs the 'px4' extra: pip install 'fosmodel[px4]'")


@needs_logs
@pytest.mark.slow
def test_the_command_line_on_a_log(tmp_path, capsys):
    out = tmp_path / "allan"
    argv = ["allan", str(SAMPLE), "--topic", "sensor_combined", "--columns", ",".join(COLUMNS),
            "--out", str(out)]
    assert cli.main(argv) == 2  # the log's gaps, told as for any record
    assert "a gap of 0.036 s" in capsys.readouterr().err
    assert cli.main([*argv, "--fill"]) == 2  # a flight: not the static record Allan needs
    assert "the record is not static" in capsys.readouterr().err
    assert cli.main([*argv, "--fill", "--static-only"]) == 0
    err = capsys.readouterr().err
    assert "fosmodel: gx: gyro in rad/s (units from the file)" in err
    assert (out / "imu.yaml").is_file()
    model = tmp_path / "m.json"
    assert cli.main(["fit", str(SMALL), "--column", "gx", "--out", str(model)]) == 2
    assert capsys.readouterr().err.startswith(
        f"fosmodel: error: {SMALL}: 10 IMU topics, choose one with --topic: sensor_accel:0 ")


@needs_logs
@pytest.mark.parametrize("settings, least", [([], "199.996 s"),  # 30 % left for 60 s of windows
                                             (["--split", "20%,20%", "--horizon", "5"], "100 s")])
def test_a_log_too_short_for_the_workflow_is_told_its_least_length_at_once(settings, least,
                                                                          tmp_path, capsys):
    """One message with the least length these settings take and what to change, before any
    work: not one more minimum per try."""
    out = tmp_path / "never"
    assert cli.main(["imu", str(SAMPLE), "--fill", "--static-only", *settings, "--out",
                     str(out)]) == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert re.match(r"fosmodel: error: the record has \d+ samples \([\d.]+ s at 250 Hz\), too "
                    f"short for these settings, which need at least {least}: the study needs "
                    f"{least} \\(", error), error
    assert "; the loop needs " in error and error.endswith(
        "shorten --split (the loop's: --loop-split) or --horizon, or give a longer record")
    assert not out.exists()
