"""The shipped Foxglove layout (docs/foxglove/omnibot-layout.json) names only topics a log and the
live server carry, and every message path in it resolves in that topic's ROS 2 schema."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from omnibot.logs import schemas, topics
from omnibot.logs.live import PANEL_PRIORITY, TWIST_SCHEMAS

LAYOUT = Path(__file__).parents[2] / "docs" / "foxglove" / "omnibot-layout.json"

TYPES = {
    topics.ODOM: "nav_msgs/msg/Odometry",
    topics.TRUTH: "nav_msgs/msg/Odometry",
    topics.TF: "tf2_msgs/msg/TFMessage",
    topics.JOINT_STATES: "sensor_msgs/msg/JointState",
    topics.ESTIMATE: "geometry_msgs/msg/Pose2D",
    topics.CONTROL: schemas.CONTROL,
    topics.PROTOCOL: schemas.PROTOCOL_LINE,
    topics.ROBOT_DESCRIPTION: "std_msgs/msg/String",
    topics.range_topic("front"): "sensor_msgs/msg/Range",
    topics.SCAN: "sensor_msgs/msg/LaserScan",
    topics.MAP: "nav_msgs/msg/OccupancyGrid",
}
"""What the recorder writes on each topic the layout uses (docs/logs.md's table)."""


def resolve(path: str) -> str:
    """The type a Foxglove message path (``topic.field[i].field``) ends on; AssertionError if a
    topic or field is unknown."""
    topic = next(
        (t for t in sorted(TYPES, key=len, reverse=True) if path == t or path.startswith(t + ".")), None
    )
    assert topic is not None, f"{path}: not a recorded topic"
    typename: Any = TYPES[topic]
    for part in filter(None, path[len(topic) :].split(".")):
        name, index = re.fullmatch(r"(\w+)(\[\d+\])?", part).groups()  # type: ignore[union-attr]
        fields: dict[str, Any] = dict(schemas.typestore().fielddefs[typename][1])
        assert name in fields, f"{path}: {typename} has no field {name}"
        kind, detail = fields[name]
        if index is not None:
            assert kind.name in ("SEQUENCE", "ARRAY"), f"{path}: {name} is not a sequence"
            kind, detail = detail[0]
        typename = detail if kind.name == "NAME" else detail[0]
    return str(typename)


def test_every_path_in_the_layout_resolves() -> None:
    layout = json.loads(LAYOUT.read_text())
    panels = layout["configById"]
    used = json.dumps(layout["layout"])
    assert all(pid in used for pid in panels)  # every configured panel is placed
    assert resolve("/joint_states.velocity[0]") == "float64"
    for pid, config in panels.items():
        kind = pid.split("!")[0]
        if kind in {"Plot", "StateTransitions"}:
            for p in config["paths"]:
                resolve(p["value"])
        elif kind == "RawMessages":
            resolve(config["topicPath"])
        elif kind == "3D":
            for topic in config["topics"]:
                resolve(topic)
            urdf = [layer for layer in config["layers"].values() if layer["layerId"] == "foxglove.Urdf"]
            assert [layer["topic"] for layer in urdf] == [topics.ROBOT_DESCRIPTION]
        elif kind == "Teleop":
            # what the live server takes as the Teleop panel's twist (PanelSource)
            assert config["topic"].lstrip("/") == topics.TELEOP and config["publishRate"] >= 5
        else:
            raise AssertionError(f"a panel the test does not know: {pid}")
    assert "geometry_msgs/msg/Twist" in TWIST_SCHEMAS and 10 < PANEL_PRIORITY < 100
