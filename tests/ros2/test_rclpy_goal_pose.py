"""A genuine rclpy (Jazzy's and Kilted's wheels, Fast DDS) sends Nav2's ``goal_pose`` to ``omnibot ros2
--map MAP.yaml`` on the simulated room, on both backends (Kilted's peer beside the dds one), in a private
network namespace.

The node gets the map (nav_msgs/OccupancyGrid, transient local, frame ``map``) and publishes
geometry_msgs/PoseStamped on ``/goal_pose``: a goal in ``odom`` and one inside the cabinet are each
refused with one line; a goal across the room is pre-empted 3 s later by another, and the robot,
localised by its scanner in the map, arrives there within 5 cm and 5 degrees by the simulator's truth
(read from the bridge's ``--log``). The outcome is in the bridge's status lines and in the ``omnibot:
goal`` diagnostic status (read with omnibot's DDS reader: diagnostic_msgs has no rclpy wheel here).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from omnibot.mapping.mapfile import load_map, save_map
from omnibot.mapping.score import world_grid
from omnibot.sim.world import load_world
from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.rclpy_distros import BOOTSTRAP, interpreter
from tests.ros2.test_rclpy_cmd_vel import truth

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

GOAL = (2.5, 1.8, math.pi / 2)

PEER = r"""
import json, math, sys, time
import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
rclpy.init()
node = Node("goal_sender")
pub = node.create_publisher(PoseStamped, "/goal_pose", 10)
latched = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
maps = []
node.create_subscription(OccupancyGrid, "/map", maps.append, latched)
end = time.monotonic() + 240
while time.monotonic() < end and not (maps and pub.get_subscription_count() > 0):
    rclpy.spin_once(node, timeout_sec=0.02)
m = maps[-1] if maps else None
print(json.dumps(None if m is None else {"frame": m.header.frame_id, "width": m.info.width,
                                         "resolution": m.info.resolution}), flush=True)
for line in sys.stdin:  # "x y yaw frame" per goal, from the watcher
    if line.strip() == "quit":
        break
    x, y, yaw, frame = line.split()
    msg = PoseStamped()
    msg.header.frame_id = frame
    msg.pose.position.x, msg.pose.position.y = float(x), float(y)
    msg.pose.orientation.z, msg.pose.orientation.w = math.sin(float(yaw) / 2), math.cos(float(yaw) / 2)
    pub.publish(msg)
    print("sent", flush=True)
