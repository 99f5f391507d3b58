"""The stall detector on made-up telemetry: each witness alone finds wheels that turn while the body
does not, a body that moves (also slower than its wheels, or stalled for less than HOLD) is no
stall, and a witness that says nothing (a silent gyro, no sonar echo farther than SONAR_NEAR) is no
evidence."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from omnibot.estimation.stall import EFFORT_WINDOW, HOLD, SONAR_NEAR, WINDOW, Stall, StallDetector
from omnibot.motion import Pose2D, Twist
from omnibot.robot import RobotDescription, load_robot

DT = 0.01


@dataclass(frozen=True)
class Sample:
    """A TEL sample (the fields the detector reads)."""

    time: float
    controller_time: float
    encoders: tuple[int, ...] | None
    tracking: tuple[int, ...] | None = None
    heading: float | None = None
    gyro_rate: float | None = None
    powers: tuple[int, ...] | None = None
    ranges: tuple[float | None, ...] | None = None


class Robot:
    """Made-up telemetry of ``robot``: the wheels turn at ``wheels`` (a body twist), the body moves at
    ``body``; each witness reports the body (the gyro with a little noise, as a working one has), the
    encoders the wheels."""

    def __init__(
        self, name: str, *, truth: bool = False, gyro: bool = True, silent_gyro: bool = False
    ) -> None:
        self.robot: RobotDescription = load_robot(name)
        self.detector = StallDetector(self.robot)
        self.truth, self.gyro, self.silent_gyro = truth, gyro, silent_gyro
        cpr = {e.wheel: e.counts_per_rev for e in self.robot.encoders.motors}
        self.per_rad = np.array([cpr[w.name] / (2.0 * math.pi) for w in self.robot.wheels])
        self.angles = np.zeros(len(self.robot.wheels))
        self.tracked = np.zeros(len(self.robot.encoders.tracking))
        self.t = 0.0
        self.pose = Pose2D(0.0, 0.0, 0.0)
        self.found: list[Stall] = []

    def drive(
        self,
        seconds: float,
        wheels: Twist,
        body: Twist | None = None,
        *,
        power: int | None = None,
        wall: float | None = None,
    ) -> None:
        """``seconds`` of samples; ``power``: every wheel's applied power (None: not sent); ``wall``:
        what the front sonar sees, m ahead of the body's start (None: nothing in range)."""
        body = wheels if body is None else body
        rates = self.robot.wheel_matrix @ np.array([wheels.vx, wheels.vy, wheels.w])
        tracking = self.robot.encoders.tracking
        for _ in range(round(seconds / DT)):
            self.detector.command(self.t, wheels)
            self.t += DT
            self.angles += rates * DT
            p = self.pose
            c, s = math.cos(p.theta), math.sin(p.theta)
            self.pose = Pose2D(
                p.x + (c * body.vx - s * body.vy) * DT,
                p.y + (s * body.vx + c * body.vy) * DT,
                p.theta + body.w * DT,
            )
            for i, spec in enumerate(tracking):
                along = body.vx * math.cos(spec.direction) + body.vy * math.sin(spec.direction)
                lever = spec.x * math.sin(spec.direction) - spec.y * math.cos(spec.direction)
                self.tracked[i] += (
                    (along + body.w * lever) * DT / (2.0 * math.pi * spec.radius) * spec.counts_per_rev
                )
            sample = Sample(
                self.t,
                self.t,
                tuple(int(v) for v in np.round(self.angles * self.per_rad)),
                tuple(int(v) for v in np.round(self.tracked)) if tracking else None,
                (0.0 if self.silent_gyro else self.pose.theta + 1e-4 * math.sin(300.0 * self.t))
                if self.gyro
                else None,
                powers=None if power is None else (power,) * len(self.robot.wheels),
                ranges=None
                if wall is None
                else (wall - self.pose.x if 0.035 < wall - self.pose.x < 4.0 else None,),
            )
            found = self.detector.update(sample, self.pose if self.truth else None)
            if found is not None:
                self.found.append(found)


FORWARD = Twist(0.4, 0.0, 0.0)
STILL = Twist(0.0, 0.0, 0.0)
TURN = Twist(0.0, 0.0, 1.5)


@pytest.mark.parametrize("name", ["omni4", "omni3", "mecanum4"])
def test_a_body_that_moves_with_its_wheels_is_no_stall(name: str) -> None:
    robot = Robot(name, truth=True)
    robot.drive(1.0, STILL)
    robot.drive(2.0, FORWARD)
    robot.drive(2.0, Twist(0.3, -0.2, 1.0))
    robot.drive(1.0, Twist(0.2, 0.0, 0.0), power=255)  # at full power, at the speed asked
    assert robot.found == [] and robot.detector.evidence == ""


def test_the_truth_finds_a_body_that_stands_still_while_its_wheels_drive() -> None:
    robot = Robot("omni4", truth=True, gyro=False)
    robot.drive(1.0, FORWARD)
    robot.drive(WINDOW + HOLD + 0.1, FORWARD, STILL)
    [stall] = robot.found
    assert stall.witness == "truth"
    assert (
        stall.text
        == "stalled: the wheels say 0.40 m/s, +0.00 rad/s but the simulator's truth has the body standing still"
    )
    assert WINDOW + HOLD - 0.1 < stall.t - 1.0 < WINDOW + HOLD + 0.1


