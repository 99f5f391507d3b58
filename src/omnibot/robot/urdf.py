"""URDF export of a robot description: a base link, one link per wheel on a continuous joint.

Frames follow REP-103/REP-105: ``base_footprint`` on the floor under the centre, ``base_link`` at
wheel-axle height. Each wheel joint's frame has x along the wheel's drive direction and its axis is
+y of that frame, so a positive joint velocity is a positive wheel speed in omnibot's convention
(the wheel carries the robot along its drive direction). Sonars and the gyro get fixed links so
tools like RViz can show them. Seed 003 writes the equivalent by hand in robot_core.xacro.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from omnibot.robot.description import RobotDescription


def _fmt(*values: float) -> str:
    return " ".join(f"{v:.9g}" for v in values)


def _inertial(parent: ET.Element, mass: float, ixx: float, iyy: float, izz: float, z: float = 0.0) -> None:
    inertial = ET.SubElement(parent, "inertial")
    ET.SubElement(inertial, "origin", xyz=_fmt(0, 0, z), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=_fmt(mass))
    ET.SubElement(inertial, "inertia", ixx=_fmt(ixx), ixy="0", ixz="0", iyy=_fmt(iyy), iyz="0", izz=_fmt(izz))


def _geometry(parent: ET.Element, robot: RobotDescription) -> None:
    fp = robot.footprint
    geom = ET.SubElement(parent, "geometry")
    if fp.shape == "circle":
        assert fp.radius is not None
        ET.SubElement(geom, "cylinder", radius=_fmt(fp.radius), length=_fmt(fp.height))
    else:
        xs = [p[0] for p in fp.outline()]
        ys = [p[1] for p in fp.outline()]
        ET.SubElement(geom, "box", size=_fmt(max(xs) - min(xs), max(ys) - min(ys), fp.height))


def to_urdf(robot: RobotDescription) -> str:
    """The robot as a URDF document (a string with an XML declaration)."""
    axle_height = max(w.radius for w in robot.wheels)
    root = ET.Element("robot", name=robot.name)
    ET.SubElement(root, "link", name="base_footprint")
    base = ET.SubElement(root, "link", name="base_link")
    fp = robot.footprint
    for tag in ("visual", "collision"):
        el = ET.SubElement(base, tag)
        ET.SubElement(el, "origin", xyz=_fmt(0, 0, fp.height / 2), rpy="0 0 0")
        _geometry(el, robot)
    wheel_mass = 0.03 * robot.mass / robot.n_wheels  # wheels carry 3% of the mass in the URDF
    body_mass = robot.mass - wheel_mass * robot.n_wheels
    # The yaw inertia is the description's; roll/pitch from a uniform slab of the footprint's size.
    r_b = fp.bounding_radius
    ixx = body_mass * (r_b**2 / 2 + fp.height**2) / 6
    _inertial(base, body_mass, ixx, ixx, robot.yaw_inertia, fp.height / 2)
    joint = ET.SubElement(root, "joint", name="base_footprint_joint", type="fixed")
    ET.SubElement(joint, "parent", link="base_footprint")
    ET.SubElement(joint, "child", link="base_link")
    ET.SubElement(joint, "origin", xyz=_fmt(0, 0, axle_height), rpy="0 0 0")

    for wheel in robot.wheels:
        link = ET.SubElement(root, "link", name=f"{wheel.name}_wheel")
        for tag in ("visual", "collision"):
            el = ET.SubElement(link, tag)
            ET.SubElement(el, "origin", xyz="0 0 0", rpy=_fmt(math.pi / 2, 0, 0))
            geom = ET.SubElement(el, "geometry")
            ET.SubElement(geom, "cylinder", radius=_fmt(wheel.radius), length=_fmt(wheel.width))
        # A thin disc: I_axle = I (from the description), the two others half of it.
        _inertial(
            link, wheel_mass, wheel.inertia / 2 or 1e-7, wheel.inertia or 1e-7, wheel.inertia / 2 or 1e-7
        )
        x, y = wheel.position
        j = ET.SubElement(root, "joint", name=f"{wheel.name}_joint", type="continuous")
        ET.SubElement(j, "parent", link="base_link")
        ET.SubElement(j, "child", link=f"{wheel.name}_wheel")
        ET.SubElement(
            j, "origin", xyz=_fmt(x, y, wheel.radius - axle_height), rpy=_fmt(0, 0, wheel.drive_angle)
        )
        ET.SubElement(j, "axis", xyz="0 1 0")

    for sonar in robot.sonars:
        ET.SubElement(root, "link", name=f"sonar_{sonar.name}")
        j = ET.SubElement(root, "joint", name=f"sonar_{sonar.name}_joint", type="fixed")
        ET.SubElement(j, "parent", link="base_link")
        ET.SubElement(j, "child", link=f"sonar_{sonar.name}")
        ET.SubElement(j, "origin", xyz=_fmt(sonar.x, sonar.y, fp.height / 2), rpy=_fmt(0, 0, sonar.angle))
    if robot.gyro is not None:
        ET.SubElement(root, "link", name="imu_link")
        j = ET.SubElement(root, "joint", name="imu_joint", type="fixed")
        ET.SubElement(j, "parent", link="base_link")
        ET.SubElement(j, "child", link="imu_link")
        ET.SubElement(j, "origin", xyz=_fmt(0, 0, fp.height / 2), rpy="0 0 0")

    ET.indent(root, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
