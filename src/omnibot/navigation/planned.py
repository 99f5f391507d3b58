"""A plan as a path to follow: the planner's waypoints (:class:`~omnibot.mapping.PlannedPath`) turned
into the project's :class:`~omnibot.control.Path` with headings (:func:`planned_path`), moved between
frames (:func:`transformed`), and the obstacles met marked on the map (:func:`mark`).
"""

from __future__ import annotations

import itertools
import math
from typing import Literal

import numpy as np

from omnibot.control import Path, resample, wrap
from omnibot.mapping import OCCUPIED, OccupancyGrid, PlannedPath
from omnibot.motion import Pose2D
from omnibot.navigation.goal import FloatArray

SPACING = 0.05
"""m between the path's points (the tracker's profile interpolates between them)."""
SHORTEST = 0.01
"""m: a shorter leg (a turn in place, a last correction) goes this far out along the heading and back."""
TRAVEL_LEAST = 0.3
"""m: a shorter leg (a correction) turns towards the goal's heading on the way even in ``travel``."""


def transformed(path: Path, t: Pose2D) -> Path:
    """``path`` with every pose moved by ``t`` (``t`` o pose)."""
    c, s = math.cos(t.theta), math.sin(t.theta)
    return Path(
        t.x + c * path.x - s * path.y, t.y + s * path.x + c * path.y, path.theta + t.theta, path.t, path.v
    )


def planned_path(plan: PlannedPath, start_theta: float, heading: Literal["travel", "goal"]) -> Path:
    """The project's path type for a plan: ``goal`` turns the heading from ``start_theta`` to the
    goal's in proportion to the distance covered; ``travel`` faces each straight run (turning in
    place before it) and turns in place to the goal's heading at the end. Resampled every
    :data:`SPACING` m (corners and turns in place kept). A plan shorter than :data:`SHORTEST` (a
    turn in place) goes that far out along the heading and back, turning on the way."""
    pts = plan.waypoints
    goal_theta = start_theta + wrap(plan.theta - start_theta)
    if plan.length < SHORTEST:  # the tracker needs a length: out along the heading and back
        ahead = pts[0] + SHORTEST * np.array([math.cos(start_theta), math.sin(start_theta)])
        pts = np.vstack([pts[:1], ahead, pts[-1:]])
        heading = "goal"
    if heading == "goal" or plan.length < TRAVEL_LEAST:
        s = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))))
        theta = start_theta + (goal_theta - start_theta) * s / s[-1]
        return resample(Path(pts[:, 0].copy(), pts[:, 1].copy(), theta), SPACING)
    xs, ys, th = [float(pts[0, 0])], [float(pts[0, 1])], [start_theta]
    current = start_theta
    for a, b in itertools.pairwise(pts):
        if math.hypot(float(b[0] - a[0]), float(b[1] - a[1])) < 1e-9:
            continue
        course = math.atan2(float(b[1] - a[1]), float(b[0] - a[0]))
        current = current + wrap(course - current)
        xs.append(float(a[0]))  # turn in place to face the run
        ys.append(float(a[1]))
        th.append(current)
        xs.append(float(b[0]))
        ys.append(float(b[1]))
        th.append(current)
    xs.append(float(pts[-1, 0]))
    ys.append(float(pts[-1, 1]))
    th.append(current + wrap(plan.theta - current))
    return resample(Path(np.array(xs), np.array(ys), np.array(th)), SPACING)


def mark(grid: OccupancyGrid, points: FloatArray) -> OccupancyGrid:
    """A copy of ``grid`` with the cells holding ``points`` (map frame, on the grid) occupied."""
    data = grid.data.copy()
    cells = grid.world_to_cell(points)
    cells = cells[grid.inside(cells)]
    data[cells[:, 0], cells[:, 1]] = OCCUPIED
    return OccupancyGrid(data, grid.resolution, grid.origin, grid.frame)
