"""A genuine rclpy (Jazzy wheels, Fast DDS) beside ``omnibot map --ros2 --namespace r1``, in a private
network namespace: it receives ``/r1/scan`` (sensor_msgs/LaserScan, sensor-data QoS, frame
``r1/laser``, the very values the run's log holds, which tests/logs/test_scan_log.py checks against
the simulator's Scan) and, subscribing late, ``/r1/map`` (nav_msgs/OccupancyGrid, transient local).
tf2_msgs has no rclpy wheel, so ``/tf_static`` (``r1/base_link -> r1/laser``) and ``/tf`` (``r1/map ->
r1/odom``) are read with omnibot's DDS reader beside it; rclpy's graph checks the /tf publisher's type."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from omnibot.control.paths.files import write_path
from omnibot.control.paths.geometry import resample
from omnibot.control.paths.path import Path as RobotPath
from omnibot.logs.schemas import type_hash
from omnibot.robot.description import load_robot
from tests.ros2.netns_helper import run_in_namespace

WATCH = r"""
import json, os, subprocess, sys, time
from omnibot.ros2.dds import Profile
QOS_TF = Profile(depth=100)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
bridge = subprocess.Popen([sys.executable, "-m", "omnibot", "map", *ARGS], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy, qos_profile_sensor_data
from sensor_msgs.msg import LaserScan
from nav_msgs.msg import OccupancyGrid
# tf2_msgs has no wheel for rclpy (the ros2-test extra has none): /tf and /tf_static are read with
# omnibot's own DDS reader (types from rosbags' definitions), a second participant here
from omnibot.ros2.dds import LATCHED, Node as DdsNode
from omnibot.ros2.types import from_dds
dds = DdsNode()
tf_readers = [(dds.reader("/tf", "tf2_msgs/msg/TFMessage", QOS_TF), "tf"), (dds.reader("/tf_static", "tf2_msgs/msg/TFMessage", LATCHED), "static")]

rclpy.init()
node = Node("scan_watcher")
got = {"scan": [], "map_tf": [], "static": [], "map": []}
def on_scan(m):
    got["scan"].append({
        "ns": m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec, "frame": m.header.frame_id,
        "angle_min": m.angle_min, "angle_max": m.angle_max, "angle_increment": m.angle_increment,
        "range_min": m.range_min, "range_max": m.range_max,
        "ranges": [r if r != float("inf") else "inf" for r in m.ranges],
    })
def on_tf(m):
    for t in m.transforms:
        if (t.header.frame_id, t.child_frame_id) == ("r1/map", "r1/odom"):
            got["map_tf"].append([t.transform.translation.x, t.transform.rotation.w])
def on_static(m):
    got["static"] += [(t.header.frame_id, t.child_frame_id, t.transform.translation.z) for t in m.transforms]
def take_tf():
    for reader, kind in tf_readers:
        for sample in reader.take(N=100):
            if hasattr(sample, "__idl_typename__"):
                (on_tf if kind == "tf" else on_static)(from_dds(sample, "tf2_msgs/msg/TFMessage"))
latched = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
node.create_subscription(LaserScan, "/r1/scan", on_scan, qos_profile_sensor_data)

def spin_until(done, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end and not done():
        rclpy.spin_once(node, timeout_sec=0.02)
        take_tf()

spin_until(lambda: len(got["scan"]) >= 30 and got["map_tf"], 90)
spin_until(lambda: False, 3.0)  # the map is made at most every 2 s: one is out by now
# a node that joins now still gets the latest map (transient local)
node.create_subscription(OccupancyGrid, "/r1/map", lambda m: got["map"].append(m), latched)
spin_until(lambda: got["map"], 20)
hashes = {t: [str(i.topic_type_hash) for i in node.get_publishers_info_by_topic(t)] for t in ("/r1/scan", "/r1/map", "/tf")}
tf_types = [i.topic_type for i in node.get_publishers_info_by_topic("/tf")]
qos = [i.qos_profile.durability.name for i in node.get_publishers_info_by_topic("/r1/map")]
scan_qos = [i.qos_profile.reliability.name for i in node.get_publishers_info_by_topic("/r1/scan")]
m = got["map"][-1] if got["map"] else None
out, _ = bridge.communicate(timeout=120)
print(json.dumps({
    "scans": got["scan"][:40], "count": len(got["scan"]), "map_tf": got["map_tf"][-3:], "static": got["static"],
    "map": None if m is None else {"frame": m.header.frame_id, "width": m.info.width, "height": m.info.height,
                                  "resolution": m.info.resolution, "cells": len(m.data),
                                  "occupied": sum(1 for v in m.data if v >= 65)},
    "hashes": hashes, "tf_types": tf_types, "map_qos": qos, "scan_qos": scan_qos, "rc": bridge.returncode, "bridge": out[-3000:],
}))
node.destroy_node()
rclpy.shutdown()
dds.close()
"""


@pytest.mark.skipif(
    importlib.util.find_spec("rclpy") is None,
    reason="rclpy is not installed (the test-only extra: pip install 'omnibot[ros2-test]')",
)
def test_rclpy_gets_scan_map_and_map_to_odom(tmp_path: Path) -> None:
    path = tmp_path / "p.csv"
    pts = np.array([(1.0, 1.0), (1.8, 1.0), (1.8, 1.5)])
    write_path(resample(RobotPath.from_points(pts, theta=0.0), 0.01), path)
    log = tmp_path / "map.mcap"
    args = ["--path", str(path), "--world", "room", "--seed", "3", "--out", str(tmp_path / "out")]
    args += ["--ros2", "--namespace", "r1", "--duration", "20", "--log", str(log)]
    script = f"ARGS = {json.dumps(args)}\n" + WATCH
    result = json.loads(run_in_namespace(script, timeout=240).stdout.strip().splitlines()[-1])
    print({k: v for k, v in result.items() if k not in ("scans", "bridge")})
    assert result["rc"] == 0, result["bridge"]
    assert result["count"] >= 30, result["bridge"]
    # the scans are the log's (stamped alike: the bridge adopts the log's placing of time)
    logged = {}
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
