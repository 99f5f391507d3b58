"""A genuine rclpy node (teleop_twist_joy's cmd_vel, rviz2's subscriptions) for the interop tests.

Run by the interpreter of a ROS 2 distribution's wheels (Jazzy's in the project's venv, Kilted's in
``.cache/ros2-kilted``), in the test's private network namespace; it imports nothing of omnibot.
``argv[1]`` is a JSON plan: ``sonars`` (names), ``twist`` (vx, vy, w), ``drive`` and ``silence`` (s),
``least`` (messages).
It waits for ``odom``, for the bridge to match its ``cmd_vel`` and for the graph to show an endpoint
of the bridge's on every topic, reads the graph (type names, RIHS01 hashes, QoS of every endpoint),
publishes TwistStamped at 20 Hz for ``drive`` s, listens ``silence`` s more, and on until it has
``least`` messages of each topic (the bridge publishes fewer in a wall-clock second on a loaded
machine), and prints one JSON line: what it received (stamps in ns and the values) and what the graph
said.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable
from typing import Any

import rclpy
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import Imu, JointState, Range

WAIT = 60.0
"""s to wait for the bridge's first odom (discovery and the simulator's start: seconds on a loaded
machine), and at most for the ``least`` messages of each topic after the silence."""
BARE = "_CREATED_BY_BARE_DDS_APP_"
"""The node rclpy's graph names for an endpoint whose participant announced no node (yet)."""
UNKNOWN = "_NODE_NAME_UNKNOWN_"
"""... and for one of a participant whose announcement does not (yet) list that endpoint."""
NAMING = 3.0
"""s the graph is given to name the bridge's endpoints after it first lists them all."""
IDLE = 0.05
"""s a spin waits at most with nothing due: each message ends it sooner (an idle spin costs rclpy
0.3-0.6 ms of CPU, a wait set built anew: at 5 ms timeouts 5.5 % of a core, 1.2 % at 50 ms)."""
GRAPH_PERIOD = 0.1
"""s between two reads of rclpy's graph while waiting for the bridge: a read (two queries a topic)
takes 0.5 ms of CPU, half what a message's spin does; made at every message (200 a second) it cost
half as much again as the messages."""
MATCHED_BACK = 0.5
"""s between our writer matching the bridge's ``cmd_vel`` reader and the first message: discovery
runs both ways, and a volatile reader that matches a writer after its first samples starts at the
writer's next one (the bridge took 49 of 50 once, no cycle of its slower than 23 ms)."""


def ns(msg: Any) -> int:
    """A header's stamp in ns."""
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


def yaw(q: Any) -> float:
    """The yaw of a quaternion (a planar base's)."""
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def endpoints(node: Node, topics: list[str]) -> dict[str, list[dict[str, Any]]]:
    """Every endpoint rclpy's graph knows on ``topics``: kind, type, hash, reliability, durability."""
    found: dict[str, list[dict[str, Any]]] = {}
    for topic in topics:
        infos = [("publisher", i) for i in node.get_publishers_info_by_topic(topic)]
        infos += [("subscription", i) for i in node.get_subscriptions_info_by_topic(topic)]
        found[topic] = [
            {
                "kind": kind,
                "node": info.node_name,
                "type": info.topic_type,
                "hash": str(info.topic_type_hash),
                "reliability": info.qos_profile.reliability.name,
                "durability": info.qos_profile.durability.name,
            }
            for kind, info in infos
        ]
    return found


