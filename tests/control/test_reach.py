"""The motors' reach: free-running wheel speeds, the body speeds they allow, and the profile's cap."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control.paths import MotionLimits, Path, time_optimal_profile
from omnibot.control.reach import course_speed_bound, free_wheel_speeds, speed_bound, wheel_rows
from omnibot.robot.description import load_robot
from omnibot.robot.kinematics import inverse, wheel_matrix


def test_free_speed_is_where_the_motor_torque_meets_its_friction() -> None:
    robot = load_robot("omni4")
    m = robot.wheels[0].motor
    omega = float(free_wheel_speeds(robot)[0])
    volts = robot.battery.voltage - m.driver_drop
    current = (volts - m.torque_constant * m.gear_ratio * omega) / m.resistance
    torque = m.gear_efficiency * m.gear_ratio * m.torque_constant * current
    assert torque == pytest.approx(m.friction_static + m.friction_viscous * omega, rel=1e-9)
    assert 0 < omega < volts / (m.torque_constant * m.gear_ratio)  # below the no-friction speed


def test_wheel_rows_are_the_kinematics_over_the_free_speed() -> None:
    robot = load_robot("omni3")
    twist = np.array([1.2, -0.4, 0.7])
    np.testing.assert_allclose(
        np.array(wheel_rows(robot)) @ twist, inverse(wheel_matrix(robot), twist) / free_wheel_speeds(robot)
    )


def test_omni3_course_bounds_follow_its_wheel_angles() -> None:
    robot = load_robot("omni3")
    rim = float(free_wheel_speeds(robot)[0]) * robot.wheels[0].radius
    # course 90: wheel 3 alone drives it at the full rim speed; course 0: wheels 1 and 2 at cos 30
    assert course_speed_bound(robot, math.pi / 2) == pytest.approx(rim, rel=1e-9)
    assert course_speed_bound(robot, 0.0) == pytest.approx(rim / math.cos(math.radians(30)), rel=1e-9)
    lo, hi = speed_bound(robot)
    assert lo == pytest.approx(rim, rel=1e-6) and hi == pytest.approx(
        rim / math.cos(math.radians(30)), rel=1e-3
    )
    assert lo < 5.0 < hi  # seed 002's 5 m/s: on some courses only
    # turning while it goes takes wheel speed from the translation
    assert speed_bound(robot, w=2.0)[0] < lo
    assert course_speed_bound(robot, 0.0, w=1e3) == 0.0


def test_the_profile_keeps_every_wheel_below_its_free_speed() -> None:
    robot = load_robot("omni3")
    limits = MotionLimits.from_robot(robot)  # 5 m/s
    sideways = Path.from_points([(0.0, 0.0), (0.0, 30.0)], theta=0.0)  # course 90 in the body
    ahead = Path.from_points([(0.0, 0.0), (30.0, 0.0)], theta=0.0)
    bound = course_speed_bound(robot, math.pi / 2)
    assert time_optimal_profile(sideways, limits).speed.max() == pytest.approx(bound, rel=1e-3)
    assert time_optimal_profile(ahead, limits).speed.max() == pytest.approx(5.0, rel=1e-6)
    planned = time_optimal_profile(sideways, limits.with_wheel_use(0.8)).speed.max()
    assert planned == pytest.approx(0.8 * bound, rel=1e-3)
    # the same run turning the body: the wheels also carry the turn, so the profile is slower
    n = 3001
    turning = Path(np.zeros(n), np.linspace(0.0, 30.0, n), np.linspace(0.0, 20.0, n))
    assert time_optimal_profile(turning, limits).min_time > time_optimal_profile(sideways, limits).min_time
    with pytest.raises(ValueError, match="wheel_use"):
        limits.with_wheel_use(1.5)
