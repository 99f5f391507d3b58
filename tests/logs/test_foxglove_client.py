"""Foxglove live spoken to by Foxglove's own protocol client: ``@foxglove/ws-protocol``'s
``FoxgloveClient`` under Node.js (over the ``ws`` package, offering only ``foxglove.websocket.v1``,
as Lichtblick does; tests/logs/node/foxglove_client.mjs) reads the server's info and channels,
subscribes to ``/odom`` and ``/tf``, decodes what arrives with ``@foxglove/rosmsg2-serialization``
from each channel's schema, and publishes a twist on a client channel advertised as Foxglove's
Teleop panel advertises it. The lockstep simulator's truth says the twist drove the robot; the
decoded odometry is the estimator's, at the simulator's pose. ``make mcap-readers`` installs the
packages; without node/npm the tests skip, saying why."""

from __future__ import annotations

import json
import math
import queue
import subprocess
import threading
from pathlib import Path
from typing import Any

import pytest

from omnibot.client import RobotClient, guarded
from omnibot.logs import schemas, topics
from omnibot.logs.foxglove_ws import FOXGLOVE_APP, REFUSED_ORIGIN
from omnibot.logs.live import PANEL_HOLD, FoxgloveLive
from omnibot.logs.recorder import Recorder
from omnibot.logs.rosmsg import POSE_VARIANCE
from omnibot.motion import Twist
from omnibot.robot import load_robot
from omnibot.runtime import Cycle, Runtime
from tests.logs.conftest import node_script
from tests.teleop.fakes import truth

SCRIPT = "foxglove_client.mjs"
AHEAD = {"linear": {"x": 0.25, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
LINE_WAIT = 60.0
"""s the client may take to print its next line: a bound for a wedged client, not a measure."""


class Spy:
    """A recorder mirror beside the live server: every message it was handed, in order."""

    def __init__(self) -> None:
        self.seen: list[tuple[str, int, bytes]] = []

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        self.seen.append((topic, ns, data))

    def close(self) -> None:
        pass


class NodeClient:
    """The client script in a subprocess, its JSON lines read in a thread (so a full pipe never
    stalls it): :meth:`next` the next one, :meth:`send` a line to its stdin."""

    def __init__(self, script: Path, config: dict[str, Any]) -> None:
        self.proc = subprocess.Popen(
            ["node", str(script), json.dumps(config)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        self.last: dict[str, Any] = {}
        """The last line read (without a message's body)."""
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line)
        self.lines.put(None)

    def next(self) -> dict[str, Any]:
        line = self.lines.get(timeout=LINE_WAIT)
        if line is None:
            self.proc.wait(timeout=10)
            assert self.proc.stderr is not None
            raise AssertionError(
                f"the client ended ({self.proc.returncode}) after {self.last}: {self.proc.stderr.read()}"
            )
        record: dict[str, Any] = json.loads(line)
        assert record["event"] != "error", record
        self.last = {k: v for k, v in record.items() if k != "message"}  # a "close" says the code
        return record

    def send(self, record: dict[str, Any]) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(record) + "\n")
        self.proc.stdin.flush()

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait(timeout=10)
        self._reader.join(timeout=10)
        for pipe in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
            if pipe is not None:
                pipe.close()


def logged_at(sent: list[tuple[str, int, bytes]], topic: str) -> list[int]:
    """The log times of the messages on ``topic`` among ``sent``, in order."""
    return [ns for t, ns, _ in sent if t == topic]


def yaw(q: dict[str, float]) -> float:
    return math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]), 1 - 2 * (q["y"] ** 2 + q["z"] ** 2))


def stamp_ns(stamp: dict[str, int]) -> int:
    return stamp["sec"] * 1_000_000_000 + stamp["nanosec"]


