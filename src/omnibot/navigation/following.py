"""The follower source of a path, made one way for ``omnibot follow``, ``run --follow`` and ROS 2's
``path`` topic."""

from __future__ import annotations

from typing import Any

from omnibot.control import Path, make_follower
from omnibot.navigation.runner import WATCHDOG
from omnibot.navigation.session import follower_limits
from omnibot.navigation.webteach import WATCHDOG as SLOW_WATCHDOG
from omnibot.navigation.webteach import gains_for
from omnibot.robot import RobotDescription
from omnibot.runtime import FollowerSource

FOLLOWER_PRIORITY = 10
"""The follower's priority: below every person and ROS 2's cmd_vel."""


def follower_source(
    robot: RobotDescription,
    path: Path,
    period: float,
    follower: str = "tracker",
    speed: float | None = None,
    *,
    name: str = "follower",
    priority: int = FOLLOWER_PRIORITY,
    options: dict[str, Any] | None = None,
) -> FollowerSource:
    """The follower source ``omnibot follow`` and ``run --follow`` drive ``path`` with at ``period``
    (the tracker's gains scaled as for the page's Repeat above 100 Hz; ``options``: the follower's own,
    e.g. ``off_path``); ROS 2's ``path`` uses it too."""
    limits = follower_limits(robot, speed)
    gains = gains_for(period, limits) if follower == "tracker" and period > 0.0101 else {}
    made = make_follower(follower, limits, rate=1.0 / period, **gains, **(options or {}))
    return FollowerSource(
        made,
        path,
        name=name,
        priority=priority,
        watchdog=WATCHDOG if period <= 0.0101 else SLOW_WATCHDOG,
    )
