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

from omnibot.mapping import load_map, save_map
from omnibot.mapping.score import world_grid
from omnibot.sim import load_world
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
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid
rclpy.init()
node = Node("goal_sender")
pub = node.create_publisher(PoseStamped, "/goal_pose", 10)
initial = node.create_publisher(PoseWithCovarianceStamped, "/initialpose", 10)
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
for line in sys.stdin:  # "goal|initialpose x y yaw frame", from the watcher
    if line.strip() == "quit":
        break
    kind, x, y, yaw, frame = line.split()
    msg = PoseStamped() if kind == "goal" else PoseWithCovarianceStamped()
    msg.header.frame_id = frame
    pose = msg.pose if kind == "goal" else msg.pose.pose
    pose.position.x, pose.position.y = float(x), float(y)
    pose.orientation.z, pose.orientation.w = math.sin(float(yaw) / 2), math.cos(float(yaw) / 2)
    if kind == "goal":
        pub.publish(msg)
    else:  # 5 cm and 5 degrees: what the watcher says it knows of the pose
        msg.pose.covariance[0] = msg.pose.covariance[7] = 0.05**2
        msg.pose.covariance[35] = math.radians(5.0) ** 2
        initial.publish(msg)
    print("sent", flush=True)
time.sleep(0.5)
node.destroy_node()
rclpy.shutdown()
"""
"""The genuine rclpy node (Jazzy's or Kilted's interpreter): gets the map, then publishes each goal
the watcher writes on its stdin."""

START = r"""
import json, math, os, subprocess, sys, threading, time
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
bridge = subprocess.Popen([sys.executable, "-m", "omnibot", "ros2", "--ros-backend", BACKEND, *ARGS],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
lines = []
def pump():
    for line in bridge.stdout:
        lines.append(line.rstrip())
threading.Thread(target=pump, daemon=True).start()
# the peer's own wheels' bootstrap, and nothing of omnibot's paths
env = {k: v for k, v in os.environ.items() if k not in (*BOOTSTRAP, "PYTHONPATH")}
peer = subprocess.Popen([PYTHON, "-c", PEER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                        stderr=subprocess.STDOUT, text=True, env=env)

def stop_bridge():
    bridge.terminate()
    try:
        bridge.wait(timeout=60)
    except subprocess.TimeoutExpired:
        bridge.kill()
        bridge.wait()
    time.sleep(0.2)
"""
"""Runs in the private namespace first: ``omnibot ros2 --ros-backend BACKEND ARGS`` (its lines kept in
``lines``) and the rclpy ``peer`` (PEER in PYTHON) on pipes; ``stop_bridge()`` ends the bridge (SIGTERM:
its log is closed)."""

WATCH = (
    START
    + r"""
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

def goal(x, y, yaw, frame="map", kind="goal"):
    peer.stdin.write(f"{kind} {x} {y} {yaw} {frame}\n")
    peer.stdin.flush()
    return peer.stdout.readline().strip() == "sent"

# The first message after discovery, sent again (up to 4 times, 8 s apart) until the bridge says
# text: the peer may see the bridge's reader before that reader has matched the peer's writer, and a
# volatile sample written in between is dropped (DDS's rule, not the bridge's).
def first(text, *args, **kwargs):
    for _ in range(4):
        goal(*args, **kwargs)
        wait(lambda: said(text), 8)
        if said(text):
            return

got_map = json.loads(peer.stdout.readline() or "null")  # once the peer has the map and a match
wait(lambda: said("localising in"), 60)
SCENARIO
wait(lambda: said("goal_pose: arrived") or said("goal_pose: did not arrive") >= GOALS, 240)
wait(lambda: statuses and statuses[-1]["state"] not in ("leg", "settling"), 10)
try:
    peer.communicate("quit\n", timeout=30)
except subprocess.TimeoutExpired:
    peer.kill()
    peer.communicate()
stop_bridge()
dds.close()
print(json.dumps({"lines": lines[-60:], "rc": bridge.returncode, "status": statuses[-1] if statuses else None,
                  "map": got_map}))
"""
)
"""Runs in the private namespace: ``omnibot ros2 --map ARGS``, the rclpy peer (PEER) fed goals on its
stdin as the bridge's status lines come (SCENARIO, spliced in before the end, sends them), and the
diagnostics reader."""

GOALS = r"""
GOALS = 2
first("goal_pose in frame 'odom' refused", 2.0, 2.0, 0.0, "odom")
goal(3.6, 1.2, 0.0)  # the cabinet
wait(lambda: said("goal_pose refused"), 30)
goal(3.0, 2.6, 0.5)
wait(lambda: said("goal_pose received"), 30)
wait(lambda: False, 3.0)  # on its way
goal(*GOAL)
"""
"""The goal_pose scenario: two refusals, a goal pre-empted by GOAL."""

TRUTH = (4.0, 3.0, math.radians(150.0))
"""Where the robot really stands in the initialpose scenario (the localiser starts at the map's start)."""

PLACE = r"""
GOALS = 1
wait(lambda: False, 2.0)  # the localiser's first scans, at the wrong pose
first("initialpose in frame 'odom' refused", *TRUTH, "odom", kind="initialpose")
goal(*TRUTH, kind="initialpose")  # the simulator's truth
wait(lambda: said("localiser re-placed by initialpose"), 30)
wait(lambda: False, 2.0)  # its scans from there
goal(*GOAL)
"""
"""The initialpose scenario: one refusal, the localiser re-placed at the truth, then GOAL."""


@pytest.fixture(scope="module")
def room_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("map") / "room.yaml"
    save_map(world_grid(load_world("room"), 0.05, 0.3), path)
    return path


def run(backend: str, distro: str, args: list[str], scenario: str) -> dict[str, Any]:
    """``omnibot ros2 --ros-backend backend ARGS`` beside ``distro``'s rclpy peer running ``scenario``:
    what the watcher saw (the bridge's last lines, its exit status, the last goal status, the map)."""
    python = interpreter(distro)
    script = (
        f"ARGS = {json.dumps(args)}\nBACKEND = {backend!r}\nGOAL = {GOAL!r}\nTRUTH = {TRUTH!r}\n"
        f"PYTHON = {python!r}\nBOOTSTRAP = {list(BOOTSTRAP)!r}\nPEER = {PEER!r}\n"
        + WATCH.replace("SCENARIO\n", scenario)
    )
    result: dict[str, Any] = json.loads(run_in_namespace(script, timeout=580).stdout.strip().splitlines()[-1])
    print("\n".join(result["lines"]))
    return result


def assert_arrived(result: dict[str, Any], log: Path, name: str) -> None:
    """The bridge said it arrived at GOAL, its status says so, and the simulator's truth agrees."""
    out = "\n".join(result["lines"])
    assert result["rc"] in (0, 143), out  # SIGTERM: the log is closed
    assert any("goal_pose: arrived at (2.50, 1.80)" in line for line in result["lines"]), out
    status = result["status"]
    assert status is not None and status["state"] == "arrived" and status["outcome"] == "arrived", status
    assert int(status["level"]) == 0 and status["goal"] == "2.500,1.800,90.0"
    x, y, theta = truth(log)[-1]  # the simulator's, in the world's frame: the map's
    error = math.hypot(x - GOAL[0], y - GOAL[1])
    heading = abs(math.remainder(theta - GOAL[2], math.tau))
    print(f"{name}: the truth {100 * error:.1f} cm and {math.degrees(heading):.1f} degrees from the goal")
    assert error <= 0.05 and heading <= math.radians(5), (error, math.degrees(heading))


PAIRS = pytest.mark.parametrize(
    ("backend", "distro"),
    [pytest.param(b, d, id=f"{b}-{d}") for b, d in (("rclpy", "jazzy"), ("dds", "jazzy"), ("dds", "kilted"))],
)
"""The (backend, distribution) pairs the tests run: Kilted's peer beside the dds backend."""


@pytest.mark.timeout(600)
@PAIRS
def test_goal_pose_is_gone_to_in_the_map(backend: str, distro: str, room_map: Path, tmp_path: Path) -> None:
    log = tmp_path / "bridge.mcap"
    args = ["--world", "room", "--seed", "3", "--map", str(room_map), "--duration", "300", "--log", str(log)]
    result = run(backend, distro, args, GOALS)
    out = "\n".join(result["lines"])
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
    assert_arrived(result, log, f"{backend}-{distro}")


@pytest.mark.timeout(600)
@PAIRS
def test_initialpose_re_places_the_localiser_then_a_goal_is_reached(
    backend: str, distro: str, room_map: Path, tmp_path: Path
) -> None:
    """The robot stands at TRUTH, the localiser starts at the map's start (1, 1, 0): an initialpose in
    ``odom`` is refused (one line), one in ``map`` at the truth re-places the localiser, and the robot
    then arrives at GOAL by the simulator's truth. Without the re-placing it goes by a pose 3.6 m and 150
    degrees off, which the localiser does not recover from (a first try with 72 cm and 30 degrees did:
    the test then passed with the re-placing taken out, so the offset was made one it cannot cross)."""
    log = tmp_path / "bridge.mcap"
    x, y, theta = TRUTH
    port = f"sim://omni4?world=room&seed=3&pose={x},{y},{math.degrees(theta):g}"
    args = ["--port", port, "--map", str(room_map), "--initial-pose", "1,1,0", "--duration", "300"]
    result = run(backend, distro, [*args, "--log", str(log)], PLACE)
    out = "\n".join(result["lines"])
    refusals = [line for line in result["lines"] if "refused" in line]
    assert len(refusals) == 1, out
    assert (
        "initialpose in frame 'odom' refused: the localiser is placed in the map frame 'map'" in refusals[0]
    )
    assert any(
        "localiser re-placed by initialpose at (4.00, 3.00, 150 deg), spread 5 cm, 5 deg" in line
        for line in result["lines"]
    ), out
    start = truth(log)[0]
    assert math.hypot(start[0] - x, start[1] - y) < 0.01  # the robot did stand there
    assert_arrived(result, log, f"{backend}-{distro}")
