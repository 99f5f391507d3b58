"""A mapping run on the runtime: scans and the runtime's odometry into the SLAM, trajectories kept.

:class:`MappingSink` is a runtime sink (:mod:`omnibot.runtime.sinks`). Every cycle it keeps the
runtime's estimate (the fused wheel and gyro odometry) as the odometry trajectory, takes the scans
completed since the last cycle from a :class:`~omnibot.lidar.reader.ScanSource` (None: the
runtime's scanner, the cycle's ``scans``, which the log, ROS 2 and the page read too), gives each to the
:class:`~omnibot.mapping.slam.Slam` with the odometry pose at the scan's first ray and the
odometry's twist from its first ray to its last (interpolated between the cycles around them; a
scan newer than the last estimate waits for the next cycle), and
keeps the SLAM's pose as the estimate trajectory. Scans and estimates must share a clock: simulated
time on ``sim://`` (the link's clock and the simulator's scans), the host's monotonic clock on a
real port (the client's clock and :class:`~omnibot.lidar.reader.RplidarScanner`'s stamps).

On a link in lockstep the SLAM runs in the runtime's thread (simulated time waits for it, and the
run is deterministic); on a real link ``threaded=True`` hands the scans to a worker thread, so a
slow loop closure never delays a VEL.

:class:`LocalisingSink` is the same feed into a :class:`~omnibot.mapping.localise.Localiser` in a
saved map (goto's). The parts, each in its module: the feed that matches scans to the odometry
(:mod:`~omnibot.mapping.feed`), the map of a run's scans (:mod:`~omnibot.mapping.snapshot`) and
what a run leaves in its directory (:mod:`~omnibot.mapping.report`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from omnibot.mapping.deskew import scan_points
from omnibot.mapping.feed import ScanFeed, Track, span_twist
from omnibot.mapping.se2 import compose, transform
from omnibot.mapping.slam import Slam
from omnibot.mapping.snapshot import MapSnapshot, RangeNoise
from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]

if TYPE_CHECKING:
    from omnibot.lidar import ScanSource
    from omnibot.mapping.grid import OccupancyGrid
    from omnibot.mapping.localise import Localiser


class MappingSink(ScanFeed):
    """Feeds the SLAM from a runtime (see the module docstring); ``close()`` when the run ends."""

    def __init__(self, scans: ScanSource | None, slam: Slam | None = None, *, threaded: bool = False) -> None:
        self.slam = slam if slam is not None else Slam()
        self.estimate = Track()
        self._clouds: list[tuple[float, NDArray[np.float32], tuple[float, float]]] = []
        self._latest: FloatArray | None = None
        self._twists: dict[float, Twist] = {}  # each scan's own, by stamp, until its update
        super().__init__(scans, threaded=threaded)

    def map_to_odom_now(self) -> Pose2D | None:
        """The SLAM's ``map -> odom`` (None until its first keyframe: there is no map before)."""
        if not self.slam.keyframes():
            return None
        with self._lock:
            return self.slam.map_to_odom

    def points_now(self) -> FloatArray | None:
        """The latest scan's returns in the map frame (None before the first): the SLAM's current
        ``map -> odom`` applied to them (goto's obstacle watch while exploring)."""
        with self._lock:
            latest, correction = self._latest, self.slam.map_to_odom
        return None if latest is None else transform(correction, latest)

    def _keep(self, scan: Scan, start: Pose2D, end: Pose2D, span: float) -> None:
        """Keep the scan's returns (distortion undone) for the map, and its twist for the SLAM."""
        twist = span_twist(start, end, span)
        points = scan_points(scan, twist)
        self._clouds.append((scan.stamp, points.astype(np.float32), (scan.mount.x, scan.mount.y)))
        with self._lock:
            self._latest = transform(start, points)  # the odometry frame
            self._twists[scan.stamp] = twist

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        with self._lock:
            twist = self._twists.pop(scan.stamp, None)
        pose = self.slam.update(odom, scan, scan.stamp, twist)
        with self._lock:
            self.estimate.add(scan.stamp, pose)

    # ------------------------------------------------------------------ results

    @property
    def pose(self) -> Pose2D | None:
        """The SLAM's latest map-frame pose of the robot (None before the first scan)."""
        with self._lock:
            return self.estimate.poses[-1] if self.estimate.poses else None

    def trajectory(self) -> Track:
        """The estimate trajectory with every correction of the pose graph so far (re-read from the
        SLAM: the poses recorded as they came are the ones known then)."""
        track = Track()
        for stamp, pose in self.slam.trajectory():
            track.add(stamp, pose)
        return track

    def grid(self, resolution: float = 0.05, noise: RangeNoise | None = None) -> OccupancyGrid:
        """The map: every scan's returns (motion distortion undone) at the SLAM's corrected pose of
        its first ray. A return marks its cell only within the scanner's ``noise.hit_range`` (where its
        range noise is small against a cell); farther ones clear the cells before them, short of their
        3-sigma uncertainty, and mark nothing (a far wall's noise would thicken it into the room and
        behind it). Rays without a return clear nothing: a dropout is no evidence of free space."""
        return self.snapshot()(resolution, noise)

    def snapshot(self) -> MapSnapshot:
        """What :meth:`grid` maps, as it is now (the scans so far at the SLAM's poses now): cheap to
        take in the runtime's thread, mapped later in another (the ROS 2 ``map`` publisher's)."""
        return MapSnapshot(list(self._clouds), dict(self.slam.trajectory()))


class LocalisingSink(ScanFeed):
    """Localises the robot in a saved map from a runtime: each scan, the odometry at its first ray
    and the twist over it (its motion distortion undone) go to a
    :class:`~omnibot.mapping.localise.Localiser`; :meth:`pose_now` is the map-frame pose now (the
    localiser's ``map -> odom`` composed with the latest odometry) and :meth:`points` the latest
    scan's returns in the map frame (for goto's obstacle watch)."""

    def __init__(self, scans: ScanSource | None, localiser: Localiser, *, threaded: bool = False) -> None:
        self.localiser = localiser
        self.updates = 0
        self._map_to_odom = Pose2D(0.0, 0.0, 0.0)
        self._points: FloatArray | None = None
        self._kept: dict[float, FloatArray] = {}  # deskewed returns by stamp, until the scan's update
        super().__init__(scans, threaded=threaded)

    def _keep(self, scan: Scan, start: Pose2D, end: Pose2D, span: float) -> None:
        """Keep the scan's returns in the base frame at its first ray, its distortion undone with the
        odometry's twist over it: the localiser's input, and (placed in the map once the scan has
        placed the odometry frame) the obstacle watch's."""
        points = scan_points(scan, span_twist(start, end, span))
        with self._lock:
            self._kept[scan.stamp] = points

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        with self._lock:
            kept = self._kept.pop(scan.stamp, None)
        self.localiser.update(odom, scan, kept)
        with self._lock:
            self._map_to_odom = self.localiser.map_to_odom
            self.updates += 1
            if kept is not None:  # the base frame at the first ray is the odometry's pose there
                self._points = transform(compose(self._map_to_odom, odom), kept)

    def map_to_odom_now(self) -> Pose2D:
        """The odometry frame's pose in the map, as the last scan placed it (the start's guess before)."""
        with self._lock:
            return self._map_to_odom

    def points(self) -> FloatArray | None:
        """The latest scan's returns in the map frame (None before the first)."""
        with self._lock:
            return self._points
