"""The obstacle watch of a goto leg: sonar ranges and scan points the map does not explain, in the
robot's corridor on the path ahead, end the leg (:class:`ObstacleWatch`, a runtime sink).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from omnibot.control import Path
from omnibot.mapping import CostMap, compose
from omnibot.motion import Pose2D
from omnibot.navigation.goal import FloatArray, PoseProvider, ScanSource
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle

EXPLAINED = 0.10
"""m: a range reading this close to a wall of the map is that wall."""
ARC_STEP = math.radians(2.5)
"""rad between the points a sonar reading marks across its cone."""
REACTION = 0.2
"""s from a scan point or a range reading to the stop acting: a 10 Hz scan's period, the runtime's
cycle and the link."""


def stopping_reach(robot: RobotDescription, speed: float, corridor: float) -> float:
    """m of path ahead of the robot's centre a watch must see so that the robot, at ``speed``, stops
    short of what it sees: the footprint and margin ahead of the centre (``corridor``), the travel
    until the stop acts (:data:`REACTION`) and the braking distance at the description's stop
    deceleration (the bound the firmware's sonar guard sizes its stop distance with, docs/safety.md)."""
    return corridor + speed * REACTION + speed * speed / (2.0 * robot.stop_deceleration)


class ObstacleWatch:
    """A sink: ends ``leg`` when a sonar reading or a scan point that ``cmap``'s walls do not
    explain (none within :data:`EXPLAINED`) lies in the robot's corridor (radius + margin either
    side) on the next ``lookahead`` m of ``path`` (map frame), or farther where the path's planned
    ``speed_at`` its arc length needs more room to stop (:func:`stopping_reach`); :attr:`points` are
    then what to mark."""

    def __init__(
        self,
        robot: RobotDescription,
        cmap: CostMap,
        path: Path,
        pose: PoseProvider,
        stop: Callable[[str], object],
        *,
        lookahead: float,
        scan: ScanSource | None = None,
        speed_at: Callable[[float], float] | None = None,
    ) -> None:
        self.robot = robot
        self.cmap = cmap
        self.path = path
        self.pose = pose
        self.stop = stop
        self.lookahead = lookahead
        self.scan = scan
        self.speed_at = speed_at
        self.points: FloatArray | None = None
        """The unexplained points that ended the leg (None: none did)."""
        self._s = 0.0

    def __call__(self, cycle: Cycle) -> None:
        """Look at this cycle's sonar ranges and the latest scan."""
        if self.points is not None:
            return
        pose = self.pose()
        if pose is None:
            return
        if len(self.path) > 1:
            self._s = self.path.project_near(pose.x, pose.y, self._s, behind=0.1, ahead=0.5).s
        clouds = [(self._sonar_points(pose, r), True) for r in self._ranges(cycle)]
        if self.scan is not None:
            scan = self.scan()
            if scan is not None and len(scan):
                clouds.append((np.asarray(scan, dtype=np.float64).reshape(-1, 2), False))
        for cloud, sonar in clouds:
            new = self._unexplained(cloud, sonar=sonar)
            if new is not None and self._ahead(new):
                self.points = new
                x, y = np.mean(new, axis=0)
                self.stop(f"an obstacle the map does not have at ({x:.2f}, {y:.2f})")
                return

    def _ranges(self, cycle: Cycle) -> list[tuple[int, float]]:
        """(sonar index, range) of the newest telemetry sample's readings within range."""
        for tel in reversed(cycle.telemetry):
            if tel.ranges is None:
                continue
            out = []
            for k, r in enumerate(tel.ranges):
                if r is None or k >= len(self.robot.sonars):
                    continue
                sonar = self.robot.sonars[k]
                if sonar.min_range < r < sonar.max_range - 0.05:
                    out.append((k, r))
            return out
        return []

    def _sonar_points(self, pose: Pose2D, reading: tuple[int, float]) -> FloatArray:
        """The arc of points a reading says something lies on (map frame)."""
        sonar = self.robot.sonars[reading[0]]
        origin = compose(pose, Pose2D(sonar.x, sonar.y, sonar.angle))
        half = 0.5 * math.radians(sonar.cone_deg)
        n = max(2, math.ceil(2 * half / ARC_STEP) + 1)
        ang = origin.theta + np.linspace(-half, half, n)
        r = reading[1]
        return np.column_stack((origin.x + r * np.cos(ang), origin.y + r * np.sin(ang)))

    def _unexplained(self, cloud: FloatArray, *, sonar: bool) -> FloatArray | None:
        """The points no wall explains: for a sonar's arc, all of it when no point of it lies near
        a wall (the echo came from the nearest thing in the cone), else None; for a scan, each
        point on its own."""
        near = self.cmap.clearances(cloud) < EXPLAINED
        if sonar:
            return None if near.any() else cloud
        out = cloud[~near]
        return out if len(out) else None

    def _ahead(self, points: FloatArray) -> bool:
        """Whether any point lies in the corridor of the next ``lookahead`` m of the path."""
        if len(self.path) < 2:
            return False
        dist, s = self.path.nearest(points)
        reach = self.lookahead
        if self.speed_at is not None:
            reach = max(reach, stopping_reach(self.robot, self.speed_at(self._s), self.cmap.inflated))
        ahead = (s >= self._s - 0.05) & (s <= self._s + reach)
        return bool(np.any(ahead & (dist < self.cmap.inflated)))
