"""The SLAM's keyframes: each scan kept, deskewed, with its estimate; the submaps made of them.

A keyframe keeps its scan, its odometry pose, its returns in the base frame (motion distortion
undone, :mod:`omnibot.mapping.deskew`) and, for the anchor submap (:mod:`omnibot.mapping.anchor`),
those measured within ``anchor_range``. A submap is keyframes' points at their current estimates,
as a match target. The estimates follow the pose graph (:mod:`omnibot.mapping.posegraph`) each time
it is optimised. :class:`KeyframeStore` is the part of :class:`~omnibot.mapping.slam.Slam` that
holds them; the loop closures and the anchor matches build on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from omnibot.mapping.deskew import scan_points
from omnibot.mapping.matcher import ScanMatcher
from omnibot.mapping.posegraph import PoseGraph
from omnibot.mapping.se2 import transform
from omnibot.mapping.target import Target, voxel_downsample
from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Keyframe:
    """A keyframe as the SLAM keeps it: its scan, odometry pose and base-frame points (deskewed)."""

    stamp: float
    odom: Pose2D
    scan: Scan
    points: FloatArray
    anchor: FloatArray
    """Its points measured within the SLAM's ``anchor_range`` (sharp), thinned to half a cell, base frame."""


class KeyframeStore:
    """The keyframes, their estimates and the pose graph they follow, on the SLAM's options."""

    matcher: ScanMatcher
    submap_keyframes: int
    search_xy: float
    loop_search_window: tuple[float, float]
    anchor_range: float
    anchor_reach: float | None
    _frames: list[Keyframe]
    _estimates: list[Pose2D]
    _graph: PoseGraph
    _twist: Twist

    def keyframes(self) -> list[tuple[Pose2D, Scan]]:
        """(corrected map-frame pose, scan) of every keyframe: what a mapper rebuilds the map from."""
        return [(pose, frame.scan) for pose, frame in zip(self._estimates, self._frames, strict=True)]

    def _keyframe(self, odom_pose: Pose2D, scan: Scan, stamp: float) -> Keyframe:
        """A keyframe of ``scan``, deskewed with the latest twist."""
        points = scan_points(scan, self._twist)
        near = np.hypot(points[:, 0] - scan.mount.x, points[:, 1] - scan.mount.y) <= self.anchor_range
        if self.anchor_reach is None:
            near[:] = False  # no anchor submap: nothing to keep
        anchor = voxel_downsample(points[near], self.matcher.resolution / 2.0)  # as a target thins them
        return Keyframe(stamp, odom_pose, scan, points, anchor)

    def _submap(self, last: int, before: int | None = None, after: int = 0) -> Target:
        """The points of keyframes ``last - before .. last + after`` at their estimates, as a match target."""
        count = self.submap_keyframes if before is None else before
        first = max(0, last - count + 1)
        end = min(len(self._frames), last + after + 1)
        pts = np.vstack([transform(self._estimates[k], self._frames[k].points) for k in range(first, end)])
        return self.matcher.target(pts, margin=max(self.search_xy, self.loop_search_window[0]) + 1.0)

    def _optimise(self, closed: bool) -> None:
        """The pose graph optimised (``closed``: after a loop closure), the estimates as it has them."""
        estimates = self._graph.optimise(closed, len(self._frames))
        if estimates is not None:
            self._estimates = estimates
