"""A person's and ROS 2's twists ramp at the robot's accelerations (``RampedTwist``)."""

from __future__ import annotations

import math

import pytest

from omnibot.motion import ZERO, Estimate, Twist
from omnibot.runtime import Cycle
from omnibot.teleop import Sample, TeleopConfig, TwistLimits
from omnibot.teleop.sources import DeadmanSource, RampedTwist

LIMITS = TwistLimits(1.0, 5.0, accel=2.0, angular_accel=10.0)


def cycle(now: float, estimate: Estimate | None = None) -> Cycle:
    return Cycle(0, now, now, estimate)


def test_a_drive_starts_from_the_robots_estimated_twist_and_ends_when_silent() -> None:
    ramped = RampedTwist(LIMITS, 0.05)
    moving = Estimate(0.0, 0.0, 0.0, math.pi / 2, vx=0.0, vy=0.5)  # heading +y at 0.5 m/s: 0.5 m/s ahead
    assert tuple(ramped(cycle(0.0, moving), ZERO) or ()) == pytest.approx((0.4, 0.0, 0.0))  # braking from 0.5
    assert ramped.body_accel == pytest.approx((-2.0, 0.0, 0.0))
    assert ramped(cycle(0.05), ZERO) == pytest.approx(Twist(0.3, 0.0, 0.0))
    assert ramped(cycle(0.1), None) is None and ramped.body_accel is None
    assert ramped(cycle(0.15), Twist(1.0, 0.0, 0.0)) == pytest.approx(Twist(0.1, 0.0, 0.0))  # from rest
    assert RampedTwist(None, 0.05)(cycle(0.0), Twist(1.0, 0.0, 0.0)) == Twist(1.0, 0.0, 0.0)
    assert RampedTwist(TwistLimits(1.0, 5.0), 0.05)(cycle(0.0), Twist(1.0, 0.0, 0.0)) == Twist(1.0, 0.0, 0.0)


def test_the_deadman_ramps_up_while_held_and_down_in_its_stop_sequence() -> None:
    config = TeleopConfig()
    page = DeadmanSource("page", config, limits=LIMITS)
    sent = []
    for k in range(12):
        now = k * config.period
        page.sample = Sample(Twist(0.5, 0.0, 0.0), k < 6, now)
        proposal = page.propose(cycle(now))
        sent.append(None if proposal is None else round(proposal.twist.vx, 3))
    # 0.1 m/s a period up to 0.5, then the stop sequence (5 periods) on the way down, then silence
    assert sent == [0.1, 0.2, 0.3, 0.4, 0.5, 0.5, 0.4, 0.3, 0.2, 0.1, 0.0, None]
    assert page.body_accel is None


def test_the_ramp_keeps_the_robots_time_when_the_wall_clock_runs_ahead() -> None:
    # a simulator paced to the wall clock on a loaded machine: 0.05 s of the robot's time a cycle
    # while 0.15 s of wall time pass; the robot must still get 2 m/s^2 of its own time
    ramped = RampedTwist(LIMITS, 0.05)
    sent = [ramped(Cycle(k, 0.15 * k, 0.05 * k, None), Twist(1.0, 0.0, 0.0)) for k in range(4)]
    assert [round(t.vx, 3) for t in sent if t is not None] == [0.1, 0.2, 0.3, 0.4]
