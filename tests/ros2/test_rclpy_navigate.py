"""Nav2's ``navigate_to_pose`` action on ``omnibot ros2 --map MAP.yaml`` (the simulated room), on both
backends, in a private network namespace.

There is no nav2_msgs wheel for rclpy, so no genuine rclpy ActionClient can be made here (docs/ros2.md);
the goals, cancels and result requests come from a client written on cyclonedds to rmw_cyclonedds'
wire and the ROS 2 layout of the action's parts (checked against rclpy's serialization in
test_navigate.py). Beside it a genuine rclpy (Jazzy's and Kilted's wheels, Fast DDS) finds the action
in its graph (``rclpy.action.get_action_names_and_types``: ``/navigate_to_pose``,
``nav2_msgs/action/NavigateToPose``) and reads ``navigate_to_pose/_action/status``
(action_msgs/msg/GoalStatusArray, transient local) with its own action_msgs.

The client sends a goal across the room and cancels it 2 s later: the cancel answers ERROR_NONE naming
it, its result is CANCELED and the robot stands still (odom moves less than 1 cm from 0.5 s to 1.5 s
after the cancel). Then a goal across the room and 1 s after the bridge took it GOAL: the first is ABORTED (pre-empted, as
Nav2), feedback comes at 5 Hz (of the robot's clock) with a shrinking distance, ``get_result`` answers SUCCEEDED with
error code 0, and the simulator's truth (the bridge's ``--log``) is within 5 cm and 5 degrees of GOAL.
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path
from typing import Any

import pytest

from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.rclpy_distros import BOOTSTRAP, interpreter
from tests.ros2.test_rclpy_cmd_vel import truth
from tests.ros2.test_rclpy_goal_pose import GOAL, PAIRS, START, room_map

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

__all__ = ["room_map"]  # the fixture

PEER = r"""
import json, sys, time
import rclpy
from rclpy.node import Node
from rclpy.action import get_action_names_and_types
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy
from action_msgs.msg import GoalStatusArray
rclpy.init()
node = Node("status_watcher")
latched = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
seen = []
def status(msg):
    for s in msg.status_list:
        entry = [int(s.goal_info.goal_id.uuid[0]), int(s.status)]
        if entry not in seen:
            seen.append(entry)
node.create_subscription(GoalStatusArray, "/navigate_to_pose/_action/status", status, latched)
actions = []
end = time.monotonic() + 280
import select
while time.monotonic() < end:
    rclpy.spin_once(node, timeout_sec=0.05)
    if not actions:
        actions = [[n, list(t)] for n, t in get_action_names_and_types(node)]
    if select.select([sys.stdin], [], [], 0)[0]:
        break
for _ in range(20):
    rclpy.spin_once(node, timeout_sec=0.05)
print(json.dumps({"statuses": seen, "actions": actions}), flush=True)
node.destroy_node()
rclpy.shutdown()
"""
"""The genuine rclpy: the action in the graph, the status array (until a line on its stdin)."""

WATCH = (
    START
    + r"""

# the action client, on rmw_cyclonedds' wire
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from omnibot.logs import header, schemas
from omnibot.ros2.dds import DEFAULT, Node as DdsNode, qos, topic_name
from omnibot.ros2.types import NAVIGATE, dds_fields, dds_type, from_dds, register_service_types, request_type
register_service_types()
client = DdsNode(name="action_client")
participant = client.participant
ACTION = "navigate_to_pose/_action/"

def service(name, srv):
    ends = []
    for kind, suffix, part, make in (("rq", "Request", "_Request", DataWriter), ("rr", "Reply", "_Response", DataReader)):
        typename = srv + part
        topic = Topic(participant, topic_name(ACTION + name, "", kind, suffix), request_type(typename))
        ends.append(make(participant, topic, qos=qos(DEFAULT, typename, "clientid=1;")))
    return ends

