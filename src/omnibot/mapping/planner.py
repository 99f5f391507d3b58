"""Planning a collision-free path for a holonomic base on an occupancy grid.

::

    OccupancyGrid --inflate()--> CostMap (costmap.py: clearance, blocked cells, a wall cost)
      --plan_path(start, goal)--> PlannedPath (map-frame waypoints, the goal's heading)

:func:`plan_path` checks the ends (ends.py: on the map, clear of the walls; a start inside the
margin climbs the clearance out of it first), asks A* whether there is a way at all, then plans
with one of two planners (``planner=``):

* ``"grid"`` (the default): A* on the 8-connected cells, then line-of-sight shortcutting
  (any-angle; astar.py). Deterministic.
* ``"rrtstar"``, ``"prmstar"``, ``"bitstar"``: OMPL's sampling planners in R2 (sampling.py), for
  ``time_limit`` s, seeded (``seed``) for repeatable runs.

The robot is a disc (its footprint's bounding radius), so any heading fits wherever its centre
may go. Errors (:mod:`omnibot.errors`): :class:`~omnibot.errors.OffMapError`,
:class:`~omnibot.errors.BlockedError` (the goal, or the start, in a wall, in unknown space or too
near a wall), :class:`~omnibot.errors.NoPathError`, each one line in the map frame's metres.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import ConfigError, NoPathError
from omnibot.mapping.astar import astar, shortcut
from omnibot.mapping.cellwalk import line_max
from omnibot.mapping.costmap import MARGIN, CostMap, inflate
from omnibot.mapping.ends import check_end, escape, why_no_path, xy
from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.sampling import ompl_plan
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]

Planner = Literal["grid", "rrtstar", "prmstar", "bitstar"]
PLANNERS: tuple[str, ...] = ("grid", "rrtstar", "prmstar", "bitstar")
COST_WEIGHT = 3.0
"""How much a step at the highest cost counts beyond its length: 1 + weight x cost per metre."""


@dataclass(frozen=True)
class PlannedPath:
    """A planned path: map-frame ``waypoints`` (n, 2) from the start's position to the goal's, the
    goal's heading, and what the plan measured."""

    waypoints: FloatArray
    goal: Pose2D
    planner: str
    clearance: float
    """The least clearance along the path (m; cells the straight runs cross)."""
    seconds: float
    """Time the planning took (wall clock), s."""

    @property
    def length(self) -> float:
        """Length of the polyline, m."""
        return float(np.hypot(*np.diff(self.waypoints, axis=0).T).sum())

    @property
    def theta(self) -> float:
        """The heading to arrive with (the goal's), rad."""
        return self.goal.theta


def plan_path(
    grid: OccupancyGrid | CostMap,
    start: Pose2D,
    goal: Pose2D,
    *,
    robot_radius: float | None = None,
    margin: float = MARGIN,
    allow_unknown: bool = False,
    planner: Planner = "grid",
    weight: float = COST_WEIGHT,
    time_limit: float = 0.5,
    seed: int = 0,
) -> PlannedPath:
    """A collision-free path from ``start`` to ``goal`` (map frame) on ``grid`` for a disc robot of
    ``robot_radius`` (needed with a grid; a :class:`CostMap` carries its own) kept ``margin`` m
    further from walls; unknown cells are walls unless ``allow_unknown``. ``planner`` and its
    options: see the module. Raises OffMapError, BlockedError or NoPathError."""
    if planner not in PLANNERS:
        raise ConfigError(f"unknown planner '{planner}' (choose one of {', '.join(PLANNERS)})")
    t0 = time.perf_counter()
    if isinstance(grid, CostMap):
        cmap = grid
    else:
        if robot_radius is None:
            raise ConfigError("plan_path needs the robot's radius to plan on an occupancy grid")
        cmap = inflate(grid, robot_radius=robot_radius, margin=margin, allow_unknown=allow_unknown)
    for name, pose in (("start", start), ("goal", goal)):
        if not all(math.isfinite(v) for v in (pose.x, pose.y, pose.theta)):
            raise ConfigError(f"the {name} pose must be finite numbers, not {pose}")
    s_cell = check_end(cmap, start, "start")
    g_cell = check_end(cmap, goal, "goal")
    out = escape(cmap, s_cell)
    climb = cmap.grid.cell_to_world(out[1:]) if len(out) > 1 else np.zeros((0, 2))
    head = np.vstack([[(start.x, start.y)], climb])
    cells = astar(~cmap.blocked, cmap.cost, out[-1], g_cell, weight)
    if cells is None:
        raise NoPathError(f"no path from {xy(start)} to {xy(goal)}: {why_no_path(cmap)}")
    if planner == "grid":
        tail = shortcut(cmap, cells, (float(head[-1, 0]), float(head[-1, 1])), (goal.x, goal.y), weight)
    else:
        tail = ompl_plan(
            cmap, (float(head[-1, 0]), float(head[-1, 1])), start, goal, planner, time_limit, seed
        )
    points = np.vstack([head[:-1], tail])
    clearance = min(
        (_segment_clearance(cmap, a, b) for a, b in itertools.pairwise(points)),
        default=cmap.clearance_at(goal.x, goal.y),
    )
    return PlannedPath(points, goal, planner, clearance, time.perf_counter() - t0)


def _segment_clearance(cmap: CostMap, a: FloatArray, b: FloatArray) -> float:
    """The least clearance of the cells a straight run crosses, m."""
    la, lb = cmap.local((float(a[0]), float(a[1]))), cmap.local((float(b[0]), float(b[1])))
    worst = line_max(-cmap.clearance, la[0], la[1], lb[0], lb[1])
    return float(-worst) if math.isfinite(worst) else 0.0
