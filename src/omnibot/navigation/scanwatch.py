"""The scanner as goto's eyes without a localiser: the latest scan's returns in the map frame.

:class:`ScanPoints` is a runtime sink (a :class:`~omnibot.mapping.feed.ScanFeed`): each scan, its
spinning distortion undone by the odometry of its revolution, is kept in the odometry frame and
given to goto's obstacle watch (its ``scan=``) in the map frame. Where the map frame sits is the
pose provider's say: the odometry frame placed so that the latest odometry lands on ``pose()``
(the provider goto steers by), or the odometry frame itself without one (the estimator started at
the map pose: ``omnibot goto`` on a robot that is not localised). :class:`~omnibot.mapping.session.
LocalisingSink` gives the same points when a localiser places the frame.

A robot whose only range sensor is its scanner (mecanum4, omni3: no sonar) sees nothing goto's
watch can stop for unless a scan is given: this is that scan.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from omnibot.mapping import ScanFeed, compose, inverse, transform, undistorted
from omnibot.motion import Pose2D
from omnibot.navigation.goal import FloatArray, PoseProvider
from omnibot.scan import Scan

if TYPE_CHECKING:
    from omnibot.lidar import ScanSource

IDENTITY = Pose2D(0.0, 0.0, 0.0)


class ScanPoints(ScanFeed):
    """The latest scan's returns in the map frame (:meth:`points`, goto's ``scan=``); the map frame
    is where ``pose`` puts the latest odometry (None: the odometry frame is the map's). Add it to
    the runtime as a sink; ``close()`` when the run ends."""

    def __init__(self, scans: ScanSource | None, pose: PoseProvider | None = None) -> None:
        self.pose = pose
        self._points: FloatArray | None = None
        self._odom: FloatArray | None = None  # the scan being handed on, in the odometry frame
        super().__init__(scans)

    def map_to_odom_now(self) -> Pose2D | None:
        """The odometry frame's pose in the map now (None while the provider has no pose)."""
        if self.pose is None:
            return IDENTITY
        here, odom = self.pose(), self.last_odometry
        return None if here is None or odom is None else compose(here, inverse(odom))

    def _keep(self, scan: Scan, start: Pose2D, end: Pose2D, span: float) -> None:
        self._odom = transform(start, undistorted(scan, start, end, span))  # the odometry frame

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        correction = self.map_to_odom_now()
        if correction is not None and self._odom is not None:
            self._points = transform(correction, self._odom)

    def points(self) -> FloatArray | None:
        """The latest scan's returns in the map frame (None before the first)."""
        return self._points


__all__ = ["ScanPoints"]