send_goal = service("send_goal", NAVIGATE + "_SendGoal")
get_result = service("get_result", NAVIGATE + "_GetResult")
cancel_goal = service("cancel_goal", "action_msgs/srv/CancelGoal")
feedback = client.reader(ACTION + "feedback", NAVIGATE + "_FeedbackMessage")
odom = client.reader("odom", "nav_msgs/msg/Odometry")
seq = 0

def uuid(n):
    return schemas.new("unique_identifier_msgs/msg/UUID", uuid=__import__("numpy").array([n] * 16, dtype="uint8"))

def call(ends, typename, timeout, **fields):
    global seq
    seq += 1
    message = schemas.new(typename + "_Request", **fields)
    ends[0].write(request_type(typename + "_Request")(guid=0x5EED, seq=seq, **dds_fields(message, typename + "_Request")))
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for reply in ends[1].take(N=16):
            if getattr(reply, "seq", None) == seq and reply.guid == 0x5EED:
                return reply
        collect()
        time.sleep(0.02)
    return None

feedbacks = {}
poses = []
def collect():
    for f in feedback.take(N=64):
        if hasattr(f, "feedback"):
            feedbacks.setdefault(int(f.goal_id.uuid[0]), []).append(
                [time.monotonic(), f.feedback.distance_remaining, f.feedback.navigation_time.sec + 1e-9 * f.feedback.navigation_time.nanosec,
                 f.feedback.current_pose.header.frame_id, f.feedback.current_pose.pose.position.x,
                 f.feedback.current_pose.pose.position.y])
    for o in odom.take(N=256):
        if hasattr(o, "pose"):
            poses.append([time.monotonic(), o.pose.pose.position.x, o.pose.pose.position.y])

def wait(seconds, done=lambda: False):
    end = time.monotonic() + seconds
    while time.monotonic() < end and not done() and bridge.poll() is None:
        collect()
        time.sleep(0.02)

def said(text):
    return sum(text in line for line in lines)

