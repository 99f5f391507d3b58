"""A planar range scan, the one type every part of the SLAM bench shares.

A :class:`Scan` is one revolution of a 2D range scanner, laid out as ROS's sensor_msgs/LaserScan
lays it out (so it maps to that message one field to one field): ray ``i`` points at
``angle_min + i * angle_increment`` radians in the scanner's frame (x forward, counter-clockwise
positive) and was measured ``i * time_increment`` seconds after ``stamp``. A ray without a return
(out of range, a dropout) holds ``inf``, as REP 117 asks; ``nan`` is never used. Lengths in m,
angles in rad, times in s (the clock of whoever made the scan: simulated time on the simulator,
the host's monotonic clock on a real scanner).

The simulated scanner, the RPLIDAR reader, the mapper, the SLAM, the localiser, the ROS 2 bridge
and the logs all take and give this type. Nothing here imports anything of omnibot but the plain
types of :mod:`omnibot.motion`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Scan:
    """One revolution of a planar range scanner (see the module docstring for the conventions)."""

    stamp: float
    """Time of the first ray, s."""
    angle_min: float
    """Direction of the first ray in the scanner frame, rad."""
    angle_increment: float
    """Angle between consecutive rays, rad (negative for a clockwise scanner)."""
    ranges: FloatArray
    """Range of each ray, m; ``inf`` where there was no return."""
    range_min: float
    """Shortest range the scanner reports, m."""
    range_max: float
    """Longest range the scanner reports, m."""
    time_increment: float = 0.0
    """Time between consecutive rays, s (0 for a scanner that measures all rays at once)."""
    scan_time: float = 0.0
    """Time between the starts of two scans, s (1 / rate)."""
    intensities: FloatArray | None = None
    """Return strength of each ray (the RPLIDAR's quality), or None."""
    frame: str = "laser"
    """Name of the scanner's frame (the URDF link it is mounted on)."""
    mount: Pose2D = field(default_factory=lambda: Pose2D(0.0, 0.0, 0.0))
    """Pose of the scanner frame in the robot's base frame (x, y in m, theta in rad)."""

    def __post_init__(self) -> None:
        ranges = np.asarray(self.ranges, dtype=np.float64)
        if ranges.ndim != 1:
            raise ValueError(f"a scan's ranges must be one-dimensional, not shape {ranges.shape}")
        if np.isnan(ranges).any():
            raise ValueError("a scan's ranges must not be nan (a ray without a return is inf)")
        if not self.angle_increment or not math.isfinite(self.angle_increment):
            raise ValueError(
                f"a scan's angle_increment must be finite and non-zero, not {self.angle_increment}"
            )
        if not 0.0 <= self.range_min < self.range_max:
            raise ValueError(
                f"a scan's ranges need 0 <= range_min < range_max, not {self.range_min} and {self.range_max}"
            )
        if self.intensities is not None and np.shape(self.intensities) != ranges.shape:
            raise ValueError("a scan's intensities must have one value per ray")
        object.__setattr__(self, "ranges", ranges)

    def but(self, stamp: float, ranges: FloatArray) -> Scan:
        """This scan with another ``stamp`` and ``ranges``, not checked again: for a producer of
        many scans alike whose ranges are one-dimensional float64 without nan (the simulated
        scanner's revolutions)."""
        scan = object.__new__(Scan)
        scan.__dict__.update(self.__dict__, stamp=stamp, ranges=ranges)
        return scan

    def __len__(self) -> int:
        return int(self.ranges.shape[0])

    @property
    def angles(self) -> FloatArray:
        """Direction of every ray in the scanner frame, rad."""
        return self.angle_min + self.angle_increment * np.arange(len(self), dtype=np.float64)

    @property
    def valid(self) -> NDArray[np.bool_]:
        """The rays with a return within [range_min, range_max]."""
        r = self.ranges
        return np.isfinite(r) & (r >= self.range_min) & (r <= self.range_max)

    def points(self, frame: str = "base") -> FloatArray:
        """The valid returns as an (n, 2) array of points, in the scanner frame or the robot's base frame."""
        if frame not in ("scanner", "base"):
            raise ValueError(f"frame must be 'scanner' or 'base', not {frame!r}")
        ok = self.valid
        a = self.angles[ok]
        r = self.ranges[ok]
        pts = np.column_stack((r * np.cos(a), r * np.sin(a)))
        if frame == "base":
            m = self.mount
            c, s = math.cos(m.theta), math.sin(m.theta)
            pts = pts @ np.array([[c, s], [-s, c]]) + np.array([m.x, m.y])
        return pts
