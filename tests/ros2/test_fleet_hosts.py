"""A fleet across machines: the robot's bridge (``omnibot ros2`` on ``sim://``) on one "host", a genuine
rclpy operator (Jazzy's wheels, Fast DDS) and a cyclonedds listener on the other; two network
namespaces joined by a veth pair (192.0.2.1 and 192.0.2.2), both made inside one private namespace
(:class:`~omnibot.ros2.netns.TwoHosts`), so the pair is all the network there is. Discovery over the
link by multicast, and on a link without multicast by static peers (``ROS_STATIC_PEERS`` on every
participant). cmd_vel in (the robot moves: the simulator's truth, from the bridge's ``--log``), odom
(rclpy) and ``/tf`` out, the robot's diagnostics under its own name and hardware_id."""

from __future__ import annotations

import importlib.util
import json
import math
import statistics
from pathlib import Path
from typing import Any

import pytest

from tests.logs.test_recorder import read_all
from tests.ros2.netns_helper import run_in_namespace

OPERATOR = Path(__file__).with_name("fleet_operator.py")

LISTENER = r"""
import json, signal, time
from omnibot.logs import schemas
from omnibot.ros2.dds import Node

stop = []
signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
node = Node()
TYPES = {"/tf": "tf2_msgs/msg/TFMessage", "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"}
readers = {name: node.reader(name, t) for name, t in TYPES.items()}
frames, statuses = set(), set()
print("ready", flush=True)
while not stop:
    for name, reader in readers.items():
        for sample in reader.take(N=100):
            if not hasattr(sample, "__idl_typename__"):
                continue
            msg = schemas.deserialize(sample.serialize(), TYPES[name])  # rosbags, not our decoder
            if name == "/tf":
                frames.update((t.header.frame_id, t.child_frame_id) for t in msg.transforms)
            else:
                statuses.update((s.hardware_id, s.name) for s in msg.status)
    time.sleep(0.02)
print(json.dumps({"tf": sorted(frames), "diagnostics": sorted(statuses)}), flush=True)
"""

SCRIPT = r"""
import json, os, signal, subprocess, sys
from omnibot.ros2.netns import TwoHosts

plan = {"namespace": "r1", "speed": 0.2, "distance": 0.3, "wait": 90}
with TwoHosts(multicast=MULTICAST) as hosts:
    a, b = hosts.ADDRESSES

    def env(peer):
        e = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="SUBNET")
        if not MULTICAST:
            e["ROS_STATIC_PEERS"] = peer
        return e

    bridge = hosts.run(0, [sys.executable, "-m", "omnibot", "ros2", "--port", "sim://omni4?seed=1&world=empty",
                           "--ros-backend", BACKEND, "--namespace", "r1", "--duration", "200", "--log", LOG],
                       env=env(b), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    listener = hosts.run(1, [sys.executable, "-c", LISTENER], env=env(a), stdout=subprocess.PIPE, text=True)
    listener.stdout.readline()
    operator = hosts.run(1, [sys.executable, OPERATOR, json.dumps(plan)], env=env(a), stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    op_out, op_err = operator.communicate(timeout=240)
    listener.terminate()
    heard = listener.communicate(timeout=30)[0]
    bridge.terminate()
    out = bridge.communicate(timeout=30)[0]
lines = op_out.strip().splitlines()
print(json.dumps({"operator": json.loads(lines[-1]) if lines else {"error": op_err},
                  "listener": json.loads(heard.strip().splitlines()[-1]), "bridge": out}))
"""


def truth(path: Path) -> list[tuple[float, float]]:
    """The simulator's positions in the bridge's log."""
    _, messages = read_all(path)
    odometry: list[Any] = messages["/omnibot/truth"]
    return [(m.pose.pose.position.x, m.pose.pose.position.y) for m in odometry]


@pytest.mark.parametrize("backend", ["dds", "rclpy"])
@pytest.mark.parametrize("multicast", [True, False], ids=["multicast", "static peers"])
def test_an_operator_on_another_host_drives_the_robot_and_reads_it(
    multicast: bool, backend: str, tmp_path: Path
) -> None:
    if importlib.util.find_spec("rclpy") is None:
        pytest.skip("rclpy is not installed (the test-only extra: pip install 'omnibot[ros2-test]')")
    log = tmp_path / "bridge.mcap"
    script = (
        f"MULTICAST, BACKEND, LOG, OPERATOR = {multicast!r}, {backend!r}, {str(log)!r}, {str(OPERATOR)!r}\n"
        f"LISTENER = {LISTENER!r}\n" + SCRIPT
    )
    result = json.loads(run_in_namespace(script, timeout=400).stdout.strip().splitlines()[-1])
    operator, heard, out = result["operator"], result["listener"], result["bridge"]
    assert operator.get("found"), (operator, out)
    # the dds wire names its static peers; rclpy's rmw reads ROS_STATIC_PEERS itself
    how = "subnet" if multicast or backend == "rclpy" else "subnet, static peers 192.0.2.2"
    assert f"node /r1/omnibot on the {backend} backend, domain 0, frames r1/odom, discovery {how}\n" in out, (
        out
    )
    # discovered across the link: the bridge's endpoints in rclpy's graph, with their ROS types
    graph = {topic: {t for _, t in entries} for topic, entries in operator["graph"].items()}
    assert "nav_msgs/msg/Odometry" in graph["/r1/odom"] and "tf2_msgs/msg/TFMessage" in graph["/tf"]
    assert graph["/r1/cmd_vel"] == {"geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"}, graph
    # cmd_vel in: the robot went ahead as far as its odom says, by the simulator's truth, and stopped
    assert operator["moved"] and operator["still"], operator
    (x0, y0), (x1, y1) = operator["start"], operator["end"]
    poses = truth(log)
    went = math.dist(poses[0], poses[-1])
    print(
        f"odom {x1 - x0:.3f} m, truth {went:.3f} m; odom latency p50 "
        f"{statistics.median(operator['latency_ns']) / 1e6:.2f} ms over {len(operator['latency_ns'])}"
    )
    assert x1 - x0 >= 0.3 and abs(y1 - y0) < 0.03, operator
    assert went == pytest.approx(math.hypot(x1 - x0, y1 - y0), abs=0.05)
    # odom and tf out, the diagnostics under the robot's name
    assert ["r1/odom", "r1/base_link"] in heard["tf"], heard
    names = {tuple(d) for d in heard["diagnostics"]}
    assert {("r1", "omnibot r1: control"), ("r1", "omnibot r1: battery")} <= names, names
    assert all(hardware_id == "r1" and name.startswith("omnibot r1: ") for hardware_id, name in names)
