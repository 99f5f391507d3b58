"""The scans the page draws: the latest scan's returns as world points, at most every
:data:`SCAN_PERIOD` s of link time (:class:`ScanView`, which the robot link owns)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from omnibot.scan import Scan

SCAN_PERIOD = 0.2
"""s of link time between two scans in the state frames (the page draws the latest)."""
SCAN_POINTS = 180
"""Most returns of a scan sent to the page (every k-th, in the scan's order)."""


def scan_points(scan: Scan, pose: tuple[float, float, float], most: int = SCAN_POINTS) -> dict[str, Any]:
    """A scan for the page: its stamp (link time) and its returns in the world frame (m, rounded to mm)
    as seen from ``pose`` (the pose the page shows), every k-th of them so that at most ``most`` go."""
    points = scan.points("base")
    step = max(1, math.ceil(len(points) / most))
    points = points[::step]
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    world = [[round(x + c * px - s * py, 3), round(y + s * px + c * py, 3)] for px, py in points.tolist()]
    return {"t": round(scan.stamp, 3), "points": world}


class ScanView:
    """The newest scan not sent yet, and when the last one went."""

    def __init__(self) -> None:
        self._scan: Scan | None = None
        self._sent = -math.inf

    def frame(
        self, scans: Sequence[Scan], now: float, pose: tuple[float, float, float] | None
    ) -> dict[str, Any] | None:
        """The state frame's ``scan`` at link time ``now`` (``scans``: the cycle's): the newest scan
        seen, from ``pose``, when one is waiting and :data:`SCAN_PERIOD` passed; None otherwise."""
        if scans:
            self._scan = scans[-1]
        if self._scan is None or pose is None or now - self._sent < SCAN_PERIOD:
            return None
        self._sent = now
        points = scan_points(self._scan, pose)
        self._scan = None
        return points
