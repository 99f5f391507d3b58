"""Two robots in one ``omnibot ros2`` on DDS: namespaces, prefixed frames, ``initialpose``,
``reset_odometry`` (a client on rmw_cyclonedds' wire), ``path``, ``battery_state`` and each robot's
diagnostics under its own name; every message
received is decoded by rosbags. In a private network namespace (tests/ros2/netns_helper.py)."""

from __future__ import annotations

import json
import re

import pytest

from tests.ros2.netns_helper import run_in_namespace

SCRIPT = r"""
import json, math, subprocess, sys, time
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from omnibot.logs import schemas
from omnibot.logs import header, quaternion
from omnibot.ros2.dds import DEFAULT, LATCHED, Node, qos
from omnibot.ros2.types import request_type, to_dds

bridge = subprocess.Popen(
    [sys.executable, "-m", "omnibot", "ros2", "--ros-backend", "dds", "--port", URL1, "--namespace", "r1",
     "--port", URL2, "--namespace", "r2", "--duration", "120"],
    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
)
node = Node()
TYPES = {
    "r1/odom": "nav_msgs/msg/Odometry", "r2/odom": "nav_msgs/msg/Odometry", "/tf": "tf2_msgs/msg/TFMessage",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray", "r1/battery_state": "sensor_msgs/msg/BatteryState",
    "r1/robot_description": "std_msgs/msg/String",
}
readers = {
    name: node.reader(name if name.startswith("/") else "/" + name, t, LATCHED if name.endswith("description") else DEFAULT)
    for name, t in TYPES.items()
}
last, frames, statuses, counts = {}, set(), {}, {name: 0 for name in TYPES}

def pump():
    for name, reader in readers.items():
        for sample in reader.take(N=100):
            if not hasattr(sample, "__idl_typename__"):
                continue
            msg = schemas.deserialize(sample.serialize(), TYPES[name])  # rosbags, not our decoder
            counts[name] += 1
            last[name] = msg
            if name == "/tf":
                frames.update((t.header.frame_id, t.child_frame_id) for t in msg.transforms)
            if name == "/diagnostics":
                for s in msg.status:
                    statuses[(s.hardware_id, s.name)] = (s.message, {kv.key: kv.value for kv in s.values})

def wait(condition, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pump()
        if condition():
            return True
        time.sleep(0.02)
    return False

def pose(name):
    p = last[name].pose.pose
    return p.position.x, p.position.y, 2 * math.atan2(p.orientation.z, p.orientation.w)

result = {"started": wait(lambda: counts["r1/odom"] > 5 and counts["r2/odom"] > 5, 60)}
r1 = Node("r1")
initial = r1.writer("initialpose", "geometry_msgs/msg/PoseWithCovarianceStamped")
paths = r1.writer("path", "nav_msgs/msg/Path")
# a reset_odometry client as rmw_cyclonedds makes one: rq/ and rr/ topics, the header first
request_t, reply_t = request_type("std_srvs/srv/Trigger_Request"), request_type("std_srvs/srv/Trigger_Response")
requests = DataWriter(r1.participant, Topic(r1.participant, "rq/r1/reset_odometryRequest", request_t),
                      qos=qos(DEFAULT, "std_srvs/srv/Trigger_Request", "clientid=test;"))
replies = DataReader(r1.participant, Topic(r1.participant, "rr/r1/reset_odometryReply", reply_t),
                     qos=qos(DEFAULT, "std_srvs/srv/Trigger_Response", "clientid=test;"))
# discovery of the new endpoints (seconds on a loaded machine): what is written before it is lost
result["matched"] = wait(lambda: bool(initial.get_matched_subscriptions() and paths.get_matched_subscriptions()
                                      and requests.get_matched_subscriptions() and replies.get_matched_publications()), 30)
point = lambda x, y: schemas.new("geometry_msgs/msg/Point", x=x, y=y, z=0.0)
msg = schemas.new("geometry_msgs/msg/PoseWithCovarianceStamped", header=header(0, "r1/odom"),
    pose=schemas.new("geometry_msgs/msg/PoseWithCovariance",
        pose=schemas.new("geometry_msgs/msg/Pose", position=point(1.0, 0.5), orientation=quaternion(0.3)),
        covariance=[0.0] * 36))
moved = lambda: abs(pose("r1/odom")[0] - 1.0) < 0.02
end = time.monotonic() + 30
while not moved() and time.monotonic() < end:  # the same pose again until it is taken: no harm
    initial.write(to_dds(msg, "geometry_msgs/msg/PoseWithCovarianceStamped"))
    wait(moved, 1)
result["initialpose"] = moved() and pose("r1/odom")
result["r2_after_initialpose"] = pose("r2/odom")

guid = requests.instance_handle & 0xFFFFFFFFFFFFFFFF  # uint64, as rmw_cyclonedds takes it
reply = None
end = time.monotonic() + 10
while reply is None and time.monotonic() < end:
    requests.write(request_t(guid=guid, seq=41, structure_needs_at_least_one_member=0))
    time.sleep(0.3)
    for sample in replies.take(N=10):
        if hasattr(sample, "guid"):
            data = sample.serialize()
            body = schemas.deserialize(data[:4] + data[20:], "std_srvs/srv/Trigger_Response")
            reply = {"guid_echoed": sample.guid == guid, "seq": sample.seq, "success": body.success, "message": body.message}
result["reply"] = reply
result["after_reset"] = wait(lambda: abs(pose("r1/odom")[0]) < 0.02, 10) and pose("r1/odom")

poses = [schemas.new("geometry_msgs/msg/PoseStamped", header=header(0, "r1/odom"),
                     pose=schemas.new("geometry_msgs/msg/Pose", position=point(0.03 * i, 0.0), orientation=quaternion(0.0)))
         for i in range(11)]
paths.write(to_dds(schemas.new("nav_msgs/msg/Path", header=header(0, "r1/odom"), poses=poses), "nav_msgs/msg/Path"))
done = lambda: statuses.get(("r1", "omnibot r1: path"), ("", {}))[1].get("state") in ("completed", "failed")
result["path_done"] = wait(done, 40)
result["path"] = statuses.get(("r1", "omnibot r1: path"))
result["r1_after_path"] = pose("r1/odom")
result["r2_after_path"] = pose("r2/odom")
result["battery"] = statuses.get(("r1", "omnibot r1: battery"))
result["diagnostics"] = sorted(statuses)
b = last.get("r1/battery_state")
result["battery_state"] = b and [b.header.frame_id, b.voltage, math.isnan(b.percentage), b.present]
result["odom_frames"] = [[last[n].header.frame_id, last[n].child_frame_id] for n in ("r1/odom", "r2/odom")]
result["tf"] = sorted(frames)
result["urdf"] = "r1/base_link" in last.get("r1/robot_description", schemas.new("std_msgs/msg/String", data="")).data
bridge.terminate()
out, _ = bridge.communicate(timeout=30)
result["bridge"] = out
print(json.dumps(result))
"""


