"""Kinematics against every seed's equations, plus properties for arbitrary layouts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from omnibot.errors import KinematicsError
from omnibot.robot import kinematics as kin
from omnibot.robot.description import load_robot


def seed003_motor_speeds(vx: float, vy: float, vtheta: float) -> np.ndarray:
    """Seed 003's own computation, written out as in its ROS node (section 4.2), in its own frame."""
    alpha = np.deg2rad([35.77, 144.23, 215.77, 324.23])
    beta = np.deg2rad([144.23, 35.77, -35.77, -144.23])
    gamma = np.deg2rad([45, -45, 45, -45])
    r, L = 0.0325, 0.0937
    j1 = np.array(
        [
            [np.sin(a + b + g), -np.cos(a + b + g), -L * np.cos(b + g)]
            for a, b, g in zip(alpha, beta, gamma, strict=False)
        ]
    )
    j2 = np.diag(r * np.cos(gamma))
    return np.asarray(np.linalg.inv(j2) @ j1 @ np.array([vx, vy, vtheta]))


def seed003_in_omnibot_frame(vx: float, vy: float, w: float) -> np.ndarray:
    """Seed 003's equations for an omnibot twist: its frame has x left and y forward, the mirror image
    of omnibot's (x forward, y left), so its twist is (vy, vx, -w)."""
    return seed003_motor_speeds(vy, vx, -w)


@pytest.mark.parametrize("twist", [(0.2, 0, 0), (0, 0.2, 0), (0.1, 0.1, 0), (0, 0, 1.5), (0.3, -0.2, 0.7)])
def test_mecanum4_matches_seed003_computation(twist: tuple[float, float, float]) -> None:
    robot = load_robot("mecanum4")
    np.testing.assert_allclose(
        kin.inverse(robot.wheel_matrix, twist), seed003_in_omnibot_frame(*twist), atol=1e-12
    )


def test_mecanum4_wheels_sit_where_their_names_say() -> None:
    """front: x > 0, left: y > 0 in omnibot's frame; in seed 003's frame (x left, y forward) the same."""
    robot = load_robot("mecanum4")
    for wheel in robot.wheels:
        x, y = wheel.position
        assert (x > 0) == wheel.name.endswith("front") and (y > 0) == wheel.name.startswith("left")
    seed_alpha = np.deg2rad([35.77, 144.23, 215.77, 324.23])  # x' left, y' forward
    for wheel, a in zip(robot.wheels, seed_alpha, strict=True):
        left, forward = 0.0937 * math.cos(a), 0.0937 * math.sin(a)
        np.testing.assert_allclose(wheel.position, (forward, left), atol=1e-12)


def test_mecanum4_main_directions_follow_seed003_fig4() -> None:
    """Fig. 4(a): forward turns all four wheels forward; sideways and rotation turn pairs against each other."""
    J = load_robot("mecanum4").wheel_matrix  # wheels: left_front, right_front, right_back, left_back
    assert np.sign(kin.inverse(J, (0.1, 0, 0))).tolist() == [1, 1, 1, 1]
    assert np.sign(kin.inverse(J, (0, 0.1, 0))).tolist() == [-1, 1, -1, 1]  # left: the diagonals oppose
    spin = kin.inverse(J, (0, 0, 1))  # counter-clockwise: left side back, right side forward
    assert np.sign(spin).tolist() == [-1, 1, 1, -1]
    diagonal = kin.inverse(J, (0.1, 0.1, 0))  # forward-left: one diagonal pair stands still
    np.testing.assert_allclose(diagonal[[0, 2]], 0.0, atol=1e-12)
    assert (diagonal[[1, 3]] > 0).all()


@pytest.mark.parametrize("theta_deg", [0, 30, 45, 90, 135, 200, 270, 333])
def test_omni3_matches_seed002_equations_5_to_7(theta_deg: float) -> None:
    robot = load_robot("omni3")
    v, th = 1.7, math.radians(theta_deg)
    rims = kin.inverse(robot.wheel_matrix, (v * math.cos(th), v * math.sin(th), 0)) * [
        w.radius for w in robot.wheels
    ]
    expected = [
        -0.5 * v * math.sin(th) + math.sqrt(3) / 2 * v * math.cos(th),  # (5)
        0.5 * v * math.sin(th) + math.sqrt(3) / 2 * v * math.cos(th),  # (6)
        v * math.sin(th),  # (7)
    ]
    np.testing.assert_allclose(rims, expected, atol=1e-12)


@pytest.mark.parametrize("course_deg", [0, 10, 45, 90, 120, 180, 270, 315])
def test_omni4_matches_seed000_power_pattern(course_deg: float) -> None:
    """Seed 000 (1): P_n ~ sin(D + D_n) with D_n = 90 (n-1); (2)/(3): turning adds the same to every motor."""
    robot = load_robot("omni4")
    d = math.radians(course_deg)
    rims = kin.inverse(robot.wheel_matrix, (math.cos(d), math.sin(d), 0)) * 0.025
    expected = [math.sin(d + math.radians(90 * n)) for n in range(4)]
    np.testing.assert_allclose(rims, expected, atol=1e-12)
    turn = kin.inverse(robot.wheel_matrix, (0, 0, 1.0)) * 0.025
    np.testing.assert_allclose(turn, [0.096] * 4, atol=1e-12)  # W R_c = w r for every wheel


