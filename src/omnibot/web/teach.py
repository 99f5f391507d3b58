"""The hook for teach and repeat from the page (record a path while driving, then follow it).

Not built here: it arrives with the navigation issue (``omnibot.control``). A navigation module
provides an object with this shape and hands it to :class:`~omnibot.web.dashboard.Dashboard`
(``teach=``); the page then enables its Teach / Stop / Repeat buttons. Both methods run in the link
thread, which owns the client::

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

NOT_AVAILABLE = "teach and repeat arrive with the navigation issue (no path follower yet)"


class TeachRepeat(Protocol):
    """Teach and repeat, driven from the page (see the module docstring)."""

    def command(self, action: str, client: RobotClient, pose: Pose | None) -> str:
        """Handle a Teach (``record``), Stop (``stop``) or Repeat (``follow``) press."""
        ...

    def tick(self, client: RobotClient, pose: Pose | None) -> bool:
        """Called every link period; True while it is driving the robot (following a path)."""
        ...
