"""The recorded run read by Foxglove's own libraries (@mcap/core, @mcap/support's decompression,
@foxglove/rosmsg2-serialization) under the machine's Node.js: every message decodes to the values
sent (``make mcap-readers`` installs them; the tests skip, saying why, without node/npm)."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path
from typing import Any

import pytest

from omnibot.logs import topics
from tests.logs.conftest import RecordedRun, node_reader


def read_with_foxglove(path: Path) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    script = node_reader()
    out = subprocess.run(
        ["node", str(script), str(path)], capture_output=True, text=True, timeout=120, check=True
    ).stdout.splitlines()
    records = [json.loads(line) for line in out]
    assert records and "done" in records[-1], records[-1:]
    return records[:-1], records[-1]


def test_every_message_decodes_with_foxglove(recorded: RecordedRun) -> None:
    messages, end = read_with_foxglove(recorded.path)
    assert end["done"] is True and end["profile"] == "ros2"
    assert not [m for m in messages if "error" in m]
    counts: dict[str, int] = {}
    for m in messages:
        counts[m["topic"]] = counts.get(m["topic"], 0) + 1
    assert counts == recorded.counts
    assert end["metadata"]["omnibot"]["estimator"] == "fused"
    assert "rosbag2" in end["metadata"]


def test_foxglove_values_are_what_was_sent(recorded: RecordedRun) -> None:
    messages, _ = read_with_foxglove(recorded.path)
    by_topic: dict[str, list[dict[str, Any]]] = {}
    for m in messages:
        by_topic.setdefault(m["topic"], []).append(m["message"])
    cmd = by_topic[topics.CMD_VEL]
    assert len(cmd) == len(recorded.vels)
    for m, vel in zip(cmd, recorded.vels, strict=True):
        assert m["twist"]["linear"]["x"] == pytest.approx(vel.vx / 100)
        assert m["twist"]["angular"]["z"] == pytest.approx(math.radians(vel.w))
    joints = by_topic[topics.JOINT_STATES]
    for js, tel in zip(joints, recorded.telemetry, strict=True):
        assert tel.encoders is not None
        assert [round(p * 440 / (2 * math.pi)) for p in js["position"]] == list(tel.encoders)
    for m, (x, y, _) in zip(by_topic[topics.TRUTH], recorded.truth, strict=True):
        assert (m["pose"]["pose"]["position"]["x"], m["pose"]["pose"]["position"]["y"]) == (x, y)
    tx = b"".join(bytes(m["data"]) for m in by_topic[topics.LINK] if m["kind"] == "TX")
    assert tx == recorded.tx
    ranges = by_topic[topics.range_topic("front")]
    for m, tel in zip(ranges, recorded.telemetry, strict=True):
        assert tel.ranges is not None
        expected = tel.ranges[0]
        assert m["range"] == ("Infinity" if expected is None else pytest.approx(expected))


def test_foxglove_sees_absolute_topics_and_odom_covariances(recorded: RecordedRun) -> None:
    from omnibot.logs.rosmsg import POSE_VARIANCE, TWIST_VARIANCE

    messages, _ = read_with_foxglove(recorded.path)
    seen = {m["topic"] for m in messages}
    assert all(topic.startswith("/") for topic in seen), sorted(seen)
    assert {topics.ODOM, topics.IMU, topics.JOINT_STATES, topics.CMD_VEL, "/range/front"} <= seen
    odom = [m["message"] for m in messages if m["topic"] == topics.ODOM]
    for m in odom:
        assert [m["pose"]["covariance"][7 * i] for i in range(6)] == list(POSE_VARIANCE)
        assert [m["twist"]["covariance"][7 * i] for i in range(6)] == list(TWIST_VARIANCE)