time.sleep(0.5)
node.destroy_node()
rclpy.shutdown()
"""
"""The genuine rclpy node (Jazzy's or Kilted's interpreter): gets the map, then publishes each goal
the watcher writes on its stdin."""

WATCH = r"""
import json, os, subprocess, sys, threading, time
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
bridge = subprocess.Popen([sys.executable, "-m", "omnibot", "ros2", "--ros-backend", BACKEND, *ARGS],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
lines = []
def pump():
    for line in bridge.stdout:
        lines.append(line.rstrip())
threading.Thread(target=pump, daemon=True).start()
env = {k: v for k, v in os.environ.items() if k not in BOOTSTRAP}  # the peer's own wheels' bootstrap
peer = subprocess.Popen([PYTHON, "-c", PEER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                        stderr=subprocess.STDOUT, text=True, env=env)
# diagnostic_msgs has no rclpy wheel here: /diagnostics is read with omnibot's own DDS reader
from omnibot.ros2.dds import Node as DdsNode, Profile
from omnibot.ros2.types import from_dds
dds = DdsNode()
diagnostics = dds.reader("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", Profile())
statuses = []

def wait(done, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end and not done() and bridge.poll() is None:
        time.sleep(0.02)
        for sample in diagnostics.take(N=100):
            if hasattr(sample, "__idl_typename__"):
                for s in from_dds(sample, "diagnostic_msgs/msg/DiagnosticArray").status:
                    if s.name == "omnibot: goal":
                        statuses.append(dict({kv.key: kv.value for kv in s.values}, message=s.message, level=s.level))

def said(text):
    return sum(text in line for line in lines)

def goal(x, y, yaw, frame="map"):
    peer.stdin.write(f"{x} {y} {yaw} {frame}\n")
    peer.stdin.flush()
    return peer.stdout.readline().strip() == "sent"

got_map = json.loads(peer.stdout.readline() or "null")  # once the peer has the map and a match
wait(lambda: said("localising in"), 60)
goal(2.0, 2.0, 0.0, "odom")
wait(lambda: said("goal_pose in frame 'odom' refused"), 30)
goal(3.6, 1.2, 0.0)  # the cabinet
wait(lambda: said("goal_pose refused"), 30)
goal(3.0, 2.6, 0.5)
wait(lambda: said("goal_pose received"), 30)
wait(lambda: False, 3.0)  # on its way
goal(*GOAL)
wait(lambda: said("goal_pose: arrived") or said("goal_pose: did not arrive") >= 2, 240)
wait(lambda: statuses and statuses[-1]["state"] not in ("leg", "settling"), 10)
try:
    peer.communicate("quit\n", timeout=30)
except subprocess.TimeoutExpired:
    peer.kill()
    peer.communicate()
bridge.terminate()
try:
    bridge.wait(timeout=60)
except subprocess.TimeoutExpired:
    bridge.kill()
    bridge.wait()
time.sleep(0.2)
dds.close()
print(json.dumps({"lines": lines[-60:], "rc": bridge.returncode, "status": statuses[-1] if statuses else None,
                  "map": got_map}))
"""
"""Runs in the private namespace: ``omnibot ros2 --map ARGS``, the rclpy peer (PEER) fed goals on its
stdin as the bridge's status lines come, and the diagnostics reader."""


@pytest.fixture(scope="module")
def room_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("map") / "room.yaml"
    save_map(world_grid(load_world("room"), 0.05, 0.3), path)
    return path


@pytest.mark.timeout(600)
@pytest.mark.parametrize(
    ("backend", "distro"), [("rclpy", "jazzy"), ("dds", "jazzy"), ("dds", "kilted")], ids="-".join
)
def test_goal_pose_is_gone_to_in_the_map(backend: str, distro: str, room_map: Path, tmp_path: Path) -> None:
    python = interpreter(distro)
    log = tmp_path / "bridge.mcap"
    args = ["--world", "room", "--seed", "3", "--map", str(room_map), "--duration", "300", "--log", str(log)]
    script = (
        f"ARGS = {json.dumps(args)}\nBACKEND = {backend!r}\nGOAL = {GOAL!r}\nPYTHON = {python!r}\n"
        f"BOOTSTRAP = {list(BOOTSTRAP)!r}\nPEER = {PEER!r}\n" + WATCH
    )
    result: dict[str, Any] = json.loads(run_in_namespace(script, timeout=580).stdout.strip().splitlines()[-1])
    out = "\n".join(result["lines"])
    print(out)
    assert result["rc"] in (0, 143), out  # SIGTERM: the log is closed
    grid = load_map(room_map)
    assert result["map"] == {
        "frame": "map",
        "width": grid.shape[1],
        "resolution": pytest.approx(grid.resolution),
    }
    refusals = [line for line in result["lines"] if "refused" in line]
    assert len(refusals) == 2, out  # one line each
    assert "goal_pose in frame 'odom' refused: goals are taken in the map frame 'map'" in refusals[0]
    assert "goal_pose refused: goal (3.60, 1.20) is inside a wall or obstacle" in refusals[1]
    assert any("goal_pose replaced: going to (2.50, 1.80, 90 deg)" in line for line in result["lines"]), out
    assert any("did not arrive: pre-empted by a new goal" in line for line in result["lines"]), out
    assert any("goal_pose: arrived at (2.50, 1.80)" in line for line in result["lines"]), out
    status = result["status"]
    assert status is not None and status["state"] == "arrived" and status["outcome"] == "arrived", status
    assert int(status["level"]) == 0 and status["goal"] == "2.500,1.800,90.0"
    x, y, theta = truth(log)[-1]  # the simulator's, in the world's frame: the map's
    error = math.hypot(x - GOAL[0], y - GOAL[1])
    heading = abs(math.remainder(theta - GOAL[2], math.tau))
    print(
        f"{backend}-{distro}: the truth {100 * error:.1f} cm and {math.degrees(heading):.1f} degrees from the goal"
    )
    assert error <= 0.05 and heading <= math.radians(5), (error, math.degrees(heading))
