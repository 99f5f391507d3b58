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


def test_a_follower_with_a_frame_steers_by_the_estimate_in_it() -> None:
    robot = load_robot("omni4")
    n = 61
    path = Path(np.linspace(0.0, 1.2, n), np.zeros(n), np.zeros(n))
    correction: list[Pose2D | None] = [None]
    follower = FollowerSource(
        make_follower("tracker", follower_limits(robot, 0.25), rate=100.0),
        path,
        frame=lambda: correction[0],
    )
    odometry = Estimate(0.0, 0.0, 0.1, 0.0)
    follower.propose(Cycle(0, 0.0, 0.0, odometry))
    assert follower.state == odometry  # no map yet: the odometry as it is
    correction[0] = Pose2D(0.0, -0.1, 0.0)  # the SLAM found the odometry 10 cm off
    follower.propose(Cycle(1, 0.01, 0.01, Estimate(0.01, 0.0, 0.1, 0.0)))
    assert follower.state is not None and follower.state.y == pytest.approx(0.0)  # on the path