@pytest.mark.parametrize(
    ("url1", "url2"),
    [
        ("sim://omni4?seed=1", "sim://omni3?seed=2"),
        ("sim://omni4?fleet=f&name=r1&pose=0,0,0", "sim://omni3?fleet=f&name=r2&pose=1.5,0,0"),
    ],
    ids=["independent simulators", "one simulated world"],
)
def test_two_robots_in_one_process_each_in_its_namespace(url1: str, url2: str) -> None:
    if "fleet=" in url1:
        pytest.importorskip("omnibot.sim.fleet_link", reason="this simulator holds one robot per world")
    script = f"URL1, URL2 = {url1!r}, {url2!r}\n" + SCRIPT
    result = json.loads(run_in_namespace(script, timeout=240).stdout.strip().splitlines()[-1])
    assert result["started"] and result["matched"], result["bridge"]
    assert result["odom_frames"] == [["r1/odom", "r1/base_link"], ["r2/odom", "r2/base_link"]]
    assert {("r1/odom", "r1/base_link"), ("r2/odom", "r2/base_link")} <= {tuple(f) for f in result["tf"]}
    assert result["urdf"], "robot_description's links carry the prefix"
    # initialpose moved r1's estimate there, not r2's
    x, y, yaw = result["initialpose"]
    assert abs(x - 1.0) < 0.02 and abs(y - 0.5) < 0.02 and abs(yaw - 0.3) < 0.02, result
    assert max(abs(v) for v in result["r2_after_initialpose"][:2]) < 0.02, result
    # reset_odometry answered on rmw_cyclonedds' wire: our header echoed, success, the estimate at 0
    reply = result["reply"]
    assert reply is not None and reply["guid_echoed"] and reply["seq"] == 41 and reply["success"], result
    assert reply["message"].startswith("odometry reset by reset_odometry")
    assert max(abs(v) for v in result["after_reset"]) < 0.02, result
    # the path (0.3 m ahead) was repeated and reported; r2 did not move
    assert result["path_done"], result
    message, values = result["path"]
    assert message.startswith("completed"), message
    assert values["state"] == "completed", result["path"]
    assert abs(result["r1_after_path"][0] - 0.3) < 0.03 and abs(result["r1_after_path"][1]) < 0.03, result
    assert max(abs(v) for v in result["r2_after_path"][:2]) < 0.02, result
    assert "ros2 [r1]: path received: following 11 poses" in result["bridge"]
    assert "ros2 [r1]: path completed" in result["bridge"]
    assert (
        f"ros2 [r2]: omni3 on {url2}: node /r2/omnibot on the dds backend, domain 0, frames r2/odom"
        in result["bridge"]
    )
    assert "has not waited" not in result["bridge"]  # a shared world's clock never held up
    # the simulated controller reports its battery: published and in diagnostics
    assert result["battery_state"][0] == "r1/base_link" and 6.0 < result["battery_state"][1] < 13.0, result
    assert result["battery_state"][2:] == [True, True]
    assert re.fullmatch(r"\d+\.\d\d V: ok", result["battery"][0]), result["battery"]  # voltage, then level
    # each robot's diagnostics under its own name: one's "path completed" never reads as the other's
    names = {tuple(key) for key in result["diagnostics"]}
    for robot in ("r1", "r2"):
        items = ("control", "battery", "path", "odometry")
        assert {(robot, f"omnibot {robot}: {item}") for item in items} <= names, names
    assert all(name.startswith(f"omnibot {hardware_id}: ") for hardware_id, name in names), names


def test_a_robot_that_cannot_be_opened_ends_the_fleet_before_any_moves() -> None:
    script = (
        "import json, subprocess, sys\n"
        "r = subprocess.run([sys.executable, '-m', 'omnibot', 'ros2', '--ros-backend', 'dds',"
        " '--port', 'sim://omni4?seed=1',"
        " '--namespace', 'r1', '--port', 'sim://nosuch', '--namespace', 'r2', '--duration', '30'],"
        " capture_output=True, text=True, timeout=120)\n"
        "print(json.dumps([r.returncode, r.stdout, r.stderr]))\n"
    )
    rc, out, err = json.loads(run_in_namespace(script, timeout=180).stdout.strip().splitlines()[-1])
    assert rc == 2, (out, err)
    assert err.strip() == "omnibot: error: unknown robot 'nosuch'; expected one of: mecanum4, omni3, omni4"
    assert "on sim://omni4" not in out  # r1 never started: the robots start together or not at all
