"""The SLAM's keyframes: each scan kept, deskewed, with its estimate; the submaps made of them.

A keyframe keeps its scan, its odometry pose, its returns in the base frame (motion distortion
undone, :mod:`omnibot.mapping.deskew`) and, for the anchor submap (:mod:`omnibot.mapping.anchor`),
those measured within ``anchor_range``. A submap is keyframes' points at their current estimates,
as a match target. The estimates follow the pose graph (:mod:`omnibot.mapping.posegraph`) each time
it is optimised. :class:`KeyframeStore` is the part of :class:`~omnibot.mapping.slam.Slam` that
holds them; the loop closures and the anchor matches build on it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

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

MAX_JOINED = 50
"""The most scans a keyframe holds (:meth:`KeyframeStore._join`): 5 s of an A1 standing still."""


@dataclass(frozen=True)
class Keyframe:
    """A keyframe as the SLAM keeps it: its scan, odometry pose and base-frame points (deskewed)."""

    stamp: float
    odom: Pose2D
    scan: Scan
    points: FloatArray
    anchor: FloatArray
    """Its points measured within the SLAM's ``anchor_range`` (sharp), thinned to half a cell, base frame."""
    scans: int = 1
    """How many scans its points are of: those taken where it was, the robot standing still, join it."""


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

    def keyframe_scans(self) -> list[int]:
        """How many scans each keyframe holds (more than one: a standstill's, :meth:`_join`)."""
        return [frame.scans for frame in self._frames]

    def _keyframe(self, odom_pose: Pose2D, scan: Scan, stamp: float) -> Keyframe:
        """A keyframe of ``scan``, deskewed with the latest twist."""
        return self._with_points(
            Keyframe(stamp, odom_pose, scan, np.zeros((0, 2)), np.zeros((0, 2)), 0), scan
        )

    def _join(self, k: int, scan: Scan, delta: Pose2D) -> None:
        """``scan``, taken with the robot standing still ``delta`` (odometry) from keyframe ``k``, joins
        its points, up to :data:`MAX_JOINED` scans.

        A wall's direction in one scan is off by its returns' noise (0.05-0.2 degree from the few
        metres an A1 sees densely), and every keyframe matched against it takes that error: the
        first keyframe's sets the map's heading for good, and a side wall 30 m on is off by its tilt.
        The scans of a standstill (the gyro's bias learned at the start, a stop) see the same walls
        from the same place: joined, the noise averages out (a target thins its points to the mean
        of each half cell)."""
        frame = self._frames[k]
        if frame.scans < MAX_JOINED:
            self._frames[k] = self._with_points(frame, scan, delta)

    def _with_points(self, frame: Keyframe, scan: Scan, delta: Pose2D | None = None) -> Keyframe:
        """``frame`` with ``scan``'s returns (deskewed with the latest twist; taken ``delta`` from it,
        None: where it was) added, and those within ``anchor_range`` to its anchor points."""
        at = delta if delta is not None else Pose2D(0.0, 0.0, 0.0)
        points = np.vstack((frame.points, transform(at, scan_points(scan, self._twist))))
        mount = transform(at, np.array([[scan.mount.x, scan.mount.y]]))[0]
        fresh = points[len(frame.points) :]
        near = np.hypot(fresh[:, 0] - mount[0], fresh[:, 1] - mount[1]) <= self.anchor_range
        if self.anchor_reach is None:
            near[:] = False  # no anchor submap: nothing to keep
        anchor = voxel_downsample(np.vstack((frame.anchor, fresh[near])), self.matcher.resolution / 2.0)
        return replace(frame, points=points, anchor=anchor, scans=frame.scans + 1)

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