def test_equal_positive_speed_on_all_omni4_wheels_turns_counter_clockwise() -> None:
    twist = kin.forward(load_robot("omni4").wheel_matrix, [10, 10, 10, 10]).twist
    assert twist[2] > 0 and abs(twist[0]) < 1e-12 and abs(twist[1]) < 1e-12


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
@settings(max_examples=60, deadline=None)
@given(
    vx=st.floats(-5, 5, allow_nan=False),
    vy=st.floats(-5, 5, allow_nan=False),
    w=st.floats(-10, 10, allow_nan=False),
)
def test_forward_inverts_inverse(preset: str, vx: float, vy: float, w: float) -> None:
    J = load_robot(preset).wheel_matrix
    result = kin.forward(J, kin.inverse(J, (vx, vy, w)))
    np.testing.assert_allclose(result.twist, (vx, vy, w), atol=1e-9)
    np.testing.assert_allclose(result.residual, 0, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(3, 6),
    data=st.data(),
)
def test_forward_inverts_inverse_for_random_holonomic_layouts(n: int, data: st.DataObject) -> None:
    angles = [2 * math.pi * k / n + data.draw(st.floats(-0.3, 0.3)) for k in range(n)]
    pos = [(0.2 * math.cos(a), 0.2 * math.sin(a)) for a in angles]
    drive = [a + math.pi / 2 + data.draw(st.floats(-0.2, 0.2)) for a in angles]
    gammas = [data.draw(st.floats(-0.8, 0.8)) for _ in range(n)]
    J = kin.wheel_rows(pos, drive, gammas, [0.05] * n)
    kin.check_holonomic(J)
    twist = (data.draw(st.floats(-2, 2)), data.draw(st.floats(-2, 2)), data.draw(st.floats(-3, 3)))
    np.testing.assert_allclose(kin.forward(J, kin.inverse(J, twist)).twist, twist, atol=1e-8)


def test_residual_flags_a_slipping_wheel() -> None:
    J = load_robot("omni4").wheel_matrix
    speeds = kin.inverse(J, (0.5, 0, 0))
    speeds[1] *= 0.8  # m2 slips: turns 20% slower than the body moves
    assert np.max(np.abs(kin.forward(J, speeds).residual)) > 0.5


def test_non_holonomic_layout_is_a_clear_error() -> None:
    # three wheels all pushing along x: nothing can move the robot sideways
    J = kin.wheel_rows([(0.1, 0), (-0.1, 0.1), (-0.1, -0.1)], [0, 0, 0], [0, 0, 0], [0.05] * 3)
    with pytest.raises(KinematicsError, match="not holonomic"):
        kin.check_holonomic(J)


def test_saturation_keeps_direction() -> None:
    values = np.array([300.0, -150.0, 60.0, 0.0])
    out = kin.saturate(values, 255)
    assert out.scale == pytest.approx(0.85)
    assert max(abs(out.values)) == pytest.approx(255)
    np.testing.assert_allclose(out.values / out.scale, values)
    unchanged = kin.saturate([10.0, -20.0], 255)
    assert unchanged.scale == 1.0
    assert unchanged.values.tolist() == [10.0, -20.0]


def test_twist_limit_scale() -> None:
    J = load_robot("omni4").wheel_matrix
    k = kin.twist_limit_scale(J, (2.0, 0, 0), wheel_speed_max=40.0)
    assert k == pytest.approx(0.5)


def test_frame_transforms_round_trip() -> None:
    twist = np.array([0.3, -0.1, 0.5])
    world = kin.body_to_world(twist, math.pi / 2)
    np.testing.assert_allclose(world, [0.1, 0.3, 0.5], atol=1e-12)
    np.testing.assert_allclose(kin.world_to_body(world, math.pi / 2), twist, atol=1e-12)


def test_bad_twist_shape_is_an_error() -> None:
    with pytest.raises(KinematicsError, match="3 components"):
        kin.inverse(load_robot("omni4").wheel_matrix, (1.0, 2.0))
    with pytest.raises(KinematicsError, match="expected 4 wheel speeds"):
        kin.forward(load_robot("omni4").wheel_matrix, [1.0, 2.0])


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
def test_contact_rows_are_the_kinematics_rows_and_their_rollers(preset: str) -> None:
    robot = load_robot(preset)
    w = robot.wheels
    traction, roller = kin.contact_rows(
        [x.position[0] for x in w],
        [x.position[1] for x in w],
        [x.drive_angle for x in w],
        [x.gamma for x in w],
    )
    rim = np.array([x.radius * np.cos(x.gamma) for x in w])
    assert np.allclose(traction / rim[:, None], robot.wheel_matrix)
    mine = kin.robot_contact_rows(robot)  # the same rows from the description
    assert np.array_equal(mine[0], traction) and np.array_equal(mine[1], roller)
    # the roller rolls across the rim's direction: unit, perpendicular translation parts
    assert np.allclose(np.einsum("ij,ij->i", traction[:, :2], roller[:, :2]), 0.0)
    assert np.allclose(np.hypot(roller[:, 0], roller[:, 1]), 1.0)
    # turning at w moves a contact by w x p, whose roller component is w (p . rim direction)
    p = np.array([x.position for x in w])
    assert np.allclose(roller[:, 2], np.einsum("ij,ij->i", p, traction[:, :2]))