def test_foxglove_s_client_subscribes_decodes_and_drives_the_robot(tmp_path: Path) -> None:
    script = node_script(SCRIPT, tmp_path)
    robot = load_robot("omni4")
    live = FoxgloveLive(0)
    spy = Spy()
    rec = Recorder(None, mirrors=[live, spy])
    client = RobotClient.open("sim://omni4?seed=3", robot)
    cycles: list[Cycle] = []
    try:
        with guarded(client, robot=robot):
            rec.attach(client, robot)
            client.telemetry(0.01)
            client.sleep(0.05)  # /odom and /tf are advertised once they carry a message
            runtime = Runtime(client, period=0.01, sources=[live.panel])
            runtime.add_sink(cycles.append)
            node = NodeClient(
                script,
                {
                    "url": live.url,
                    "subscribe": [topics.ODOM, topics.TF],
                    "publish": {"topic": "/cmd_vel", "twist": AHEAD},
                },
            )
            try:
                assert node.next() == {"event": "open", "protocol": "foxglove.websocket.v1"}
                info = node.next()
                channels = node.next()
                published = node.next()
                # the server takes a connection's messages in order: the twist handed over, the
                # subscriptions sent before it are in place
                handed = threading.Event()
                for _ in range(int(LINE_WAIT / 0.01)):
                    if live.panel.received:
                        handed.set()
                        break
                    handed.wait(0.01)
                assert handed.is_set(), "the twist never reached the panel's source"
                before, start = len(spy.seen), truth(client).pose
                runtime.run(duration=1.0)  # lockstep: 1 s of simulated time, the panel silent after its twist
                runtime.close()
                sent = spy.seen[before:]
                node.send(
                    {"until": {topic: str(logged_at(sent, topic)[-1]) for topic in (topics.ODOM, topics.TF)}}
                )
                records = []
                while (record := node.next())["event"] != "done":
                    records.append(record)
                done = record
            finally:
                node.close()
            end = truth(client).pose
    finally:
        rec.close()  # stops the server

    # what Foxglove's client was told
    assert info["event"] == "serverInfo" and info["info"]["name"] == "omnibot"
    assert "clientPublish" in info["info"]["capabilities"]
    advertised = {c["topic"]: c for c in channels["channels"]}
    assert advertised[topics.ODOM]["schemaName"] == "nav_msgs/msg/Odometry"
    assert advertised[topics.TF]["schemaName"] == "tf2_msgs/msg/TFMessage"
    assert {c["encoding"] for c in advertised.values()} == {"cdr"}
    assert {c["schemaEncoding"] for c in advertised.values()} == {"ros2msg"}
    # the encoding Lichtblick picks from the server's for the Teleop panel's channel, and no status:
    # the server took the channel and the twist
    assert published["encoding"] == "cdr" and published["schemaName"] == "geometry_msgs/Twist"
    assert done["statuses"] == []
    assert live.panel.received == 1

    # the twist drove the robot: the runtime handed it to the simulator, whose truth moved ahead
    drove = [c for c in cycles if c.decision.source == "foxglove" and c.sent is not None]
    assert drove and drove[0].sent == Twist(0.25, 0.0, 0.0)
    assert drove[-1].sent == Twist()  # the panel's stop after its hold
    assert len(drove) == pytest.approx(PANEL_HOLD / 0.01 + 2, abs=2)
    assert end.x - start.x > 0.08 and abs(end.y - start.y) < 0.02

    # every /odom and /tf message logged while subscribed reached the client, in order, and decodes
    # with Foxglove's reader to what the estimator said, near the simulator's truth
    def logged(topic: str, typename: str) -> dict[int, Any]:
        return {ns: schemas.deserialize(data, typename) for t, ns, data in sent if t == topic}

    estimate = logged(topics.ESTIMATE, "geometry_msgs/msg/Pose2D")
    real = logged(topics.TRUTH, "nav_msgs/msg/Odometry")
    odom = [r for r in records if r["topic"] == topics.ODOM]
    tf = [r for r in records if r["topic"] == topics.TF]
    assert [int(r["logTime"]) for r in odom] == logged_at(sent, topics.ODOM)
    assert [int(r["logTime"]) for r in tf] == logged_at(sent, topics.TF)
    assert len(odom) >= 90
    for record in odom:
        ns, msg = int(record["logTime"]), record["message"]
        est, pose = estimate[ns], msg["pose"]["pose"]
        assert stamp_ns(msg["header"]["stamp"]) == ns
        assert (msg["header"]["frame_id"], msg["child_frame_id"]) == ("odom", "base_link")
        assert (pose["position"]["x"], pose["position"]["y"]) == (est.x, est.y)
        assert math.remainder(yaw(pose["orientation"]) - est.theta, math.tau) == pytest.approx(0, abs=1e-9)
        assert [msg["pose"]["covariance"][7 * i] for i in range(6)] == list(POSE_VARIANCE)
        at = real[ns].pose.pose.position
        assert math.hypot(pose["position"]["x"] - at.x, pose["position"]["y"] - at.y) < 0.02
    xs = [r["message"]["pose"]["pose"]["position"]["x"] for r in odom]
    assert xs[-1] - xs[0] > 0.08  # the estimate saw it drive
    assert max(r["message"]["twist"]["twist"]["linear"]["x"] for r in odom) > 0.2
    positions = {int(r["logTime"]): r["message"]["pose"]["pose"]["position"] for r in odom}
    for record in tf:
        (transform,) = record["message"]["transforms"]
        assert (transform["header"]["frame_id"], transform["child_frame_id"]) == ("odom", "base_link")
        position = positions[int(record["logTime"])]
        assert (transform["transform"]["translation"]["x"], transform["transform"]["translation"]["y"]) == (
            position["x"],
            position["y"],
        )


@pytest.mark.parametrize(
    ("origin", "served"),
    [("https://evil.example", False), (FOXGLOVE_APP[0], True)],
    ids=["a foreign origin", "Foxglove's app"],
)
def test_foxglove_s_client_from_a_foreign_origin_is_refused(
    tmp_path: Path, origin: str, served: bool
) -> None:
    """The same client with an ``Origin`` header (a web page's) is refused with the reason; the
    same client from Foxglove's app is served (it is the origin, not the client, that is refused)."""
    script = node_script(SCRIPT, tmp_path)
    live = FoxgloveLive(0)
    try:
        run = subprocess.run(
            ["node", str(script), json.dumps({"url": live.url, "origin": origin})],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
    finally:
        live.close()
    assert run.returncode == 0, run.stderr
    events = [json.loads(line) for line in run.stdout.splitlines()]
    if served:
        assert [e["event"] for e in events] == ["open", "serverInfo", "close"]
    else:
        assert events == [{"event": "refused", "status": 403, "body": REFUSED_ORIGIN}]
