"""The bridge's cmd_vel source without DDS: the newest twist while fresh, ramped at the robot's limits."""

from __future__ import annotations

import pytest

from omnibot.logs import schemas
from omnibot.logs.recorder import header, twist
from omnibot.motion import Twist
from omnibot.ros2.bridge import TWIST_STAMPED, CmdVelSource
from omnibot.ros2.types import to_dds
from omnibot.runtime.cycle import Cycle
from omnibot.teleop.mapping import TwistLimits
from tests.ros2.test_odometry import Node


def test_cmd_vel_ramps_at_the_robots_acceleration_and_falls_silent_when_stale() -> None:
    node = Node()
    source = CmdVelSource(node, limits=TwistLimits(1.0, 5.0, accel=2.0, angular_accel=10.0), period=0.02)  # type: ignore[arg-type]
    message = to_dds(
        schemas.new(TWIST_STAMPED, header=header(0, "base_link"), twist=twist(0.3, 0.0, 0.0)), TWIST_STAMPED
    )
    node.endpoints["cmd_vel"].samples.append(message)
    speeds = []
    for k in range(10):
        proposal = source.propose(Cycle(k, k * 0.02, k * 0.02, None))
        assert proposal is not None
        speeds.append(round(proposal.twist.vx, 3))
    assert speeds == [0.04, 0.08, 0.12, 0.16, 0.2, 0.24, 0.28, 0.3, 0.3, 0.3]
    assert source.body_accel == pytest.approx((0.0, 0.0, 0.0))
    assert source.propose(Cycle(10, 0.2 + source.timeout + 0.01, 0.0, None)) is None  # stale: silent
    unlimited = CmdVelSource(Node())  # type: ignore[arg-type]
    unlimited.reader.samples.append(message)
    proposal = unlimited.propose(Cycle(0, 0.0, 0.0, None))
    assert proposal is not None and proposal.twist == Twist(0.3, 0.0, 0.0)