def test_a_body_slower_than_its_wheels_is_a_slipping_floor_not_a_stall() -> None:
    robot = Robot("omni4", truth=True)
    robot.drive(3.0, FORWARD, Twist(0.1, 0.0, 0.0))  # a quarter of the wheels' speed, for 3 s
    assert robot.found == []


def test_a_stall_shorter_than_hold_is_none_and_a_stall_is_told_once() -> None:
    robot = Robot("omni4", truth=True, gyro=False)
    robot.drive(1.0, FORWARD)
    robot.drive(WINDOW + HOLD - 0.15, FORWARD, STILL)
    robot.drive(1.0, FORWARD)
    assert robot.found == []
    robot.drive(3.0, FORWARD, STILL)
    assert len(robot.found) == 1  # once while it lasts
    robot.drive(1.0, STILL)  # the evidence ends: the next stall is told again
    robot.drive(2.0, FORWARD, STILL)
    assert len(robot.found) == 2


def test_the_gyro_finds_wheels_that_turn_a_body_that_does_not() -> None:
    robot = Robot("mecanum4")
    robot.drive(1.0, TURN)
    robot.drive(2.0, TURN, STILL)
    [stall] = robot.found
    assert stall.witness == "gyro" and "the gyro says the body does not turn" in stall.text


def test_a_silent_gyro_is_no_witness() -> None:
    robot = Robot("mecanum4", silent_gyro=True)  # a controller without a gyro sends heading 0
    robot.drive(1.0, STILL)
    robot.drive(3.0, TURN)
    assert robot.detector.silence.silent and robot.found == []


def test_the_tracking_wheels_find_a_body_that_does_not_move() -> None:
    robot = Robot("omni3")
    robot.drive(1.0, FORWARD)
    assert robot.found == []
    robot.drive(2.0, FORWARD, STILL)
    [stall] = robot.found
    assert stall.witness == "tracking" and "the tracking wheels do not roll" in stall.text


def test_the_sonar_finds_wheels_that_close_on_an_obstacle_that_comes_no_nearer() -> None:
    robot = Robot("omni4", gyro=False)
    robot.drive(1.0, FORWARD, wall=0.5)  # the front sonar sees the wall come nearer: no stall
    assert robot.found == [] and 0.09 < 0.5 - robot.pose.x < 0.11
    robot.drive(1.5, FORWARD, STILL, wall=0.5)  # pinned 10 cm from it: its range stands still
    [stall] = robot.found
    assert stall.witness == "sonar" and "sonar front's range stands at 1" in stall.text  # 10-14 cm


def test_the_sonar_finds_wheels_that_went_through_what_it_saw() -> None:
    robot = Robot("omni4", gyro=False)
    robot.drive(1.0, FORWARD, wall=0.43)  # nearer than 3.5 cm: no echo
    robot.drive(1.5, FORWARD, STILL, wall=0.43)
    [stall] = robot.found
    assert (
        stall.witness == "sonar"
        and "the wheels went" in stall.text
        and "towards what sonar front last saw" in stall.text
    )


def test_a_sonar_range_beyond_near_is_no_witness() -> None:
    robot = Robot("omni4", gyro=False)  # someone walking ahead at the robot's speed keeps the range
    robot.drive(3.0, FORWARD, STILL, wall=SONAR_NEAR + 0.1 + 3.0 * FORWARD.vx)
    assert robot.found == []


def held(robot: Robot, seconds: float, asked: Twist, turning: Twist, power: int) -> None:
    """``seconds`` of the wheels turning at ``turning`` (the body still) while ``asked`` is sent."""
    rates = robot.robot.wheel_matrix @ np.array([turning.vx, turning.vy, turning.w])
    for _ in range(round(seconds / DT)):
        robot.t += DT
        robot.angles += rates * DT
        robot.detector.command(robot.t, asked)
        counts = tuple(int(v) for v in np.round(robot.angles * robot.per_rad))
        found = robot.detector.update(Sample(robot.t, robot.t, counts, powers=(power,) * len(rates)))
        if found is not None:
            robot.found.append(found)


def test_the_effort_finds_wheels_held_back_at_full_power() -> None:
    robot = Robot("mecanum4", gyro=False)  # no witness of its translation but the wheels' effort
    robot.drive(1.0, FORWARD, power=120)
    held(robot, EFFORT_WINDOW + HOLD + 0.1, FORWARD, Twist(0.04, 0.0, 0.0), power=255)
    [stall] = robot.found
    assert stall.witness == "effort" and "a wheel at full power turns at 1" in stall.text  # 10-12 %


def test_a_wheel_held_back_below_full_power_or_asked_nothing_is_no_effort() -> None:
    robot = Robot("mecanum4", gyro=False)
    held(robot, 2.0, FORWARD, Twist(0.04, 0.0, 0.0), power=200)  # the loop has power to spare
    held(robot, 2.0, STILL, STILL, power=255)  # asked nothing
    # at a carpet's reach: 0.8 m/s asked 1 m/s, at full power (40 % of the wheels' free speed)
    held(robot, 2.0, Twist(1.0, 0.0, 0.0), Twist(0.8, 0.0, 0.0), power=255)
    assert robot.found == []
