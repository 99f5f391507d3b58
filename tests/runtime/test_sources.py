"""A follower steering in another frame than the odometry's (a SLAM's map -> odom)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control import Path, make_follower
from omnibot.mapping import compose
from omnibot.motion import Estimate, Pose2D
from omnibot.navigation.session import follower_limits
from omnibot.robot import load_robot
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.sources import FollowerSource, moved


def test_an_estimate_moved_into_another_frame_keeps_its_motion() -> None:
    t = Pose2D(0.3, -0.2, math.pi / 2)
    state = Estimate(5.0, 1.0, 2.0, 0.1, vx=0.4, vy=0.0, w=0.2)
    m = moved(state, t)
    expected = compose(t, state.pose)
    assert (m.x, m.y, m.theta) == pytest.approx((expected.x, expected.y, expected.theta))
    assert (m.vx, m.vy, m.w) == pytest.approx((0.0, 0.4, 0.2))  # turned with the frame
    assert m.body_twist.vx == pytest.approx(state.body_twist.vx)  # the same motion of the body


def framed_follower() -> tuple[FollowerSource, list[Pose2D | None]]:
    """The tracker on a 1.2 m line (omni4 at up to 0.25 m/s) steering in a frame, and the frame's
    correction to set (None: the odometry as it is)."""
    robot = load_robot("omni4")
    n = 61
    path = Path(np.linspace(0.0, 1.2, n), np.zeros(n), np.zeros(n))
    correction: list[Pose2D | None] = [None]
    follower = FollowerSource(
        make_follower("tracker", follower_limits(robot, 0.25), rate=100.0),
        path,
        frame=lambda: correction[0],
    )
    return follower, correction


def test_a_follower_with_a_frame_steers_by_the_estimate_in_it() -> None:
    follower, correction = framed_follower()
    odometry = Estimate(0.0, 0.0, 0.1, 0.0)
    follower.propose(Cycle(0, 0.0, 0.0, odometry))
    assert follower.state == odometry  # no map yet: the odometry as it is
    correction[0] = Pose2D(0.0, -0.1, 0.0)  # the SLAM found the odometry 10 cm off
    follower.propose(Cycle(1, 0.01, 0.01, Estimate(0.01, 0.0, 0.1, 0.0)))
    assert follower.state is not None and follower.state.y == pytest.approx(0.0)  # on the path


def test_a_localisers_correction_that_puts_the_robot_far_off_the_path_ends_the_run() -> None:
    follower, correction = framed_follower()
    assert follower.propose(Cycle(0, 0.0, 0.0, Estimate(0.0, 0.0, 0.0, 0.0))) is not None
    correction[0] = Pose2D(0.0, 0.2, 0.0)  # 20 cm: steered back, at the path's speed plus the bound
    proposal = follower.propose(Cycle(1, 0.01, 0.01, Estimate(0.01, 0.0, 0.0, 0.0)))
    assert proposal is not None and 0.1 < math.hypot(proposal.twist.vx, proposal.twist.vy) <= 0.25
    correction[0] = Pose2D(0.0, -0.7, 0.0)  # 70 cm: not chased
    assert follower.propose(Cycle(2, 0.02, 0.02, Estimate(0.02, 0.0, 0.0, 0.0))) is None
    assert follower.finished and not follower.completed
    assert follower.failure.startswith("off the path: 70.0 cm from it")
