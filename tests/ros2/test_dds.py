"""rmw's naming, QoS and environment, without starting DDS."""

from __future__ import annotations

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.errors import ConfigError
from omnibot.logs.schemas import type_hash
from omnibot.ros2 import dds, netns


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
