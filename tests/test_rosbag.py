"""ROS 1 and ROS 2 bags (sqlite3 and MCAP storage), written here with rosbags' writers from
known arrays and read back through load_record: sample for sample, the temperature aligned,
the topic chosen, the loader's checks, and bad input in one exact line."""

import sys

import numpy as np
import pytest

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.io.loader import load_record
from fosmodel.io.topics import ImuTopic, TopicError, imu_topics, read_topic

pytest.importorskip("rosbags", reason="reading ROS bags needs the 'ros' extra")

STORAGES = {"ros1": ("imu.bag", "ROS 1 bag"), "sqlite3": ("imu", "ROS 2 bag"),
            "mcap": ("imu", "ROS 2 bag")}
COLUMNS = ["gx", "gy", "gz", "ax", "ay", "az"]
UNITS = {**dict.fromkeys(COLUMNS[:3], "rad/s"), **dict.fromkeys(COLUMNS[3:], "m/s^2")}
ZERO = "1700000000.123456789"  # the fixture's first stamp


def _seconds(stamps, origin):
    return (stamps - origin) / 1e9


@pytest.mark.parametrize("storage", STORAGES)
def test_a_bag_reads_back_sample_for_sample(imu_bag, storage):
    name, kind = STORAGES[storage]
    path, arrays = imu_bag(name, storage)
    written = arrays["/imu0"]
    rec = load_record(path)
    assert rec.names == COLUMNS and rec.n_samples == 400
    for column in COLUMNS:
        np.testing.assert_array_equal(rec.column(column), written[column])
    np.testing.assert_array_equal(rec.time, _seconds(written["stamp"], written["stamp"][0]))
    assert rec.rate == pytest.approx(200.0, rel=1e-12)
    assert rec.units == UNITS
    assert rec.metadata == {"format": kind, "topic": "/imu0", "message type":
                            "sensor_msgs/msg/Imu", "time zero": ZERO}
    assert rec.notes == [f"{kind}, topic /imu0 (sensor_msgs/msg/Imu, 400 messages): gx, gy, gz "
                         f"in rad/s, ax, ay, az in m/s^2; time from header.stamp, in seconds "
                         f"from the first message's ({ZERO} s)"]


@pytest.mark.parametrize(("storage", "suffix", "kind"),
                         [("sqlite3", ".db3", "ROS 2 bag file (sqlite3)"),
                          ("mcap", ".mcap", "MCAP file")])
def test_the_storage_file_inside_a_ros2_bag_reads_alone(imu_bag, storage, suffix, kind):
    path, arrays = imu_bag("imu", storage)
    rec = load_record(path / f"imu{suffix}")
    np.testing.assert_array_equal(rec.column("az"), arrays["/imu0"]["az"])
    assert rec.metadata["format"] == kind


@pytest.mark.parametrize("storage", STORAGES)
def test_the_temperature_topic_is_interpolated_onto_the_imu_times(imu_bag, storage):
    path, arrays = imu_bag(STORAGES[storage][0], storage, temperature={"/imu/temperature": 15})
    imu, temperature = arrays["/imu0"], arrays["/imu/temperature"]
    rec = load_record(path)
    origin = imu["stamp"][0]
    expected = np.interp(_seconds(imu["stamp"], origin),
                         _seconds(temperature["stamp"], origin), temperature["temperature"])
    np.testing.assert_array_equal(rec.column("temperature"), expected)
    # the IMU's sample 10 (50 ms) falls on the temperature's second reading (at 50 ms)
    assert rec.column("temperature")[10] == temperature["temperature"][1]
    assert rec.units["temperature"] == "degC"
    assert rec.metadata["temperature topic"] == "/imu/temperature"
    # the temperature spans -50 ms to 1.35 s, the IMU 0 to 1.995 s: 129 samples after its last
    assert rec.notes[1] == ("column temperature (degC) from topic /imu/temperature (15 messages), "
                            "linearly interpolated onto the IMU samples' times; 129 IMU "
                            "sample(s) outside its span take its first or last value")
    assert np.all(rec.column("temperature")[-129:] == temperature["temperature"][-1])


def test_several_temperature_topics_none_chosen_is_a_note_and_one_can_be_chosen(imu_bag):
    path, arrays = imu_bag("imu", "mcap", temperature={"/t_die": 25, "/t_board": 25})
    rec = load_record(path)
    assert "temperature" not in rec.names
    assert rec.notes[1] == ("2 temperature topics (/t_board, /t_die): none read; choose one to "
                            "add a temperature column")
    rec = load_record(path, temperature_topic="/t_board")
    assert rec.metadata["temperature topic"] == "/t_board"
    assert rec.column("temperature")[10] == arrays["/t_board"]["temperature"][1]


