"""A genuine rclpy (Jazzy's and Kilted's wheels, Fast DDS) beside ``omnibot map --ros2 --namespace r1``, in a private
network namespace: it receives ``/r1/scan`` (sensor_msgs/LaserScan, sensor-data QoS, frame
``r1/laser``, the very values the run's log holds, which tests/logs/test_scan_log.py checks against
the simulator's Scan) and, subscribing late, ``/r1/map`` (nav_msgs/OccupancyGrid, transient local).
tf2_msgs has no rclpy wheel, so ``/tf_static`` (``r1/base_link -> r1/laser``) and ``/tf`` (``r1/map ->
r1/odom``) are read with omnibot's DDS reader beside it; rclpy's graph checks the /tf publisher's type."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from omnibot.control import Path as RobotPath
from omnibot.control import resample, write_path
from omnibot.logs import type_hash
from omnibot.robot import load_robot
from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.rclpy_distros import BOOTSTRAP, DISTROS, interpreter

PEER = r"""
import json, time
import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy, qos_profile_sensor_data
from sensor_msgs.msg import LaserScan
from nav_msgs.msg import OccupancyGrid

rclpy.init()
node = Node("scan_watcher")
got = {"scan": [], "map": []}
def on_scan(m):
    got["scan"].append({
        "ns": m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec, "frame": m.header.frame_id,
        "angle_min": m.angle_min, "angle_max": m.angle_max, "angle_increment": m.angle_increment,
        "range_min": m.range_min, "range_max": m.range_max,
        "ranges": [r if r != float("inf") else "inf" for r in m.ranges],
    })
latched = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
node.create_subscription(LaserScan, "/r1/scan", on_scan, qos_profile_sensor_data)

