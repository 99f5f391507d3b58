"""rmw's naming, QoS and environment, without starting DDS; a writer's CDR bytes on the wire, in a private
network namespace."""

from __future__ import annotations

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.errors import ConfigError
from omnibot.logs import type_hash
from omnibot.ros2 import dds, netns
from tests.ros2.netns_helper import run_in_namespace


def test_topic_names_follow_rmw() -> None:
    assert dds.topic_name("odom") == "rt/odom"
    assert dds.topic_name("odom", "/robot1/") == "rt/robot1/odom"
    assert dds.topic_name("/tf", "robot1") == "rt/tf"


def test_domain_id() -> None:
    assert dds.domain_id({}) == 0
    assert dds.domain_id({"ROS_DOMAIN_ID": "42"}) == 42
    for bad in ("-1", "x", "233"):
        with pytest.raises(ConfigError, match="ROS_DOMAIN_ID"):
            dds.domain_id({"ROS_DOMAIN_ID": bad})


def test_discovery_is_localhost_under_pytest_whatever_the_environment() -> None:
    assert dds.discovery_range({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}) == "LOCALHOST"


def test_discovery_range_as_rmw_reads_it(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(netns, "under_pytest", lambda: False)
    assert dds.discovery_range({}) == "SUBNET"
    assert dds.discovery_range({"ROS_LOCALHOST_ONLY": "1"}) == "LOCALHOST"
    assert dds.discovery_range({"ROS_AUTOMATIC_DISCOVERY_RANGE": "off"}) == "OFF"
    assert (
        dds.discovery_range({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET", "ROS_LOCALHOST_ONLY": "1"})
        == "SUBNET"
    )
    with pytest.raises(ConfigError, match="ROS_AUTOMATIC_DISCOVERY_RANGE"):
        dds.discovery_range({"ROS_AUTOMATIC_DISCOVERY_RANGE": "everywhere"})


def test_localhost_configuration_turns_multicast_off() -> None:
    xml = dds.config_xml(7, "LOCALHOST")
    assert '<Domain Id="7">' in xml
    assert "<AllowMulticast>false</AllowMulticast>" in xml
    assert '<NetworkInterface address="127.0.0.1"/>' in xml
    assert '<Peer address="127.0.0.1"/>' in xml


def test_qos_carries_the_type_hash_and_rclpy_profiles() -> None:
    qos = dds.qos(dds.SENSOR_DATA, "sensor_msgs/msg/Imu")
    text = repr(qos)
    assert f"typehash={type_hash('sensor_msgs/msg/Imu')};" in text
    assert "BestEffort" in text and "KeepLast(depth=5)" in text
    latched = repr(dds.qos(dds.LATCHED, "std_msgs/msg/String"))
    assert "TransientLocal" in latched and "Reliable" in latched and "KeepLast(depth=1)" in latched
    default = repr(dds.qos(dds.DEFAULT, "nav_msgs/msg/Odometry"))
    assert "Volatile" in default and "Reliable" in default and "KeepLast(depth=10)" in default


def test_static_peers_are_read_as_rmw_reads_them_and_a_bad_one_is_refused() -> None:
    assert dds.static_peers({}) == ()
    env = {"ROS_STATIC_PEERS": " 192.0.2.2; robot-2.local;;"}
    assert dds.static_peers(env) == ("192.0.2.2", "robot-2.local")
    for bad in ('192.0.2.2"/><Peer address="x', "a b"):
        with pytest.raises(ConfigError, match="ROS_STATIC_PEERS holds addresses or host names"):
            dds.static_peers({"ROS_STATIC_PEERS": bad})


def test_static_peers_go_into_the_configuration_as_rmw_cyclonedds_puts_them() -> None:
    """SUBNET: multicast stays, the peers are added with automatic participant indexes (the ports a
    peer's unicast discovery tries); LOCALHOST: after 127.0.0.1; OFF: ignored."""
    peers = ("192.0.2.2", "192.0.2.3")
    subnet = dds.config_xml(0, "SUBNET", peers)
    assert '<Peers><Peer address="192.0.2.2"/><Peer address="192.0.2.3"/></Peers>' in subnet
    assert "<ParticipantIndex>auto</ParticipantIndex>" in subnet and "AllowMulticast" not in subnet
    assert "<Peers>" not in dds.config_xml(0, "SUBNET")
    local = dds.config_xml(0, "LOCALHOST", peers)
    assert '<Peers><Peer address="127.0.0.1"/><Peer address="192.0.2.2"/><Peer address="192.0.2.3"/>' in local
    assert "<Peer " not in dds.config_xml(0, "OFF", peers)


CDR = r"""
import json, time
from omnibot.motion import Pose2D
from omnibot.logs import header, schemas
from omnibot.logs.rosmsg import odometry
from omnibot.ros2.dds import Node
from omnibot.ros2.types import from_dds

ODOM, STRING = "nav_msgs/msg/Odometry", "std_msgs/msg/String"
bridge, peer = Node("r1"), Node()
odom, text = bridge.writer("odom", ODOM), bridge.writer("/note", STRING)
readers = peer.reader("/r1/odom", ODOM), peer.reader("/note", STRING)
end = time.monotonic() + 30
while not all(r.get_matched_publications() for r in readers):
    assert time.monotonic() < end, "never matched"
    time.sleep(0.02)
message = odometry(1_700_000_000_000_000_001, "odom", "base_link", Pose2D(1.5, -0.25, 0.7), (0.3, -0.1, 0.4))
message.pose.covariance[0] = 0.125
odom.write_cdr(schemas.serialize(message, ODOM))
text.write_cdr(schemas.serialize(schemas.new(STRING, data="abcde"), STRING))  # 4 + 4 + 6 bytes: padded
got = {}
while len(got) < 2 and time.monotonic() < end:
    for reader, typename in zip(readers, (ODOM, STRING)):
        for sample in reader.take(N=10):
            got[typename] = from_dds(sample, typename)
    time.sleep(0.01)
odom_in, text_in = got[ODOM], got[STRING]
print(json.dumps({
    "stamp": [odom_in.header.stamp.sec, odom_in.header.stamp.nanosec],
    "frames": [odom_in.header.frame_id, odom_in.child_frame_id],
    "x": odom_in.pose.pose.position.x, "cov0": float(odom_in.pose.covariance[0]),
    "vy": odom_in.twist.twist.linear.y, "text": text_in.data,
}))
bridge.close(); peer.close()
"""


def test_a_writer_sends_cdr_bytes_as_a_reader_takes_them() -> None:
    """``write_cdr`` of rosbags' bytes: a cyclonedds reader takes the message with every field (a
    string whose CDR is not a multiple of 4 bytes long too)."""
    import json

    got = json.loads(run_in_namespace(CDR).stdout.strip().splitlines()[-1])
    assert got == {
        "stamp": [1_700_000_000, 1],
        "frames": ["odom", "base_link"],
        "x": 1.5,
        "cov0": 0.125,
        "vy": -0.1,
        "text": "abcde",
    }