def test_the_topic_is_chosen_among_several(imu_bag):
    path, arrays = imu_bag("imu.bag", "ros1", imu={"/imu0": 300, "/imu1": 200})
    rec = load_record(path, topic="/imu1")
    assert rec.n_samples == 200 and rec.metadata["topic"] == "/imu1"
    np.testing.assert_array_equal(rec.column("gy"), arrays["/imu1"]["gy"])
    assert imu_topics(path) == [
        ImuTopic("/imu0", "sensor_msgs/msg/Imu", 300, pytest.approx(200.0, rel=1e-12)),
        ImuTopic("/imu1", "sensor_msgs/msg/Imu", 200, pytest.approx(200.0, rel=1e-12))]


def test_imu_topics_and_read_topic_for_library_users(imu_bag):
    path, arrays = imu_bag("imu", "sqlite3", imu={"/imu0": 101}, rate=50.0)
    topics = imu_topics(path)
    assert topics == [ImuTopic("/imu0", "sensor_msgs/msg/Imu", 101, pytest.approx(50.0))]
    assert topics[0].describe() == "/imu0 (sensor_msgs/msg/Imu, 101 messages, 50 Hz)"
    log = read_topic(path)
    assert list(log.columns) == ["time", *COLUMNS] and log.units == UNITS


def test_zero_stamps_give_way_to_the_times_the_bag_recorded(imu_bag):
    path, arrays = imu_bag("imu.bag", "ros1", zero_stamps=True)
    rec = load_record(path)
    log_time = arrays["/imu0"]["log_time"]
    np.testing.assert_array_equal(rec.time, _seconds(log_time, log_time[0]))
    assert "time from the times the bag recorded the messages (every header.stamp is zero)" in (
        rec.notes[0])


def test_a_vector_marked_not_measured_is_left_out(imu_bag):
    path, _ = imu_bag("imu", "mcap", unmeasured=("linear_acceleration",))
    rec = load_record(path)
    assert rec.names == ["gx", "gy", "gz"]
    assert rec.notes[1] == ("ax, ay, az left out: linear_acceleration_covariance[0] is -1 in "
                            "every message, which says the linear_acceleration is not measured")


def test_the_loaders_checks_apply_to_a_bag(imu_bag):
    path, arrays = imu_bag("imu", "sqlite3", gap_after=99)
    with pytest.raises(InputError) as err:
        load_record(path)
    assert str(err.value) == (f"{path}: column 'time', row 100: a gap of 0.025 s where the sample "
                              "interval is 0.005 s (1 gap(s) in the record); pass --fill to "
                              "interpolate across them or --segments to fit on the pieces")
    filled = load_record(path, gaps="fill", columns=["gx"])
    assert filled.names == ["gx"] and filled.n_samples == 404
    np.testing.assert_allclose(filled.column("gx")[:100], arrays["/imu0"]["gx"][:100], rtol=1e-9)
    pieces = load_record(path, gaps="segments")
    assert pieces.segments == [slice(0, 100), slice(100, 400)]
    scaled = load_record(path, gaps="fill", scale={"gx": 180 / np.pi})
    assert "gx" not in scaled.units and scaled.units["gy"] == "rad/s"  # its units changed
    with pytest.raises(InputError, match=r"--rate 100 Hz disagrees with the time column "
                                         r"\(200 Hz\)$"):
        load_record(path, gaps="fill", rate=100.0)
    with pytest.raises(InputError, match=r": no column 'gq'; columns: gx, gy, gz, ax, ay, az$"):
        load_record(path, columns=["gq"])


def _message(call):
    with pytest.raises(InputError) as err:
        call()
    assert "\n" not in str(err.value)
    return str(err.value)


def test_several_topics_none_chosen(imu_bag):
    path, _ = imu_bag("imu", "mcap", imu={"/imu0": 300, "/imu1": 200})
    with pytest.raises(TopicError) as err:
        load_record(path)
    assert str(err.value) == (f"{path}: 2 IMU topics, choose one with topic=: /imu0 "
                              "(sensor_msgs/msg/Imu, 300 messages), /imu1 (sensor_msgs/msg/Imu, "
                              "200 messages)")
    assert err.value.with_flag() == str(err.value).replace("topic=", "--topic")


