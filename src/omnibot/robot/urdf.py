"""URDF export of a robot description: a base link, one link per wheel on a continuous joint.

Frames follow REP-103/REP-105: ``base_footprint`` on the floor under the centre, ``base_link`` at
wheel-axle height. Each wheel joint sits at the wheel's position in the description; its frame has x
along the direction the hub rolls and its axis is +y of that frame (the axle), so a positive joint
velocity is a positive wheel speed in omnibot's convention. The hub rolls along the wheel's drive
direction, except that a Swedish wheel (rollers at gamma) with drive angle d is drawn in its equivalent
form (d + 2 gamma, -gamma) when that one rolls closer to the body's x axis (:func:`hub_angle`). The
passive tracking wheels are links on continuous joints the same way; sonars and the gyro fixed links.
The laser scanner is a fixed link named by its ``frame`` (the frame of its scans, ``laser``) at its
mount pose: ``z`` in the description is the scan plane's height above the floor, so the joint from
base_link (at axle height) is at ``z`` less the axle height.

Masses and inertias are physically valid (positive definite, triangle inequality) and add up to the
description: the driven wheels carry 3 % of the mass, each tracking wheel 0.5 %, the body the rest;
the robot's yaw inertia about its centre is the description's ``yaw_inertia`` (the body's share is
what the wheels leave), and the body's roll and pitch inertias follow from that and the footprint's
extent and height. Seed 003 writes the equivalent by hand in robot_core.xacro.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from omnibot.robot.description import RobotDescription
from omnibot.robot.parts import WheelSpec

WHEEL_MASS_SHARE = 0.03
"""Share of the robot's mass in its driven wheels (all of them)."""
TRACKING_MASS_SHARE = 0.005
"""Share of the robot's mass in each passive tracking wheel."""
TRACKING_WIDTH = 0.01
"""m: width of a tracking wheel as drawn."""


def _fmt(*values: float) -> str:
    """Numbers as URDF attributes (9 significant digits, rounding noise such as 4e-16 or -0 shown as 0)."""
    return " ".join(f"{round(v, 12) + 0.0:.9g}" for v in values)


def hub_angle(wheel: WheelSpec) -> float:
    """Direction (rad, body frame) the wheel's hub rolls in as drawn: its drive angle d, or for a wheel
    with rollers at gamma the equivalent d + 2 gamma (the same constraint direction d + gamma and the
    same cos(gamma), so the same wheel to kinematics) when that one is closer to the body's x axis."""
    d = wheel.drive_angle
    mirrored = d + 2 * wheel.gamma
    return mirrored if abs(math.cos(mirrored)) > abs(math.cos(d)) + 1e-9 else d


def disc_inertia(mass: float, radius: float, width: float, axle: float | None = None) -> tuple[float, float]:
    """(about a diameter, about the axle) of a wheel: the axle's from the description when it gives
    one, else a uniform disc's; a diameter's half the axle's plus the width's share."""
    ia = axle if axle else mass * radius**2 / 2
    return ia / 2 + mass * width**2 / 12, ia


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


def _wheel(
    root: ET.Element,
    name: str,
    joint_name: str,
    x: float,
    y: float,
    z: float,
    yaw: float,
    radius: float,
    width: float,
    mass: float,
    inertia: tuple[float, float],
) -> None:
    """A wheel link on a continuous joint from base_link: origin (x, y, z), x along yaw, axis +y."""
    link = ET.SubElement(root, "link", name=name)
    for tag in ("visual", "collision"):
        el = ET.SubElement(link, tag)
        ET.SubElement(el, "origin", xyz="0 0 0", rpy=_fmt(math.pi / 2, 0, 0))
        geom = ET.SubElement(el, "geometry")
        ET.SubElement(geom, "cylinder", radius=_fmt(radius), length=_fmt(width))
    diameter, axle = inertia
    _inertial(link, mass, diameter, axle, diameter)
    j = _joint(root, joint_name, "continuous", "base_link", name, _fmt(x, y, z), _fmt(0, 0, yaw))
    ET.SubElement(j, "axis", xyz="0 1 0")


def _joint(root: ET.Element, name: str, kind: str, parent: str, child: str, xyz: str, rpy: str) -> ET.Element:
    """A joint of ``kind`` from ``parent`` to ``child`` at ``xyz``, ``rpy``."""
    j = ET.SubElement(root, "joint", name=name, type=kind)
    ET.SubElement(j, "parent", link=parent)
    ET.SubElement(j, "child", link=child)
    ET.SubElement(j, "origin", xyz=xyz, rpy=rpy)
    return j