def goal(n, x, y, yaw):
    msg = schemas.new("geometry_msgs/msg/PoseStamped", header=header(0, "map"), pose=schemas.new(
        "geometry_msgs/msg/Pose", position=schemas.new("geometry_msgs/msg/Point", x=x, y=y, z=0.0),
        orientation=schemas.new("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))))
    reply = call(send_goal, NAVIGATE + "_SendGoal", 30, goal_id=uuid(n),
                 goal=schemas.new(NAVIGATE + "_Goal", pose=msg, behavior_tree=""))
    return None if reply is None else bool(reply.accepted)

def result(n, timeout):
    reply = call(get_result, NAVIGATE + "_GetResult", timeout, goal_id=uuid(n))
    return None if reply is None else [int(reply.status), int(reply.result.error_code), reply.result.error_msg]

out = {}
wait(60, lambda: said("localising in"))
out["accepted"] = [goal(1, 3.0, 2.6, 0.5)]
wait(2.0)
info = schemas.new("action_msgs/msg/GoalInfo", goal_id=uuid(1), stamp=schemas.new("builtin_interfaces/msg/Time", sec=0, nanosec=0))
reply = call(cancel_goal, "action_msgs/srv/CancelGoal", 30, goal_info=info)
cancelled = time.monotonic()
out["cancel"] = None if reply is None else [int(reply.return_code), [int(g.goal_id.uuid[0]) for g in reply.goals_canceling]]
out["cancelled"] = result(1, 10)
wait(2.0)
out["still"] = [[p[1], p[2]] for p in poses if cancelled + 0.5 <= p[0] <= cancelled + 1.5]
out["accepted"].append(goal(2, 3.0, 2.6, 0.5))
wait(30, lambda: said("navigate_to_pose received") >= 2)
wait(1.0)  # on its way: 1.1-1.3 m to go, which the robot covers in under 3 s on a quiet machine
out["accepted"].append(goal(3, *GOAL))
out["pre-empted"] = result(2, 10)
out["arrived"] = result(3, 240)
out["feedback"] = {n: f for n, f in feedbacks.items()}
try:
    peer_out, _ = peer.communicate("quit\n", timeout=60)
    out["peer"] = json.loads(peer_out.strip().splitlines()[-1])
except Exception as exc:
    peer.kill()
    out["peer"] = {"error": repr(exc)}
stop_bridge()
client.close()
out["lines"] = lines[-60:]
out["rc"] = bridge.returncode
print(json.dumps(out))
"""
)
"""Runs in the private namespace: the bridge, the rclpy peer (PEER) and the action client."""

GOAL_IDS = {1: "cancelled", 2: "pre-empted", 3: "GOAL"}


@pytest.mark.timeout(600)
@PAIRS
def test_navigate_to_pose_goes_pre_empts_and_cancels(
    backend: str, distro: str, room_map: Path, tmp_path: Path
) -> None:
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
    assert result["rc"] in (0, 143), out
    assert result["accepted"] == [True, True, True], result
    assert result["cancel"] == [0, [1]], result  # ERROR_NONE, goal 1 canceling
    assert result["cancelled"] == [5, 0, "cancelled by navigate_to_pose's cancel_goal"], result  # CANCELED
    still = result["still"]
    assert len(still) > 10, result
    moved = max(math.hypot(x - still[0][0], y - still[0][1]) for x, y in still)
    assert moved < 0.01, moved  # the robot stopped
    assert result["pre-empted"] == [6, 0, "pre-empted by a new goal"], result  # ABORTED, as Nav2
    assert result["arrived"] == [4, 0, ""], (result, out)  # SUCCEEDED
    # feedback for the goal that arrived: ~5 Hz, in the map frame, the distance shrinking to ~0
    fb = result["feedback"]["3"]
    rate = (len(fb) - 1) / (fb[-1][2] - fb[0][2])  # on the robot's clock (navigation_time)
    wall = (len(fb) - 1) / (fb[-1][0] - fb[0][0])  # as received: the simulation lags on a loaded host
    print(
        f"{backend}-{distro}: feedback {len(fb)} messages at {rate:.1f} Hz of the robot's clock "
        f"({wall:.1f} Hz of the wall clock), distance {fb[0][1]:.2f} -> {fb[-1][1]:.2f} m"
    )
    assert 4.0 <= rate <= 5.5, rate
    assert all(f[3] == "map" for f in fb)
    for _, left, _, _, x, y in fb:  # along the plan: at least the straight way there, at most twice it
        straight = math.hypot(GOAL[0] - x, GOAL[1] - y)
        assert straight - 0.1 <= left <= 2 * straight + 0.1, (left, straight)
    assert fb[0][1] > fb[-1][1] and fb[-1][1] < 0.1, (fb[0], fb[-1])
    assert all(b[2] >= a[2] for a, b in itertools.pairwise(fb)), "navigation_time went back"
    # the genuine rclpy: the action in its graph, every goal's states in the status array
    peer = result["peer"]
    assert "error" not in peer, peer
    assert ["/navigate_to_pose", ["nav2_msgs/action/NavigateToPose"]] in peer["actions"], peer
    statuses = peer["statuses"]
    for goal, final in ((1, 5), (2, 6), (3, 4)):
        assert [goal, 2] in statuses and [goal, final] in statuses, (GOAL_IDS[goal], statuses)
    x, y, theta = truth(log)[-1]  # the simulator's, in the world's frame: the map's
    error = math.hypot(x - GOAL[0], y - GOAL[1])
    heading = abs(math.remainder(theta - GOAL[2], math.tau))
    print(
        f"{backend}-{distro}: the truth {100 * error:.1f} cm and {math.degrees(heading):.1f} degrees from the goal"
    )
    assert error <= 0.05 and heading <= math.radians(5), (error, math.degrees(heading))