def test_a_topic_the_bag_lacks(imu_bag):
    path, _ = imu_bag("imu.bag", "ros1")
    assert _message(lambda: load_record(path, topic="/imu1")) == (
        f"{path}: no topic '/imu1' (did you mean '/imu0'?); IMU topics (choose with topic=): "
        "/imu0 (sensor_msgs/msg/Imu, 400 messages)")


def test_a_topic_of_another_message_type(imu_bag):
    path, _ = imu_bag("imu", "sqlite3", temperature={"/temp": 5})
    assert _message(lambda: load_record(path, topic="/temp")) == (
        f"{path}: topic '/temp' holds sensor_msgs/msg/Temperature messages, not IMU data; IMU "
        "topics (choose with topic=): /imu0 (sensor_msgs/msg/Imu, 400 messages)")
    with pytest.raises(TopicError) as err:
        load_record(path, temperature_topic="/imu0")
    assert err.value.with_flag() == (
        f"{path}: topic '/imu0' holds sensor_msgs/msg/Imu messages, not temperature data; "
        "temperature topics (choose with --temperature-topic): /temp "
        "(sensor_msgs/msg/Temperature, 5 messages)")


def test_a_bag_without_imu_topics(imu_bag):
    path, _ = imu_bag("temp.bag", "ros1", imu={}, temperature={"/temp": 5})
    assert _message(lambda: load_record(path)) == (
        f"{path}: no IMU topic (sensor_msgs/msg/Imu); its topics: /temp "
        "(sensor_msgs/msg/Temperature)")


def test_a_truncated_bag(imu_bag, tmp_path):
    path, _ = imu_bag("imu.bag", "ros1")
    cut = tmp_path / "cut.bag"
    cut.write_bytes(path.read_bytes()[:20_000])
    assert _message(lambda: load_record(cut)) == (
        f"{cut}: not a readable ROS 1 bag (Bag index looks damaged: ('Header could not be read "
        "from file.',))")
    path, _ = imu_bag("imu2", "mcap")
    storage = path / "imu2.mcap"
    storage.write_bytes(storage.read_bytes()[:20_000])
    assert _message(lambda: load_record(path)) == (
        f"{path}: not a readable ROS 2 bag (File end magic is invalid.)")


def test_missing_and_empty_bags_and_a_topic_for_a_table(tmp_path):
    assert _message(lambda: load_record(tmp_path / "none.bag")) == (
        f"{tmp_path / 'none.bag'}: no such file")
    (tmp_path / "empty.mcap").write_bytes(b"")
    assert _message(lambda: load_record(tmp_path / "empty.mcap")) == (
        f"{tmp_path / 'empty.mcap'}: the file is empty")
    (tmp_path / "r.csv").write_text("gx\n1\n2\n")
    with pytest.raises(TopicError) as err:
        load_record(tmp_path / "r.csv", topic="/imu0")
    assert err.value.with_flag() == (
        f"{tmp_path / 'r.csv'}: not a ROS bag (.bag, a ROS 2 bag directory, .db3, .mcap) or a "
        "PX4 ULog file (.ulg), so no topic to choose; leave out --topic")


def test_without_the_ros_extra(imu_bag, monkeypatch):
    path, _ = imu_bag("imu.bag", "ros1")
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # import fails
    assert _message(lambda: load_record(path)) == (
        f"{path}: reading ROS bags needs the 'ros' extra: pip install 'fosmodel[ros]'")


@pytest.mark.slow
def test_the_command_line_on_a_bag(imu_bag, tmp_path, capsys):
    path, _ = imu_bag("imu", "mcap", imu={"/imu0": 4000, "/imu1": 100})
    model = tmp_path / "gx.json"
    assert cli.main(["fit", str(path), "--topic", "/imu0", "--column", "gx", "--max-lag", "2",
                     "--out", str(model)]) == 0
    assert model.is_file()
    out = tmp_path / "allan"
    assert cli.main(["allan", str(path), "--topic", "/imu0", "--columns", ",".join(COLUMNS),
                     "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "fosmodel: gx: gyro in rad/s (units from the file)" in err
    assert "fosmodel: az: accel in m/s^2 (units from the file)" in err
    assert (out / "imu.yaml").is_file()
    assert cli.main(["fit", str(path), "--column", "gx", "--out", str(model)]) == 2
    assert capsys.readouterr().err == (
        f"fosmodel: error: {path}: 2 IMU topics, choose one with --topic: /imu0 "
        "(sensor_msgs/msg/Imu, 4000 messages), /imu1 (sensor_msgs/msg/Imu, 100 messages)\n")