def _fixed_link(root: ET.Element, name: str, joint_name: str, xyz: str, rpy: str = "0 0 0") -> None:
    """A sensor's link, fixed to base_link at ``xyz``, ``rpy``."""
    ET.SubElement(root, "link", name=name)
    _joint(root, joint_name, "fixed", "base_link", name, xyz, rpy)


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
    _joint(
        root, "base_footprint_joint", "fixed", "base_footprint", "base_link", _fmt(0, 0, axle_height), "0 0 0"
    )
    wheel_mass = WHEEL_MASS_SHARE * robot.mass / robot.n_wheels
    tracking_mass = TRACKING_MASS_SHARE * robot.mass
    yaw_of_wheels = _wheels(root, robot, axle_height, wheel_mass, tracking_mass)
    body_mass = robot.mass - wheel_mass * robot.n_wheels - tracking_mass * len(robot.encoders.tracking)
    _body_inertial(base, robot, body_mass, yaw_of_wheels)
    _sensors(root, robot, axle_height)
    ET.indent(root, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _wheels(
    root: ET.Element, robot: RobotDescription, axle_height: float, wheel_mass: float, tracking_mass: float
) -> float:
    """The driven wheels' links and joints, then the tracking wheels'; their share of the robot's yaw
    inertia about its centre."""
    yaw_of_wheels = 0.0
    for wheel in robot.wheels:
        x, y = wheel.position
        inertia = disc_inertia(wheel_mass, wheel.radius, wheel.width, wheel.inertia)
        yaw_of_wheels += inertia[0] + wheel_mass * (x * x + y * y)
        z = wheel.radius - axle_height
        yaw = hub_angle(wheel)
        size = (wheel.radius, wheel.width)
        _wheel(root, f"{wheel.name}_wheel", f"{wheel.name}_joint", x, y, z, yaw, *size, wheel_mass, inertia)
    for tw in robot.encoders.tracking:
        inertia = disc_inertia(tracking_mass, tw.radius, TRACKING_WIDTH)
        yaw_of_wheels += inertia[0] + tracking_mass * (tw.x**2 + tw.y**2)
        size = (tw.radius, TRACKING_WIDTH)
        name = f"{tw.name}_tracking_wheel"
        z = tw.radius - axle_height
        _wheel(
            root,
            name,
            f"{tw.name}_tracking_joint",
            tw.x,
            tw.y,
            z,
            tw.direction,
            *size,
            tracking_mass,
            inertia,
        )
    return yaw_of_wheels


def _body_inertial(base: ET.Element, robot: RobotDescription, body_mass: float, yaw_of_wheels: float) -> None:
    """The body's inertial: its yaw inertia is what the wheels leave of the robot's (a tenth of it at
    least); its spread in x and in y follows the footprint's extent, its spread in z a uniform slab's."""
    fp = robot.footprint
    izz = max(robot.yaw_inertia - yaw_of_wheels, 0.1 * robot.yaw_inertia)
    outline = fp.outline()
    ex = max(p[0] for p in outline) - min(p[0] for p in outline)
    ey = max(p[1] for p in outline) - min(p[1] for p in outline)
    sum_x2 = izz * ex**2 / (ex**2 + ey**2)  # the body's integral of x^2 dm; y^2 the rest of izz
    sum_z2 = body_mass * fp.height**2 / 12
    _inertial(base, body_mass, izz - sum_x2 + sum_z2, sum_x2 + sum_z2, izz, fp.height / 2)


def _sensors(root: ET.Element, robot: RobotDescription, axle_height: float) -> None:
    """The sonars', the gyro's and the laser scanner's fixed links."""
    height = robot.footprint.height / 2
    for sonar in robot.sonars:
        xyz = _fmt(sonar.x, sonar.y, height)
        _fixed_link(root, f"sonar_{sonar.name}", f"sonar_{sonar.name}_joint", xyz, _fmt(0, 0, sonar.angle))
    if robot.gyro is not None:
        _fixed_link(root, "imu_link", "imu_joint", _fmt(0, 0, height))
    scanner = robot.scanner
    if scanner is not None:
        xyz = _fmt(scanner.x, scanner.y, scanner.z - axle_height)
        _fixed_link(root, scanner.frame, f"{scanner.frame}_joint", xyz, _fmt(0, 0, scanner.yaw))
