"""The rclpy backend's pieces that need no node: the raw reader's queue, the graph's publications,
rclpy's classes and QoS (rclpy is the test-only extra; without it these skip)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

pytest.importorskip(
    "rclpy", reason="rclpy is not installed (the test-only extra: pip install 'omnibot[ros2-test]')"
)

from omnibot.logs import schemas
from omnibot.ros2.backend import LATCHED, SENSOR_DATA
from omnibot.ros2.rclpy_backend import message_class, qos_profile
from omnibot.ros2.rclpy_endpoints import GRAPH_PERIOD, GraphPublications, RclpyReader
from omnibot.ros2.types import from_dds

TWIST = "geometry_msgs/msg/Twist"


def twist_cdr(vx: float) -> bytes:
    def vector(x: float) -> Any:
        return schemas.new("geometry_msgs/msg/Vector3", x=x, y=0.0, z=0.0)

    return schemas.serialize(schemas.new(TWIST, linear=vector(vx), angular=vector(0.0)), TWIST)


def test_the_raw_reader_hands_over_cyclonedds_samples_oldest_first() -> None:
    reader = RclpyReader(TWIST, depth=10)
    for vx in (0.1, 0.2, 0.3):
        reader(twist_cdr(vx))
    first = reader.take(N=2)
    assert [from_dds(s, TWIST).linear.x for s in first] == [0.1, 0.2]
    assert all(hasattr(s, "__idl_typename__") for s in first)
    assert [from_dds(s, TWIST).linear.x for s in reader.take(N=64)] == [0.3]
    assert reader.take(N=64) == []


def test_the_raw_reader_keeps_the_newest_when_full() -> None:
    reader = RclpyReader(TWIST, depth=1)
    for k in range(100):
        reader(twist_cdr(float(k)))
    taken = reader.take(N=1000)
    assert len(taken) == 64 and from_dds(taken[-1], TWIST).linear.x == 99.0


class Graph:
    def __init__(self) -> None:
        self.publishers: dict[str, list[Any]] = {}
        self.reads = 0

    def get_topic_names_and_types(self) -> list[tuple[str, list[str]]]:
        self.reads += 1
        return [(t, []) for t in self.publishers]

    def get_publishers_info_by_topic(self, topic: str) -> list[Any]:
        return self.publishers[topic]


def info(typename: str, gid: int) -> Any:
    return SimpleNamespace(topic_type=typename, endpoint_gid=[gid] * 16)


def test_publications_name_each_publisher_once_as_dcps_publication_does() -> None:
    graph, now = Graph(), [0.0]
    pubs = GraphPublications(graph, clock=lambda: now[0])
    graph.publishers["/cmd_vel"] = [info(TWIST, 1)]
    assert [(p.topic_name, p.type_name) for p in pubs.take(N=64)] == [
        ("rt/cmd_vel", "geometry_msgs::msg::dds_::Twist_")
    ]
    graph.publishers["/cmd_vel"].append(info("geometry_msgs/msg/TwistStamped", 2))
    assert pubs.take(N=64) == []  # not read again within the period
    now[0] += GRAPH_PERIOD
    assert [p.type_name for p in pubs.take(N=64)] == ["geometry_msgs::msg::dds_::TwistStamped_"]
    now[0] += GRAPH_PERIOD
    assert pubs.take(N=64) == [] and graph.reads == 3


def test_classes_and_qos() -> None:
    assert message_class(TWIST).__name__ == "Twist"
    assert message_class("no_such_msgs/msg/Thing") is None
    latched, sensor = qos_profile(LATCHED), qos_profile(SENSOR_DATA)
    assert (latched.depth, latched.durability.name, latched.reliability.name) == (
        1,
        "TRANSIENT_LOCAL",
        "RELIABLE",
    )
    assert (sensor.depth, sensor.durability.name, sensor.reliability.name) == (5, "VOLATILE", "BEST_EFFORT")
