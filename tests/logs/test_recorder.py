"""A recorded run read back by rosbags (a reader we did not write): every message decodes, and the
values are the ones sent and received."""

from __future__ import annotations

import math
import signal
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.data_stream import RecordBuilder
from rosbags.highlevel import AnyReader

from omnibot.client import Telemetry
from omnibot.logs import schemas, topics
from omnibot.logs.reader import LogFile
from omnibot.logs.recorder import Recorder
from omnibot.protocol import text
from omnibot.protocol.messages import Telemetry as TelMessage
from omnibot.signals import Terminated, terminate_cleanly
from tests.logs.conftest import RecordedRun


def read_all(path: Path) -> tuple[dict[str, str], dict[str, list[object]]]:
    """(topic -> type, topic -> decoded messages) through rosbags' AnyReader."""
    out: dict[str, list[object]] = {}
    with AnyReader([path]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        for connection, _, raw in reader.messages():
            out.setdefault(connection.topic, []).append(reader.deserialize(raw, connection.msgtype))
    return types, out


def test_every_message_decodes_with_rosbags(recorded: RecordedRun) -> None:
    types, messages = read_all(recorded.path)
    assert {topic: len(msgs) for topic, msgs in messages.items()} == recorded.counts
    assert types[topics.ODOM] == "nav_msgs/msg/Odometry"
    assert types[topics.TF] == "tf2_msgs/msg/TFMessage"
    assert types[topics.IMU] == "sensor_msgs/msg/Imu"
    assert types[topics.JOINT_STATES] == "sensor_msgs/msg/JointState"
    assert types[topics.CMD_VEL] == "geometry_msgs/msg/TwistStamped"
    assert types[topics.range_topic("front")] == "sensor_msgs/msg/Range"
    assert types[topics.ROBOT_DESCRIPTION] == "std_msgs/msg/String"
    assert types[topics.LINK] == schemas.LINK_BYTES
    assert types[topics.PROTOCOL] == schemas.PROTOCOL_LINE


def test_values_are_what_was_sent_and_received(recorded: RecordedRun) -> None:
    _, messages = read_all(recorded.path)
    cmd = messages[topics.CMD_VEL]
    assert len(cmd) == len(recorded.vels) > 100
    for m, vel in zip(cmd, recorded.vels, strict=True):
        tw = m.twist  # type: ignore[attr-defined]
        assert tw.linear.x == pytest.approx(vel.vx / 100)
        assert tw.linear.y == pytest.approx(vel.vy / 100)
        assert tw.angular.z == pytest.approx(math.radians(vel.w))
    tel_lines = [m.text for m in messages[topics.PROTOCOL] if m.keyword == "TEL"]  # type: ignore[attr-defined]
    assert len(tel_lines) == len(recorded.telemetry) > 100
    for line, tel in zip(tel_lines, recorded.telemetry, strict=True):
        assert text.parse_line(line.encode()) == tel.message
    joints = messages[topics.JOINT_STATES]
    assert len(joints) == len(recorded.telemetry)
    for js, tel in zip(joints, recorded.telemetry, strict=True):
        assert list(js.name) == ["m1_joint", "m2_joint", "m3_joint", "m4_joint"]  # type: ignore[attr-defined]
        assert tel.encoders is not None and tel.powers is not None
        assert [round(p * 440 / (2 * math.pi)) for p in js.position] == list(tel.encoders)  # type: ignore[attr-defined]
        assert list(js.effort) == [float(p) for p in tel.powers]  # type: ignore[attr-defined]
    imu = messages[topics.IMU]
    for m, tel in zip(imu, recorded.telemetry, strict=True):
        assert m.angular_velocity.z == pytest.approx(tel.gyro_rate)  # type: ignore[attr-defined]
        yaw = 2 * math.atan2(m.orientation.z, m.orientation.w)  # type: ignore[attr-defined]
        assert math.remainder(yaw - (tel.heading or 0.0), math.tau) == pytest.approx(0.0, abs=1e-12)
    truths = messages[topics.TRUTH]
    assert len(truths) == len(recorded.truth)
    for m, (x, y, theta) in zip(truths, recorded.truth, strict=True):
        pose = m.pose.pose  # type: ignore[attr-defined]
        assert (pose.position.x, pose.position.y) == (x, y)
        assert 2 * math.atan2(pose.orientation.z, pose.orientation.w) == pytest.approx(theta)
    assert math.hypot(*recorded.truth[-1][:2]) > 0.2  # the robot did move


def test_link_bytes_are_the_bytes_written(recorded: RecordedRun) -> None:
    _, messages = read_all(recorded.path)
    tx = b"".join(bytes(m.data) for m in messages[topics.LINK] if m.kind == "TX")  # type: ignore[attr-defined]
    assert tx == recorded.tx
    assert b"VEL," in tx


def test_robot_description_is_the_urdf(recorded: RecordedRun) -> None:
    from omnibot.robot import load_robot, to_urdf

    _, messages = read_all(recorded.path)
    assert messages[topics.ROBOT_DESCRIPTION][0].data == to_urdf(load_robot("omni4"))  # type: ignore[attr-defined]
    assert "k_l" in messages[topics.CALIBRATION][0].data  # type: ignore[attr-defined]


def test_rosbag2_metadata_and_profile(recorded: RecordedRun) -> None:
    import yaml
    from mcap.reader import make_reader

    with recorded.path.open("rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        summary = reader.get_summary()
    assert summary is not None
    chunks = summary.chunk_indexes
    assert chunks and {c.compression for c in chunks} == {"zstd"}
    info = yaml.safe_load(meta["rosbag2"]["serialized_metadata"])["rosbag2_bagfile_information"]
    assert info["storage_identifier"] == "mcap"
    assert info["message_count"] == sum(recorded.counts.values())
    listed = {t["topic_metadata"]["name"]: t["message_count"] for t in info["topics_with_message_count"]}
    assert listed == recorded.counts
    assert all(
        t["topic_metadata"]["type_description_hash"].startswith("RIHS01_")
        for t in info["topics_with_message_count"]
    )


def test_a_malformed_line_is_recorded_as_such(tmp_path: Path) -> None:
    from omnibot.protocol.messages import Malformed

    rec = Recorder(tmp_path / "m.mcap")
    rec.message(0.0, "event", Malformed(b"TEL,1,x", "not an integer"))
    rec.close()
    _, messages = read_all(tmp_path / "m.mcap")
    (line,) = messages[topics.PROTOCOL]
    assert line.keyword == "MALFORMED" and "TEL,1,x" in line.text  # type: ignore[attr-defined]


def test_telemetry_round_trips_through_the_protocol_line() -> None:
    tel = TelMessage(1234, (1, -2, 3, -4), (10, 20, 30, 40), None, 55, -9000, 7200, (0, 1), (42,))
    line = text.encode(tel).decode().strip()
    assert text.parse_line(line.encode()) == tel
    assert Telemetry.from_message(tel, 1.0).encoders == (10, 20, 30, 40)


def test_a_second_link_goes_on_from_the_last_message(tmp_path: Path) -> None:
    """calibrate opens a fresh simulated robot per floor, each clock starting at 0 again."""
    from omnibot.client import RobotClient, guarded
    from omnibot.logs.reader import LogFile
    from omnibot.robot import load_robot

    robot = load_robot("omni4")
    rec = Recorder(tmp_path / "two.mcap")
    for seed in (1, 2):
        client = RobotClient.open(f"sim://omni4?seed={seed}", robot)
        with guarded(client, robot=robot):
            rec.attach(client, robot)
            client.telemetry(0.01)
            client.sleep(0.5)
    rec.close()
    times = [m.ns for m in LogFile.open(tmp_path / "two.mcap").messages()]
    assert times == sorted(times) and (times[-1] - times[0]) / 1e9 > 0.9


STANDARD = {
    topics.ODOM,
    topics.TF,
    topics.IMU,
    topics.JOINT_STATES,
    topics.CMD_VEL,
    topics.ROBOT_DESCRIPTION,
    topics.CALIBRATION,
    "/range/front",
}
"""The topics a ROS 2 base publishes, as rosbag2 records them from a robot without a namespace."""


def test_every_channel_is_absolute_as_rosbag2_writes_it(recorded: RecordedRun) -> None:
    types, _ = read_all(recorded.path)
    assert set(types) >= STANDARD, sorted(types)
    assert all(topic.startswith("/") for topic in types), sorted(types)
    log = LogFile.open(recorded.path)
    log.read_all()  # the metadata comes on the way
    rosbag2 = log.metadata["rosbag2"]["serialized_metadata"]
    meta = yaml.safe_load(rosbag2)["rosbag2_bagfile_information"]  # what `ros2 bag info` reads
    named = {t["topic_metadata"]["name"] for t in meta["topics_with_message_count"]}
    assert named == set(types)


def test_odom_in_the_log_has_the_covariances_the_bridge_publishes(recorded: RecordedRun) -> None:
    from omnibot.logs.rosmsg import POSE_VARIANCE, TWIST_VARIANCE

    _, messages = read_all(recorded.path)
    odom: list[Any] = messages[topics.ODOM]
    assert odom
    for m in odom:
        assert list(np.diag(np.reshape(m.pose.covariance, (6, 6)))) == list(POSE_VARIANCE)
        assert list(np.diag(np.reshape(m.twist.covariance, (6, 6)))) == list(TWIST_VARIANCE)
    truth: list[Any] = messages[topics.TRUTH]
    assert not np.any(truth[0].pose.covariance)  # the simulator's truth: exact, no covariance


def test_writes_from_several_threads_make_a_whole_file(tmp_path: Path) -> None:
    """The link's thread, the runtime's and a localiser's write into one recorder: each record whole
    (an MCAP record is several writes; unguarded, rosbags found chunks it could not decompress)."""
    path = tmp_path / "threads.mcap"
    recorder = Recorder(path, chunk_size=4096, flush_period=0.001)
    start = threading.Barrier(4)

    def write(k: int) -> None:
        start.wait()
        for i in range(1500):
            message = schemas.new("std_msgs/msg/String", data=f"{k}:{i}," * (1 + i % 7))
            recorder.write(f"/thread{k}", "std_msgs/msg/String", message, 1_000_000 + i)

    threads = [threading.Thread(target=write, args=(k,)) for k in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    recorder.close()
    recorder.write("/thread0", "std_msgs/msg/String", schemas.new("std_msgs/msg/String", data="late"), 0)
    _, messages = read_all(path)
    assert {topic: len(msgs) for topic, msgs in messages.items()} == {f"/thread{k}": 1500 for k in range(4)}
    for k in range(4):
        assert [m.data for m in messages[f"/thread{k}"]] == [  # type: ignore[attr-defined]
            f"{k}:{i}," * (1 + i % 7) for i in range(1500)
        ]


@pytest.mark.parametrize("cut", range(1, 9))
def test_a_signal_mid_record_ends_the_run_after_the_record(
    cut: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SIGTERM's exception (or Ctrl-C's) raised between two of an MCAP record's writes: the record is
    finished first, the file closes whole (the two-host fleet test once read a chunk holding a record
    cut after its header: rosbags' "unpack requires a buffer of 22 bytes")."""
    writes = [0]
    write8 = RecordBuilder.write8

    def counting(self: RecordBuilder, value: int) -> None:
        writes[0] += 1
        if writes[0] == 40 + cut:  # inside some message's record, at each of its writes in turn
            signal.raise_signal(signal.SIGTERM)
        write8(self, value)

    monkeypatch.setattr(RecordBuilder, "write8", counting)
    path = tmp_path / "cut.mcap"
    recorder = Recorder(path)
    written = []
    with pytest.raises(Terminated), terminate_cleanly():
        try:
            for i in range(100):
                recorder.write(
                    "/chatter", "std_msgs/msg/String", schemas.new("std_msgs/msg/String", data=f"{i}"), i
                )
                written.append(f"{i}")
        finally:
            recorder.close()
    _, messages = read_all(path)
    assert 10 < len(written) < 100
    # the message the signal came in is in the file: its write ended, then the exception was raised
    assert [m.data for m in messages["/chatter"]] == [*written, f"{len(written)}"]  # type: ignore[attr-defined]


def test_range_events_are_recorded_as_the_sonars_ranges(tmp_path: Path) -> None:
    """A sonar pinged by ``SONAR`` reports in ``RANGE`` events (no TEL sonar field): each is a
    sensor_msgs/Range on the sonar's topic, its distance (m) as the event's."""
    from omnibot.client import RangeEvent, RobotClient, guarded
    from omnibot.robot import load_robot

    robot = load_robot("omni4")
    client = RobotClient.open("sim://omni4?seed=3&world=room", robot)
    rec = Recorder(tmp_path / "run.mcap")
    events: list[RangeEvent] = []
    with guarded(client, robot=robot):
        rec.attach(client, robot)
        client.on_range(events.append)
        for reply in client.submit_text("SONAR,1,60,0,500,0"):  # every reading inside 0..500 cm
            reply.result(1.0)
        client.sleep(1.0)
        rec.close()
    _, messages = read_all(tmp_path / "run.mcap")
    ranges = messages[topics.range_topic("front")]
    assert len(events) >= 10 and len(ranges) == len(events)
    for m, event in zip(ranges, events, strict=True):
        assert m.header.frame_id == "sonar_front"  # type: ignore[attr-defined]
        expected = math.inf if event.distance is None else event.distance
        assert m.range == pytest.approx(expected, rel=1e-6)  # type: ignore[attr-defined]
