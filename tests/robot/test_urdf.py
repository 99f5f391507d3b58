"""URDF export, read back by an independent parser (yourdfpy) and checked against the description:
wheel and tracking-wheel joints where the description puts them, axles that give omnibot's positive
wheel speed, physically valid inertias that add up to the description's mass and yaw inertia."""

from __future__ import annotations

import io
import math
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np
import pytest
import yourdfpy

from omnibot.robot.description import RobotDescription, load_robot, parse_description
from omnibot.robot.urdf import hub_angle, to_urdf

PRESETS = ["omni4", "omni3", "mecanum4"]


def parsed(robot: RobotDescription) -> Any:
    urdf = yourdfpy.URDF.load(io.StringIO(to_urdf(robot)), build_scene_graph=True, load_meshes=False)
    assert urdf.validate()
    return urdf


def joint(urdf: Any, name: str) -> Any:
    return next(j for j in urdf.robot.joints if j.name == name)


def base_to(urdf: Any, link: str) -> np.ndarray:
    """4x4 pose of ``link`` in base_link at the zero configuration (the parser's scene graph)."""
    return np.asarray(urdf.get_transform(frame_to=link, frame_from="base_link"))


@pytest.mark.parametrize("preset", PRESETS)
def test_the_parser_reads_every_link_and_joint(preset: str) -> None:
    robot = load_robot(preset)
    urdf = parsed(robot)
    assert urdf.robot.name == preset and urdf.base_link == "base_footprint"
    continuous = [j.name for j in urdf.robot.joints if j.type == "continuous"]
    assert continuous == [f"{w.name}_joint" for w in robot.wheels] + [
        f"{t.name}_tracking_joint" for t in robot.encoders.tracking
    ]
    assert {f"sonar_{s.name}" for s in robot.sonars} <= set(urdf.link_map)
    assert ("imu_link" in urdf.link_map) == (robot.gyro is not None)


@pytest.mark.parametrize("preset", PRESETS)
def test_wheels_sit_where_the_description_puts_them_and_turn_its_way(preset: str) -> None:
    """Joint origin = the wheel's position (axle height); axis = the axle, so that rolling without
    slip at a positive joint speed carries the hub along the direction it rolls in."""
    robot = load_robot(preset)
    urdf = parsed(robot)
    axle_height = max(w.radius for w in robot.wheels)
    wheels = [(w.name + "_wheel", *w.position, w.radius, hub_angle(w)) for w in robot.wheels]
    tracking = [
        (t.name + "_tracking_wheel", t.x, t.y, t.radius, t.direction) for t in robot.encoders.tracking
    ]
    for link, x, y, radius, rolls in wheels + tracking:
        pose = base_to(urdf, link)
        np.testing.assert_allclose(pose[:3, 3], [x, y, radius - axle_height], atol=1e-9)
        axis = pose[:3, :3] @ joint(urdf, link.replace("_wheel", "_joint")).axis
        np.testing.assert_allclose(axis, [-math.sin(rolls), math.cos(rolls), 0.0], atol=1e-8)
        hub = np.cross(axis, [0.0, 0.0, radius]) / radius  # hub velocity per rad/s, over r
        np.testing.assert_allclose(hub, [math.cos(rolls), math.sin(rolls), 0.0], atol=1e-8)


def test_omni_wheels_roll_along_their_drive_direction_and_mecanum_ones_along_x() -> None:
    for preset in ("omni4", "omni3"):
        assert all(hub_angle(w) == w.drive_angle for w in load_robot(preset).wheels)
    mecanum = load_robot("mecanum4")
    # in omnibot's frame every mecanum4 wheel drives along +x: the hubs roll along x, axles along y
    assert all(math.isclose(abs(math.cos(hub_angle(w))), 1.0) for w in mecanum.wheels)


def test_the_drawn_form_of_a_mecanum_wheel_is_the_same_wheel_to_kinematics() -> None:
    robot = load_robot("mecanum4")
    data = robot.model_dump(exclude_none=True)
    for spec, wheel in zip(data["wheels"], robot.wheels, strict=True):
        for key in ("alpha_deg", "beta_deg", "L"):
            spec.pop(key)
        x, y = wheel.position
        gamma = math.radians(spec["gamma_deg"])
        spec |= {"x": x, "y": y, "drive_angle_deg": math.degrees(hub_angle(wheel))}
        spec["gamma_deg"] = math.degrees(gamma + wheel.drive_angle - hub_angle(wheel))  # -gamma when mirrored
    drawn = parse_description(data, "mecanum4 as drawn")
    np.testing.assert_allclose(drawn.wheel_matrix, robot.wheel_matrix, atol=1e-12)


@pytest.mark.parametrize("preset", PRESETS)
def test_inertias_are_physical_and_add_up_to_the_description(preset: str) -> None:
    robot = load_robot(preset)
    urdf = parsed(robot)
    total_mass = yaw = 0.0
    for name, link in urdf.link_map.items():
        if link.inertial is None:
            continue
        inertia = np.asarray(link.inertial.inertia)
        mass = float(link.inertial.mass)
        assert mass > 0
        np.testing.assert_allclose(inertia, inertia.T)
        moments = np.linalg.eigvalsh(inertia)
        assert moments.min() > 0, name  # positive definite
        a, b, c = moments
        assert a + b >= c * (1 - 1e-12), name  # triangle inequality of the principal moments
        # its yaw inertia about the robot's centre (the links do not tilt: z stays vertical)
        pose = base_to(urdf, name) @ np.asarray(link.inertial.origin)
        rotation, (x, y, _) = pose[:3, :3], pose[:3, 3]
        yaw += float((rotation @ inertia @ rotation.T)[2, 2]) + mass * (x * x + y * y)
        total_mass += mass
    assert total_mass == pytest.approx(robot.mass)
    assert yaw == pytest.approx(robot.yaw_inertia)


def test_the_omni3_base_obeys_the_triangle_inequality() -> None:
    """The reported case: ixx + iyy < izz."""
    base = ET.fromstring(to_urdf(load_robot("omni3"))).find("link[@name='base_link']/inertial/inertia")
    assert base is not None
    ixx, iyy, izz = (float(base.get(k, "nan")) for k in ("ixx", "iyy", "izz"))
    assert ixx + iyy > izz


@pytest.mark.parametrize("preset", PRESETS)
def test_the_scanner_is_a_fixed_link_named_as_its_scans_frame_at_its_mount(preset: str) -> None:
    data = load_robot(preset).model_dump(exclude_none=True)
    data["scanner"].update(x=0.03, y=-0.02, yaw_deg=30.0)
    robot = parse_description(data)
    assert robot.scanner is not None
    urdf = parsed(robot)
    laser = joint(urdf, "laser_joint")
    assert laser.type == "fixed" and laser.parent == "base_link" and laser.child == "laser"
    floor = np.asarray(urdf.get_transform(frame_to="laser", frame_from="base_footprint"))
    np.testing.assert_allclose(floor[:3, 3], [0.03, -0.02, robot.scanner.z], atol=1e-9)
    yaw = math.atan2(floor[1, 0], floor[0, 0])
    assert yaw == pytest.approx(math.radians(30.0)) and floor[2, 2] == pytest.approx(1.0)
    del data["scanner"]
    assert "laser" not in parsed(parse_description(data)).link_map
