"""Tracking-wheel odometry: seed 002's (8)-(12) as written against the version that handles turning."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.errors import ConfigError
from omnibot.estimation.tracking import Seed002Odometry, TrackingGeometry, TrackingOdometry
from omnibot.motion import Pose2D
from omnibot.robot import load_robot, parse_description
from omnibot.sim import Simulator


def test_geometry_removes_the_rotation_term() -> None:
    geo = TrackingGeometry(load_robot("omni3").encoders.tracking)
    # the preset's wheels: "vertical" at (0, 0.1) along x, "horizontal" at (0.1, 0) along y
    # pure rotation by 0.2 rad: the wheels roll -0.1*0.2 and +0.1*0.2 without any translation
    rolled = np.array([-0.02, 0.02])
    assert geo.displacement(rolled, 0.2) == pytest.approx((0.0, 0.0))
    assert geo.naive(rolled) == pytest.approx((-0.02, 0.02))  # seed 002 takes it for a move
    assert geo.displacement(np.array([0.05, -0.01]), 0.0) == pytest.approx((0.05, -0.01))


def drive(robot_name: str = "omni3", pwm: tuple[int, ...] = (40, 10, 35), seconds: float = 3.0):
    robot = load_robot(robot_name)
    sim = Simulator(robot, seed=2)
    proper, seed = TrackingOdometry(robot), Seed002Odometry(robot)
    for odo in (proper, seed):
        odo.update(sim.tracking_counts(), 0.0)
    sim.set_pwm(list(pwm))
    theta = sim.pose.theta
    for _ in range(int(seconds / 0.01)):
        sim.advance(0.01)
        d_theta, theta = sim.pose.theta - theta, sim.pose.theta  # the true rotation (a perfect gyro)
        proper.update(sim.tracking_counts(), d_theta)
        seed.update(sim.tracking_counts(), d_theta)
    return sim, proper, seed


def test_turning_robot_proper_odometry_stays_on_truth_seed002_does_not() -> None:
    sim, proper, seed = drive()
    truth = sim.pose
    assert abs(truth.theta) > 1.0  # the robot turned a lot while driving
    err = math.hypot(proper.pose.x - truth.x, proper.pose.y - truth.y)
    err_seed = math.hypot(seed.pose.x - truth.x, seed.pose.y - truth.y)
    assert proper.distance > 0.5
    assert err < 0.005 * proper.distance + 0.002
    assert err_seed > 10 * err
    assert proper.pose.theta == pytest.approx(truth.theta)


def test_needs_two_non_parallel_wheels() -> None:
    data = load_robot("omni3").model_dump()
    one = dict(data, encoders=dict(data["encoders"], tracking=data["encoders"]["tracking"][:1]))
    with pytest.raises(ConfigError, match="at least two tracking wheels"):
        TrackingOdometry(parse_description(one))
    parallel = [dict(t, direction_deg=0) for t in data["encoders"]["tracking"]]
    with pytest.raises(ConfigError, match="parallel"):
        TrackingOdometry(parse_description(dict(data, encoders=dict(data["encoders"], tracking=parallel))))
    with pytest.raises(ConfigError, match="has 0"):
        TrackingOdometry(load_robot("omni4"))
    with pytest.raises(ValueError, match="expected 2 tracking counts"):
        TrackingOdometry(load_robot("omni3"), Pose2D(0, 0, 0)).update([1, 2, 3], 0.0)


def test_counts_wrap_at_32_bits() -> None:
    odo = TrackingOdometry(load_robot("omni3"))
    top = 2**31 - 1
    odo.update([top, 0], 0.0)
    odo.update([-(2**31) + 99, 0], 0.0)  # 100 counts forward through the wrap
    per = 2 * math.pi * 0.029 / 2400
    assert odo.pose.x == pytest.approx(100 * per)
