"""A genuine rclpy (Jazzy's wheels, Fast DDS) drives ``omnibot ros2`` with Twist, then TwistStamped, on
one ``cmd_vel``, beside a publisher of a type the bridge cannot take, in a private network namespace.
How far the robot went is the simulator's truth, read from the bridge's ``--log`` with rosbags."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path
from typing import Any

import pytest

from tests.logs.test_recorder import read_all
from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.rclpy_scripts import beside_bridge

DRIVE = r"""
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import String

node = Node("two_teleops")
odom = []
node.create_subscription(Odometry, "odom", lambda m: odom.append(m), 10)
joints = []  # (stamp, positions): to find in the log
stamp = lambda m: m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec
node.create_subscription(JointState, "joint_states", lambda m: joints.append((stamp(m), list(m.position))), 10)
plain = node.create_publisher(Twist, "cmd_vel", 10)  # teleop_twist_joy's and Jazzy Nav2's default

def other_node(name):  # Fast DDS takes one type per topic name in a participant: one context each
    context = rclpy.Context()
    context.init()
    return Node(name, context=context)

stamped = other_node("nav2_stand_in").create_publisher(TwistStamped, "cmd_vel", 10)
wrong = other_node("wrong_type").create_publisher(String, "cmd_vel", 10)  # the bridge cannot drive on it

def send_plain():
    msg = Twist()
    msg.linear.x = 0.2
    plain.publish(msg)

def send_stamped():
    msg = TwistStamped()
    msg.header.stamp = node.get_clock().now().to_msg()
    msg.header.frame_id = "base_link"
    msg.twist.linear.y = 0.2
    stamped.publish(msg)

def position():
    p = odom[-1].pose.pose.position
    return p.x, p.y

def settled():
    return len(odom) > 10 and all(abs(m.twist.twist.linear.x) + abs(m.twist.twist.linear.y) < 0.01 for m in odom[-10:])

spin_until(lambda: odom and plain.get_subscription_count() and stamped.get_subscription_count(), 90)
spin_until(lambda: False, 1.0, lambda: wrong.publish(String(data="forward")))
x0, y0 = position()
spin_until(lambda: position()[0] - x0 > 0.3, 20, send_plain)
spin_until(settled, 20)
x1, y1 = position()
spin_until(lambda: position()[1] - y1 > 0.3, 20, send_stamped)
spin_until(settled, 20)
x2, y2 = position()
bridge.terminate()
out, _ = bridge.communicate(timeout=30)
print(json.dumps({"odom": [[x0, y0], [x1, y1], [x2, y2]], "joints": joints, "bridge": out}))
node.destroy_node()
rclpy.shutdown()
"""


def test_the_log_holds_the_messages_published_live(drive: dict[str, Any]) -> None:
    """Each joint_states rclpy took is in the bridge's ``--log``, stamp and values alike (the bridge
    stamps as its command's log does)."""
    _, messages = read_all(drive["log"])
    logged: dict[int, list[float]] = {}
    for m in messages["/joint_states"]:
        js: Any = m
        logged[js.header.stamp.sec * 1_000_000_000 + js.header.stamp.nanosec] = list(js.position)
    live = drive["joints"]
    assert len(live) > 50
    assert all(logged.get(ns) == positions for ns, positions in live), "a live message not in the log"


def truth(path: Path) -> list[tuple[float, float, float]]:
    """The simulator's poses in the bridge's log (x, y, heading)."""
    _, messages = read_all(path)
    poses = []
    odometry: list[Any] = messages["/omnibot/truth"]  # nav_msgs/Odometry, of rosbags' making
    for m in odometry:
        q = m.pose.pose.orientation
        poses.append((m.pose.pose.position.x, m.pose.pose.position.y, 2 * math.atan2(q.z, q.w)))
    return poses


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The run: what the rclpy node saw, the bridge's output and its log."""
    if importlib.util.find_spec("rclpy") is None:
        pytest.skip("rclpy is not installed (the test-only extra: pip install 'omnibot[ros2-test]')")
    log = tmp_path_factory.mktemp("cmd_vel") / "bridge.mcap"
    script = beside_bridge(["--port", "sim://omni4", "--duration", "150", "--log", str(log)], DRIVE)
    result: dict[str, Any] = json.loads(run_in_namespace(script, timeout=300).stdout.strip().splitlines()[-1])
    result["log"] = log
    return result


def test_twist_and_twist_stamped_publishers_both_drive_the_robot(drive: dict[str, Any]) -> None:
    """0.3 m ahead on Twist, then 0.3 m to the left on TwistStamped, each as far as the odometry
    says; the simulator's truth, in the robot's starting frame, agrees within 5 cm. The String
    publisher is told of in one line, once."""
    result, log = drive, drive["log"]
    lines = [line for line in result["bridge"].splitlines() if "cmd_vel: a publisher of" in line]
    assert lines == [
        "ros2: cmd_vel: a publisher of std_msgs/msg/String ignored: omnibot drives on "
        "geometry_msgs/msg/Twist or geometry_msgs/msg/TwistStamped"
    ], result["bridge"]
    poses = truth(log)
    x0, y0, heading = poses[0]

    def moved(pose: tuple[float, float, float]) -> tuple[float, float]:
        dx, dy = pose[0] - x0, pose[1] - y0
        c, s = math.cos(heading), math.sin(heading)
        return c * dx + s * dy, -s * dx + c * dy

    turn = next(i for i, p in enumerate(poses) if moved(p)[1] > 0.05)  # where the sideways drive began
    ahead, aside = moved(poses[turn]), moved(poses[-1])
    (ox0, oy0), (ox1, oy1), (ox2, oy2) = result["odom"]
    print(f"truth: {ahead[0]:.3f} m ahead on Twist, then {aside[1]:.3f} m aside on TwistStamped")
    assert ox1 - ox0 > 0.3 and oy2 - oy1 > 0.3, result["odom"]  # the odometry saw both drives
    assert abs(ox2 - ox1) < 0.05, result["odom"]
    assert ahead[0] == pytest.approx(ox1 - ox0, abs=0.05)
    assert aside[1] == pytest.approx(oy2 - oy0, abs=0.05)
    assert abs(aside[0] - ahead[0]) < 0.05  # the sideways drive went sideways
