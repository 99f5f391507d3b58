"""tf frame names of a robot on a shared ``/tf``: a frame prefix, as ros2_controllers' ``tf_frame_prefix``
(and the namespace it defaults to, checked).

Several robots publish on one ``/tf`` (an absolute topic) and tell their frames apart by a prefix:
``r1/odom``, ``r1/base_link``, ``r1/sonar_front``. ros2_controllers' rule is followed: the prefix
defaults to the namespace (without its leading ``/``), a ``/`` is appended when it lacks one, and an
empty prefix leaves the frames as they are. The prefix is applied to every frame the bridge
publishes (message headers, ``child_frame_id``, transforms) and to the link names of the URDF on
``robot_description``, so that robot_state_publisher and rviz2's RobotModel need no prefix of their
own; joint names are not frames and stay as the URDF names them (each robot's ``joint_states`` is in
its own namespace).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from omnibot.errors import ConfigError


def _names(parts: list[str]) -> bool:
    """Each part is a ROS name's token: a letter or ``_`` first, then letters, digits and ``_``."""
    return all(
        part and (part[0].isalpha() or part[0] == "_") and part.replace("_", "").isalnum() for part in parts
    )


def check_namespace(namespace: str) -> str:
    """``namespace`` without its slashes, or a one-line error."""
    text = namespace.strip("/")
    if not _names(text.split("/") if text else []):
        raise ConfigError(f"not a valid ROS namespace: {namespace!r}", key="--namespace")
    return text


def frame_prefix(prefix: str | None, namespace: str) -> str:
    """The prefix to put before every frame: ``prefix`` (None: the namespace) ending in ``/``, or ""."""
    text = namespace.strip("/") if prefix is None else prefix.strip()
    if text.startswith("/"):
        text = text[1:]
    if not text:
        return ""
    parts = text.rstrip("/").split("/")
    if not _names(parts):
        raise ConfigError(f"not a valid tf frame prefix: {prefix!r}", key="--frame-prefix")
    return "/".join(parts) + "/"


def prefixed(message: Any, prefix: str) -> Any:
    """``message`` (a rosbags message object) with ``prefix`` before each frame it names, in place:
    ``header.frame_id``, ``child_frame_id`` and the transforms of a tf2_msgs/TFMessage (an empty frame,
    as a DiagnosticArray's, stays empty)."""
    if not prefix:
        return message
    header = getattr(message, "header", None)
    if header is not None and header.frame_id:
        header.frame_id = prefix + header.frame_id
    child = getattr(message, "child_frame_id", None)
    if child:
        message.child_frame_id = prefix + child
    for transform in getattr(message, "transforms", None) or ():
        prefixed(transform, prefix)
    return message


def urdf_for_tf(urdf: str, prefix: str) -> str:
    """The URDF as published on ``robot_description``: every link named with ``prefix``, and
    ``base_link`` its root.

    omnibot's URDF hangs ``base_link`` under ``base_footprint`` (REP 105), while ``odom`` -> ``base_link``
    is what the bridge publishes (ros2_controllers' default ``base_frame_id``): robot_state_publisher
    would give ``base_link`` a second parent. The fixed ``base_footprint_joint`` is turned round
    (``base_footprint`` a child of ``base_link``, the offset negated), so the frames form one tree under
    ``odom`` and every link keeps its place.
    """
    root = ET.fromstring(urdf)
    for joint in root.iter("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            continue
        if parent.get("link") == "base_footprint" and child.get("link") == "base_link":
            parent.set("link", "base_link")
            child.set("link", "base_footprint")
            origin = joint.find("origin")
            if origin is not None:
                xyz = [float(v) for v in origin.get("xyz", "0 0 0").split()]
                origin.set("xyz", " ".join(f"{-v:g}" if v else "0" for v in xyz))
    if prefix:
        for link in root.iter("link"):
            link.set("name", prefix + link.get("name", ""))
        for tag in ("parent", "child"):
            for element in root.iter(tag):
                if element.get("link"):
                    element.set("link", prefix + element.get("link", ""))
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode")