def main() -> None:
    """See the module docstring."""
    plan = json.loads(sys.argv[1])
    rclpy.init()
    node = Node("teleop_twist_joy_stand_in")
    got: dict[str, list[Any]] = {"odom": [], "imu": [], "joint_states": []}

    def on_odom(m: Any) -> None:
        got["odom"].append(
            {
                "ns": ns(m),
                "frames": [m.header.frame_id, m.child_frame_id],
                "pose": [m.pose.pose.position.x, m.pose.pose.position.y, yaw(m.pose.pose.orientation)],
                "twist": [m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.angular.z],
                "cov": [m.pose.covariance[0], m.pose.covariance[35], m.twist.covariance[0]],
            }
        )

    def on_imu(m: Any) -> None:
        got["imu"].append(
            {
                "ns": ns(m),
                "frame": m.header.frame_id,
                "rate": m.angular_velocity.z,
                "yaw": yaw(m.orientation),
                "accel_cov0": m.linear_acceleration_covariance[0],
            }
        )

    def on_joints(m: Any) -> None:
        got["joint_states"].append(
            {"ns": ns(m), "name": list(m.name), "position": list(m.position), "velocity": list(m.velocity)}
        )

    def on_range(key: str) -> Callable[[Any], None]:
        def take(m: Any) -> None:
            got[key].append({"ns": ns(m), "frame": m.header.frame_id, "range": m.range, "max": m.max_range})

        return take

    node.create_subscription(Odometry, "odom", on_odom, 10)
    node.create_subscription(Imu, "imu", on_imu, qos_profile_sensor_data)
    node.create_subscription(JointState, "joint_states", on_joints, 10)
    for sonar in plan["sonars"]:
        got[f"range/{sonar}"] = []
        node.create_subscription(Range, f"range/{sonar}", on_range(f"range/{sonar}"), qos_profile_sensor_data)
    publisher = node.create_publisher(TwistStamped, "cmd_vel", 10)

    topics = ["/odom", "/imu", "/joint_states", "/tf", "/tf_static", "/robot_description", "/cmd_vel"]
    topics += [f"/range/{s}" for s in plan["sonars"]]

    named_by: list[float] = []  # when the graph first had the bridge's endpoints
    graph_read = [-math.inf]  # when it was last read

    def discovered() -> bool:  # the bridge publishes, has matched our cmd_vel, and rclpy's graph has it
        if not got["odom"] or publisher.get_subscription_count() < 1:
            return False
        if time.monotonic() - graph_read[0] < GRAPH_PERIOD:
            return False
        graph_read[0] = time.monotonic()
        graph = endpoints(node, topics)
        if not all(any(e["node"] != node.get_name() for e in graph[t]) for t in topics):
            return False
        # an endpoint seen before its node's ros_discovery_info update is listed as a bare DDS app's:
        # give the graph NAMING s to name it (on a distribution that never does, the test says so)
        named_by.append(time.monotonic())
        bare = any(e["node"] in (BARE, UNKNOWN) for t in topics for e in graph[t])
        return not bare or named_by[-1] - named_by[0] >= NAMING

    end = time.monotonic() + WAIT
    while not discovered() and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    matched_back = time.monotonic() + MATCHED_BACK
    while time.monotonic() < matched_back:
        rclpy.spin_once(node, timeout_sec=0.05)
    graph = endpoints(node, topics)

    vx, vy, w = plan["twist"]
    start = time.monotonic()
    drive_end, end = start + plan["drive"], start + plan["drive"] + plan["silence"]
    next_publish, sent, last_sent = start, 0, None
    streams = ["odom", "imu", "joint_states"] + [f"range/{s}" for s in plan["sonars"]]
    hard_end = end + WAIT
    while time.monotonic() < end or (
        time.monotonic() < hard_end and min(len(got[k]) for k in streams) < plan.get("least", 0)
    ):
        now = time.monotonic()
        if now < drive_end and now >= next_publish:
            msg = TwistStamped()
            msg.header.stamp = node.get_clock().now().to_msg()
            msg.header.frame_id = "base_link"
            msg.twist.linear.x, msg.twist.linear.y, msg.twist.angular.z = float(vx), float(vy), float(w)
            publisher.publish(msg)
            sent += 1
            last_sent = ns(msg)
            next_publish += 0.05  # 20 Hz, as teleop_twist_joy
        due = next_publish - time.monotonic() if now < drive_end else IDLE  # a message ends it sooner
        rclpy.spin_once(node, timeout_sec=min(IDLE, max(due, 0.0)))
    print(json.dumps({"got": got, "graph": graph, "sent": sent, "last_sent": last_sent}), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