def spin_until(done, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end and not done():
        rclpy.spin_once(node, timeout_sec=0.02)

spin_until(lambda: len(got["scan"]) >= 30, 240)  # the map run starts slowly on a loaded machine
spin_until(lambda: False, 3.0)  # the map is made at most every 2 s: one is out by now
# a node that joins now still gets the latest map (transient local)
def on_map(m):
    got["map"].append((m, sum(1 for v in m.data if v >= 65)))
node.create_subscription(OccupancyGrid, "/r1/map", on_map, latched)
spin_until(lambda: got["map"], 60)
late_join = len(got["map"])
# the map of the first scans may mark no cell yet, and a loaded machine makes the next one late
spin_until(lambda: got["map"] and got["map"][-1][1] > 50, 120)
hashes = {t: [str(i.topic_type_hash) for i in node.get_publishers_info_by_topic(t)] for t in ("/r1/scan", "/r1/map", "/tf")}
tf_types = [i.topic_type for i in node.get_publishers_info_by_topic("/tf")]
qos = [i.qos_profile.durability.name for i in node.get_publishers_info_by_topic("/r1/map")]
scan_qos = [i.qos_profile.reliability.name for i in node.get_publishers_info_by_topic("/r1/scan")]
m, occupied = got["map"][-1] if got["map"] else (None, 0)
print(json.dumps({
    "scans": got["scan"][:40], "count": len(got["scan"]),
    "map": None if m is None else {"frame": m.header.frame_id, "width": m.info.width, "height": m.info.height,
                                  "resolution": m.info.resolution, "cells": len(m.data),
                                  "occupied": occupied},
    "late_join": late_join,
    "hashes": hashes, "tf_types": tf_types, "map_qos": qos, "scan_qos": scan_qos,
}))
node.destroy_node()
rclpy.shutdown()
"""
"""The genuine rclpy node (Jazzy's or Kilted's interpreter): scan, then a late map, and rclpy's graph."""

WATCH = r"""
import json, os, subprocess, sys, time
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
bridge = subprocess.Popen([sys.executable, "-m", "omnibot", "map", *ARGS], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
env = {k: v for k, v in os.environ.items() if k not in BOOTSTRAP}  # the peer's own wheels' bootstrap
# its result (40 scans: more than a pipe holds) to a file, read once it ended
peer = subprocess.Popen([PYTHON, "-c", PEER], stdout=open(PEER_OUT, "w"), stderr=subprocess.STDOUT, env=env)
# tf2_msgs has no wheel for rclpy (Jazzy's or Kilted's): /tf and /tf_static are read with omnibot's own
# DDS reader (types from rosbags' definitions), a participant beside the rclpy node
from omnibot.ros2.dds import LATCHED, Node, Profile
from omnibot.ros2.types import from_dds
dds = Node()
readers = [(dds.reader("/tf", "tf2_msgs/msg/TFMessage", Profile(depth=100)), "tf"),
           (dds.reader("/tf_static", "tf2_msgs/msg/TFMessage", LATCHED), "static")]
got = {"map_tf": [], "static": []}
while peer.poll() is None:
    for reader, kind in readers:
        for sample in reader.take(N=100):
            if not hasattr(sample, "__idl_typename__"):
                continue
            for t in from_dds(sample, "tf2_msgs/msg/TFMessage").transforms:
                if kind == "static":
                    got["static"].append((t.header.frame_id, t.child_frame_id, t.transform.translation.z))
                elif (t.header.frame_id, t.child_frame_id) == ("r1/map", "r1/odom"):
                    got["map_tf"].append([t.transform.translation.x, t.transform.rotation.w])
    time.sleep(0.02)
peer.wait()
peer_out = open(PEER_OUT).read()
bridge.terminate()  # (on a loaded machine the wall-paced run may not have reached its --duration)
try:
    out, _ = bridge.communicate(timeout=60)
except subprocess.TimeoutExpired:
    bridge.kill()
    out, _ = bridge.communicate()
dds.close()
lines = peer_out.strip().splitlines()
result = json.loads(lines[-1]) if lines and lines[-1].startswith("{") else {"peer_error": peer_out[-3000:]}
result.update(map_tf=got["map_tf"][-3:], static=got["static"], rc=bridge.returncode, bridge=out[-3000:])
print(json.dumps(result))
"""
"""Runs in the private namespace: ``omnibot map --ros2 ARGS``, the rclpy peer (PEER) and the tf reader."""


@pytest.mark.timeout(600)  # the map run, its SLAM and two peers share two loaded cores
@pytest.mark.parametrize("distro", DISTROS)
def test_rclpy_gets_scan_map_and_map_to_odom(distro: str, tmp_path: Path) -> None:
    python = interpreter(distro)
    path = tmp_path / "p.csv"
    pts = np.array([(1.0, 1.0), (1.8, 1.0), (1.8, 1.5)])
    write_path(resample(RobotPath.from_points(pts, theta=0.0), 0.01), path)
    log = tmp_path / "map.mcap"
    args = ["--path", str(path), "--world", "room", "--seed", "3", "--out", str(tmp_path / "out")]
    args += ["--ros2", "--ros-backend", "dds", "--namespace", "r1", "--duration", "120", "--log", str(log)]
    script = (
        f"ARGS = {json.dumps(args)}\nPYTHON = {python!r}\nBOOTSTRAP = {list(BOOTSTRAP)!r}\n"
        f"PEER_OUT = {str(tmp_path / 'peer.out')!r}\n"
        f"PEER = {PEER!r}\n" + WATCH
    )
    result = json.loads(run_in_namespace(script, timeout=580).stdout.strip().splitlines()[-1])
    print({k: v for k, v in result.items() if k not in ("scans", "bridge")})
    assert "peer_error" not in result, result
    assert result["rc"] in (0, 143), result["bridge"]  # its --duration, or SIGTERM: the log is closed
    assert result["count"] >= 30, result["bridge"]
    # the scans are the log's (stamped alike: the bridge adopts the log's placing of time)
    logged: dict[int, Any] = {}
    with AnyReader([log]) as reader:
        conns = [c for c in reader.connections if c.topic == "/scan"]
        for conn, ns, raw in reader.messages(connections=conns):
            logged[ns] = reader.deserialize(raw, conn.msgtype)
    robot = load_robot("omni4")
    assert robot.scanner is not None
    for got in result["scans"]:
        msg = logged[got["ns"]]
        assert got["frame"] == "r1/laser"
        for key in ("angle_min", "angle_max", "angle_increment", "range_min", "range_max"):
            assert got[key] == pytest.approx(getattr(msg, key), rel=1e-6), key
        assert got["angle_increment"] < 0  # clockwise, as the simulated RPLIDAR turns
        ranges = np.array([math.inf if r == "inf" else r for r in got["ranges"]], dtype=np.float32)
        np.testing.assert_array_equal(ranges, msg.ranges)
    assert result["scan_qos"] == ["BEST_EFFORT"], result
    laser = [s for s in result["static"] if s[1] == "r1/laser"]
    axle = max(w.radius for w in robot.wheels)
    assert laser and laser[0][0] == "r1/base_link" and laser[0][2] == pytest.approx(robot.scanner.z - axle)
    assert result["map_tf"], result  # r1/map -> r1/odom on /tf
    assert all(math.isfinite(x) for x, _ in result["map_tf"])
    assert result["late_join"] >= 1, result["bridge"]  # the late subscriber got the latched map
    grid = result["map"]
    assert grid is not None, result["bridge"]
    assert grid["frame"] == "r1/map" and grid["resolution"] == pytest.approx(0.05)
    assert grid["cells"] == grid["width"] * grid["height"] and grid["occupied"] > 50
    assert result["map_qos"] == ["TRANSIENT_LOCAL"], result
    assert result["hashes"]["/r1/scan"] == [type_hash("sensor_msgs/msg/LaserScan")]
    assert result["hashes"]["/r1/map"] == [type_hash("nav_msgs/msg/OccupancyGrid")]
    # rclpy's graph sees the bridge's /tf (the map -> odom itself is read with omnibot's DDS reader)
    assert "tf2_msgs/msg/TFMessage" in result["tf_types"], result
    assert type_hash("tf2_msgs/msg/TFMessage") in result["hashes"]["/tf"], result
