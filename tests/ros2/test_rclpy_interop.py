"""A genuine rclpy (Jazzy wheels, Fast DDS) drives and watches ``omnibot ros2``, in a private network
namespace. The wheels are the test-only extra ``ros2-test``; without them the test skips."""

from __future__ import annotations

import importlib.util
import json

import pytest

from omnibot.logs import type_hash
from omnibot.robot import load_robot
from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.rclpy_scripts import beside_bridge

INTEROP = r"""
from rclpy.qos import qos_profile_sensor_data
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState, Imu

node = Node("teleop_twist_joy_stand_in")
got = {"odom": [], "joint_states": [], "imu": []}
node.create_subscription(Odometry, "odom", lambda m: got["odom"].append((time.monotonic(), m)), 10)
node.create_subscription(JointState, "joint_states", lambda m: got["joint_states"].append(m), 10)
node.create_subscription(Imu, "imu", lambda m: got["imu"].append(m), qos_profile_sensor_data)
pub = node.create_publisher(TwistStamped, "cmd_vel", 10)

def publish_sideways():
    msg = TwistStamped()
    msg.header.stamp = node.get_clock().now().to_msg()
    msg.header.frame_id = "base_link"
    msg.twist.linear.y = 0.2
    pub.publish(msg)

def last_odom():
    return got["odom"][-1][1] if got["odom"] else None

deadline = time.monotonic() + 30  # the bridge may take several seconds to start on a loaded machine
while not got["odom"] and time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.05)
hashes = {}
for topic in ("/odom", "/cmd_vel", "/joint_states"):
    infos = node.get_publishers_info_by_topic(topic) or node.get_subscriptions_info_by_topic(topic)
    hashes[topic] = [str(i.topic_type_hash) for i in infos]
y0 = last_odom().pose.pose.position.y if got["odom"] else None
moved = lambda: got["odom"] and last_odom().pose.pose.position.y - y0 > 0.3
spin_until(moved, 20.0, publish_sideways)  # 0.2 m/s sideways: 1.5 s plus the start, if the bridge follows
y_moving = last_odom().pose.pose.position.y if got["odom"] else None
drive = [m.twist.twist.linear.y for _, m in got["odom"][-5:]]
vy_moving = sum(drive) / len(drive) if drive else None  # the speed it drives at, lately
# Stopped: the drive's timeout and deceleration end it; then the odometry must stay still.
settled_from = len(got["odom"])
def settled():
    recent = [m.twist.twist.linear.y for _, m in got["odom"][settled_from:]][-10:]
    return len(recent) == 10 and max(abs(v) for v in recent) < 0.02
spin_until(settled, 20.0)
still = [m.twist.twist.linear.y for _, m in got["odom"][settled_from:]][-10:]
mark = len(got["odom"])
spin_until(lambda: len(got["odom"]) >= mark + 10, 10.0)
still += [m.twist.twist.linear.y for _, m in got["odom"][mark:]]
last = last_odom()
bridge.terminate()
out, _ = bridge.communicate(timeout=20)
print(json.dumps({
    "odom": len(got["odom"]), "joint_states": len(got["joint_states"]), "imu": len(got["imu"]),
    "joints": list(got["joint_states"][-1].name) if got["joint_states"] else [],
    "y0": y0, "y_moving": y_moving, "vy_moving": vy_moving, "y_end": last.pose.pose.position.y if last else None,
    "still": still, "hashes": hashes, "bridge": out[-2000:],
}))
node.destroy_node()
rclpy.shutdown()
"""


@pytest.mark.skipif(
    importlib.util.find_spec("rclpy") is None,
    reason="rclpy is not installed (the test-only extra: pip install 'omnibot[ros2-test]')",
)
def test_rclpy_drives_and_watches_the_bridge() -> None:
    script = beside_bridge(["--port", "sim://omni4", "--duration", "90"], INTEROP)
    result = json.loads(run_in_namespace(script, timeout=180).stdout.strip().splitlines()[-1])
    print({k: v for k, v in result.items() if k not in ("bridge", "still")})
    assert result["odom"] > 20 and result["joint_states"] > 20 and result["imu"] > 20, result
    assert result["joints"] == [f"{w.name}_joint" for w in load_robot("omni4").wheels], result
    assert result["y_moving"] - result["y0"] > 0.3, result  # it went sideways, as asked
    assert 0.15 < result["vy_moving"] < 0.25, result  # at the asked 0.2 m/s
    assert len(result["still"]) >= 20 and max(abs(v) for v in result["still"]) < 0.02, result
    assert abs(result["y_end"] - result["y_moving"]) < 0.3, result  # the timeout, then braking
    assert result["hashes"]["/odom"] == [type_hash("nav_msgs/msg/Odometry")], result
    assert result["hashes"]["/joint_states"] == [type_hash("sensor_msgs/msg/JointState")], result
