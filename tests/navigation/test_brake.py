"""The brake a goto leg ends with: the last twist ramped to rest at the robot's accelerations, done
once the estimate says still (or after the longest coast), never before."""

from __future__ import annotations

import itertools
import math

import pytest

from omnibot.motion import Estimate, Twist
from omnibot.navigation.brake import STILL_FOR, BrakeSource, coast_excess
from omnibot.robot import load_robot
from omnibot.runtime import Cycle

PERIOD = 0.01


def _cycle(k: int, speed: float) -> Cycle:
    return Cycle(k, k * PERIOD, k * PERIOD, Estimate(k * PERIOD, 0.0, 0.0, 0.0, vx=speed))


def test_the_brake_ramps_the_last_twist_to_rest_at_the_robots_acceleration() -> None:
    robot = load_robot("omni3")
    brake = BrakeSource(robot, Twist(1.5, 0.0, 1.0), PERIOD)
    a, alpha = robot.limits.acceleration_max, robot.limits.angular_acceleration_max
    speeds = []
    for k in range(200):
        proposal = brake.propose(_cycle(k, 1.0))  # the estimate still moving: not done
        assert proposal is not None
        speeds.append((proposal.twist.vx, proposal.twist.w))
    assert not brake.finished
    steps = [speeds[0][0] - 1.5] + [b[0] - a0[0] for a0, b in itertools.pairwise(speeds)]
    assert min(steps) >= -a * PERIOD - 1e-12  # never faster than the motors' acceleration
    assert speeds[0][0] > 1.5 - 2 * a * PERIOD  # it starts from the twist last asked, not from zero
    assert round(1.5 / (a * PERIOD)) <= next(k for k, s in enumerate(speeds) if s == (0.0, 0.0)) + 1
    assert math.isclose(speeds[0][1], 1.0 - alpha * PERIOD)
    assert brake.body_accel is not None and brake.accel == 0.0


def test_the_brake_is_done_once_the_estimate_is_still_for_a_while() -> None:
    brake = BrakeSource(load_robot("omni4"), Twist(0.2, 0.0, 0.0), PERIOD)
    k = 0
    while k < 50 and not brake.finished:
        brake.propose(_cycle(k, 0.0))
        k += 1
    assert brake.finished and brake.still
    # the ramp's own time to zero (0.2 m/s at 2 m/s^2: 0.1 s), then still for STILL_FOR
    assert 0.1 + STILL_FOR - PERIOD <= k * PERIOD <= 0.1 + STILL_FOR + 2 * PERIOD
    assert brake.propose(_cycle(k, 0.0)) is None


def test_the_brake_gives_up_after_the_longest_coast() -> None:
    robot = load_robot("omni4")
    brake = BrakeSource(robot, Twist(0.5, 0.0, 0.0), PERIOD)
    assert math.isclose(brake.limit, 0.5 / robot.stop_deceleration + 1.0)
    k = 0
    while not brake.finished:
        brake.propose(_cycle(k, 0.3))  # an estimate that never comes to rest
        k += 1
    assert not brake.still
    assert brake.limit < k * PERIOD <= brake.limit + 2 * PERIOD


def test_where_the_coast_stops_as_soon_the_motors_are_cut_and_the_brake_only_waits() -> None:
    # omni4's friction stops it harder than its motors may: nothing to gain by braking on them
    assert coast_excess(load_robot("omni4"), 1.0) < 0.0
    # omni3's 30 kg coast from 1 m/s: 1.56 m against 0.2 m on its motors
    omni3 = load_robot("omni3")
    assert math.isclose(
        coast_excess(omni3, 1.0), 0.5 / omni3.stop_deceleration - 0.5 / omni3.limits.acceleration_max
    )
    assert coast_excess(omni3, 1.0) > 1.0
    cut = BrakeSource(load_robot("omni4"), Twist(0.5, 0.0, 0.0), PERIOD, cut=True)
    assert cut.propose(_cycle(0, 0.3)) is None and not cut.finished  # proposes nothing, still moving
    k = 1
    while not cut.finished:
        assert cut.propose(_cycle(k, 0.0)) is None
        k += 1
    assert cut.still and (k - 1) * PERIOD == pytest.approx(STILL_FOR, abs=PERIOD)
