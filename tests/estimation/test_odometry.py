"""Wheel odometry against the simulator's ground truth."""

from __future__ import annotations

import math

import pytest

from omnibot.errors import ConfigError
from omnibot.estimation.odometry import WheelOdometry, compose_arc
from omnibot.motion import Pose2D
from omnibot.robot import load_robot
from omnibot.sim import Simulator


def test_compose_arc_follows_a_circle() -> None:
    # a quarter circle of radius 1 driven forward while turning left: ends at (1, 1) facing +y
    pose = Pose2D(0, 0, 0)
    for _ in range(100):
        pose = compose_arc(pose, math.pi / 2 / 100, 0.0, math.pi / 2 / 100)
    assert (pose.x, pose.y, pose.theta) == pytest.approx((1.0, 1.0, math.pi / 2), abs=1e-9)
    # one step of the same arc is exact too: constant twist over the interval
    one = compose_arc(Pose2D(0, 0, 0), math.pi / 2, 0.0, math.pi / 2)
    assert (one.x, one.y) == pytest.approx((1.0, 1.0), abs=1e-12)


@pytest.mark.parametrize("preset", ["omni4", "mecanum4", "omni3"])
def test_odometry_tracks_truth_while_driving_and_turning(preset: str) -> None:
    robot = load_robot(preset)
    sim = Simulator(robot, seed=1)
    odo = WheelOdometry(robot)
    odo.update(sim.encoder_counts())
    power = 30 if preset == "omni3" else 120  # omni3 (30 kg, 200 W motors) slips under hard driving
    patterns = [[power, power // 2, -power, power // 3][: robot.n_wheels], [power // 2] * robot.n_wheels]
    for pwm in patterns:
        sim.set_pwm(pwm)
        for _ in range(100):
            sim.advance(0.01)
            odo.update(sim.encoder_counts())
    truth = sim.pose
    err = math.hypot(odo.pose.x - truth.x, odo.pose.y - truth.y)
    assert odo.distance > 0.2
    assert err < 0.05 * odo.distance + 0.01
    assert odo.pose.theta == pytest.approx(truth.theta, abs=0.1)


def test_slip_shows_in_the_residual() -> None:
    robot = load_robot("omni3")
    gentle, hard = Simulator(robot, seed=1), Simulator(robot, seed=1)
    worst = []
    for sim, pwm in ((gentle, [30, 15, -30]), (hard, [255, 120, -255])):
        odo = WheelOdometry(robot)
        odo.update(sim.encoder_counts())
        sim.set_pwm(pwm)
        peak = 0.0
        for _ in range(50):
            sim.advance(0.01)
            odo.update(sim.encoder_counts())
            peak = max(peak, float(abs(odo.residual).max()))
        worst.append(peak)
    assert worst[1] > 5 * worst[0]


def test_gyro_heading_is_used_for_rotation() -> None:
    robot = load_robot("omni4")
    odo = WheelOdometry(robot)
    odo.update([0, 0, 0, 0], heading=0.0)
    pose = odo.update([0, 0, 0, 0], heading=0.3)  # wheels still (e.g. slipping) but the gyro turned
    assert pose.theta == pytest.approx(0.3)


def test_needs_encoders_and_the_right_count() -> None:
    data = load_robot("omni4").model_dump()
    data["encoders"]["motors"] = data["encoders"]["motors"][:3]
    from omnibot.robot import parse_description

    with pytest.raises(ConfigError, match="none on m4"):
        WheelOdometry(parse_description(data))
    with pytest.raises(ValueError, match="expected 4 encoder counts"):
        WheelOdometry(load_robot("omni4")).update([1, 2, 3])


def test_slipping_flag_and_counter_wrap() -> None:
    robot = load_robot("omni4")
    odo = WheelOdometry(robot)
    top = 2**31 - 1
    odo.update([top, 0, -top, 0])
    pose = odo.update([-(2**31) + 9, 0, 2**31 - 9, 0])  # 10 counts each way through the wrap
    assert pose.y == pytest.approx(10 * 2 * math.pi / 440 * 0.025)
    assert not odo.slipping
    odo.update([-(2**31) + 9, 50, 2**31 - 9, 0])  # one wheel turns alone: no rigid motion does that
    assert odo.slipping


def test_the_residual_and_slip_check_asked_late_are_the_last_intervals() -> None:
    """Computed when asked for, they are what checking every interval as it came leaves."""
    robot = load_robot("omni4")
    late, eager = WheelOdometry(robot), WheelOdometry(robot)
    counts = [[0, 0, 0, 0], [40, 0, -40, 0], [80, 0, -80, 0], [80, 50, -80, 0]]  # the last: one wheel alone
    flags = []
    for c in counts:
        late.update(c)
        eager.update(c)
        flags.append(eager.slipping)  # asked every time
    assert flags == [False, False, False, True]
    assert late.pose == eager.pose and late.slipping and late.residual.tolist() == eager.residual.tolist()
    assert late.slip_check.slip.tolist() == eager.slip_check.slip.tolist() and any(late.residual)
