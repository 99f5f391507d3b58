"""The hook for teach and repeat from the page (record a path while driving, then follow it).

The dashboard only calls it; navigation implements it
(:class:`omnibot.navigation.webteach.PathTeacher`, which ``omnibot dashboard`` hands to
:class:`~omnibot.web.dashboard.Dashboard` as ``teach=``); the page then enables its Teach / Stop /
Repeat buttons. Both methods run in the link thread, which owns the client::

    class PathTeacher:
        def command(self, action, client, pose):   # "record" | "stop" | "follow"
            ...                                    # start/stop recording poses, or start following
            return "recording"                     # a line the page shows
        def tick(self, client, pose):              # every link period (50 ms)
            ...                                    # record a pose, or send the follower's VEL
            return following                       # True: it drives, page input is ignored

``pose`` is the state frame's pose (x, y, theta) or None. The emergency stop still works while a
path is followed: it sends STOP and calls ``command("stop", ...)``.
"""

from __future__ import annotations

from typing import Protocol

from omnibot.client.client import RobotClient

Pose = tuple[float, float, float]

NOT_AVAILABLE = "teach and repeat are not enabled on this dashboard (omnibot dashboard enables them)"


class TeachRepeat(Protocol):
    """Teach and repeat, driven from the page (see the module docstring)."""

    def command(self, action: str, client: RobotClient, pose: Pose | None) -> str:
        """Handle a Teach (``record``), Stop (``stop``) or Repeat (``follow``) press."""
        ...

    def tick(self, client: RobotClient, pose: Pose | None) -> bool:
        """Called every link period; True while it is driving the robot (following a path)."""
        ...
