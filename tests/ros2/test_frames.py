"""The tf frame prefix: ros2_controllers' rule, every frame of a message, the URDF's links."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from omnibot.errors import ConfigError
from omnibot.logs import header, quaternion, schemas, vector
from omnibot.logs.rosmsg import odometry
from omnibot.motion import Pose2D
from omnibot.robot import load_robot, to_urdf
from omnibot.ros2.frames import frame_prefix, prefixed, urdf_for_tf


def test_the_prefix_defaults_to_the_namespace_and_ends_in_a_slash() -> None:
    assert frame_prefix(None, "") == ""
    assert frame_prefix(None, "/r1") == "r1/"
    assert frame_prefix(None, "fleet/r1") == "fleet/r1/"
    assert frame_prefix("", "r1") == ""  # empty: no prefix, whatever the namespace
    assert frame_prefix("robot_a", "r1") == "robot_a/"
    assert frame_prefix("/robot_a/", "") == "robot_a/"
    for bad in ("1x", "a//b", "a b", "a-b"):
        with pytest.raises(ConfigError, match="frame prefix"):
            frame_prefix(bad, "")


def test_every_frame_of_a_message_is_prefixed() -> None:
    odom = prefixed(odometry(0, "odom", "base_link", Pose2D(1, 2, 0.5), (0.0, 0.0, 0.0)), "r1/")
    assert (odom.header.frame_id, odom.child_frame_id) == ("r1/odom", "r1/base_link")
    transform = schemas.new(
        "geometry_msgs/msg/TransformStamped",
        header=header(0, "base_link"),
        child_frame_id="sonar_front",
        transform=schemas.new("geometry_msgs/msg/Transform", translation=vector(), rotation=quaternion(0)),
    )
    tf = prefixed(schemas.new("tf2_msgs/msg/TFMessage", transforms=[transform]), "r1/")
    assert (tf.transforms[0].header.frame_id, tf.transforms[0].child_frame_id) == (
        "r1/base_link",
        "r1/sonar_front",
    )
    empty = prefixed(
        schemas.new("diagnostic_msgs/msg/DiagnosticArray", header=header(0, ""), status=[]), "r1/"
    )
    assert empty.header.frame_id == ""
    same = odometry(0, "odom", "base_link", Pose2D(0, 0, 0), (0.0, 0.0, 0.0))
    assert prefixed(same, "").header.frame_id == "odom"


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
def test_the_published_urdf_is_one_tree_under_base_link_with_prefixed_links(preset: str) -> None:
    robot = load_robot(preset)
    original = ET.fromstring(to_urdf(robot))
    root = ET.fromstring(urdf_for_tf(to_urdf(robot), "r1/"))
    links = {link.get("name") for link in root.iter("link")}
    assert links == {"r1/" + str(link.get("name")) for link in original.iter("link")}
    children = {str(j.find("child").get("link")) for j in root.iter("joint")}  # type: ignore[union-attr]
    parents = {str(j.find("parent").get("link")) for j in root.iter("joint")}  # type: ignore[union-attr]
    assert links - children == {"r1/base_link"}  # the one root: what odom -> base_link hangs from
    assert parents <= links
    # joint names are not frames: as joint_states names them
    assert {j.get("name") for j in root.iter("joint")} == {j.get("name") for j in original.iter("joint")}
    footprint = next(j for j in root.iter("joint") if j.get("name") == "base_footprint_joint")
    before = next(j for j in original.iter("joint") if j.get("name") == "base_footprint_joint")
    z_before = float(before.find("origin").get("xyz").split()[2])  # type: ignore[union-attr]
    z_after = float(footprint.find("origin").get("xyz").split()[2])  # type: ignore[union-attr]
    assert z_before > 0 and z_after == pytest.approx(-z_before)  # the floor stays where it was
    unprefixed = ET.fromstring(urdf_for_tf(to_urdf(robot), ""))
    assert {link.get("name") for link in unprefixed.iter("link")} == {
        link.get("name") for link in original.iter("link")
    }
