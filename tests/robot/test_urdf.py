"""URDF export: one continuous joint per wheel whose axis gives omnibot's positive wheel speed."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from omnibot.robot.description import load_robot
from omnibot.robot.urdf import to_urdf


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
def test_urdf_structure(preset: str) -> None:
    robot = load_robot(preset)
    root = ET.fromstring(to_urdf(robot))
    assert root.tag == "robot" and root.get("name") == preset
    links = {link.get("name") for link in root.iter("link")}
    assert {"base_footprint", "base_link"} <= links
    wheel_joints = [j for j in root.iter("joint") if j.get("type") == "continuous"]
    assert [j.get("name") for j in wheel_joints] == [f"{w.name}_joint" for w in robot.wheels]
    for joint in root.iter("joint"):  # every joint connects existing links
        assert joint.find("parent").get("link") in links  # type: ignore[union-attr]
        assert joint.find("child").get("link") in links  # type: ignore[union-attr]
    total = sum(float(m.get("value", "0")) for m in root.iter("mass"))
    assert total == pytest.approx(robot.mass)


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
def test_positive_joint_rotation_carries_robot_along_drive_direction(preset: str) -> None:
    """Rolling without slip: hub velocity = omega * axis x (r z) must point along the drive direction."""
    robot = load_robot(preset)
    root = ET.fromstring(to_urdf(robot))
    for wheel in robot.wheels:
        joint = next(j for j in root.iter("joint") if j.get("name") == f"{wheel.name}_joint")
        yaw = float(joint.find("origin").get("rpy").split()[2])  # type: ignore[union-attr]
        axis_local = np.array([float(v) for v in joint.find("axis").get("xyz").split()])  # type: ignore[union-attr]
        c, s = math.cos(yaw), math.sin(yaw)
        axis = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ axis_local
        hub = np.cross(axis, [0, 0, wheel.radius])
        drive = [math.cos(wheel.drive_angle), math.sin(wheel.drive_angle), 0]
        np.testing.assert_allclose(hub / wheel.radius, drive, atol=1e-7)
