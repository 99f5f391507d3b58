"""The runtime's VELs (runtime/sending.py): clamped to what the controller accepts."""

from __future__ import annotations

import math

import pytest

from omnibot.client import RobotClient
from omnibot.motion import Twist
from omnibot.runtime.sending import clamp_to


def test_commands_are_clamped_to_the_controllers_limits() -> None:
    with RobotClient.open("sim://omni4", timeout=0.5) as client:
        limits = client.limits
    vmax = (limits.speed_max_cms - 1.0) / 100.0
    fast = clamp_to(limits, Twist(10.0, 10.0, 100.0))
    assert fast.speed == pytest.approx(vmax) and fast.vx == pytest.approx(fast.vy)
    assert fast.w == pytest.approx(math.radians(limits.rate_max_dps - 1.0))
    assert clamp_to(limits, Twist(0.1, -0.1, -0.5)) == Twist(0.1, -0.1, -0.5)
