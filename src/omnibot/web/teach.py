"""The hook for teach and repeat from the page (record a path while driving, then follow it).

The dashboard only calls it; navigation implements it
(:class:`omnibot.navigation.webteach.PathTeacher`, which ``omnibot dashboard`` hands to
:class:`~omnibot.web.dashboard.Dashboard` as ``teach=``); the page then enables its Teach / Stop /
Repeat buttons. Everything runs in the link thread, which owns the runtime (and through it the
client)::

    class PathTeacher:
        def attach(self, runtime, pose):    # once, before the first cycle: add sinks, an estimator
            ...
        def command(self, action, pose):    # "record" | "stop" | "follow"
            ...                             # start/stop recording poses, or add a follower source
            return "recording"              # a line the page shows
        following: bool                     # a repeat is under way (its source is in the runtime)

``pose`` is the state frame's pose (x, y, theta) or None. The repeat is a source of the runtime, so
the page's stick, keys or gamepad take over from it and hand back, and the emergency stop (a lock)
ends it.
"""

from __future__ import annotations

from typing import Protocol

from omnibot.runtime import Runtime

Pose = tuple[float, float, float]

NOT_AVAILABLE = "teach and repeat are not enabled on this dashboard (omnibot dashboard enables them)"


class TeachRepeat(Protocol):
    """Teach and repeat, driven from the page (see the module docstring)."""

    def attach(self, runtime: Runtime, pose: Pose | None) -> None:
        """Join ``runtime`` (link thread, once, before the first cycle)."""
        ...

    def command(self, action: str, pose: Pose | None) -> str:
        """Handle a Teach (``record``), Stop (``stop``) or Repeat (``follow``) press."""
        ...

    @property
    def following(self) -> bool:
        """True while a repeat is under way."""
        ...
