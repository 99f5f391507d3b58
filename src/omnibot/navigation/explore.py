"""Exploring: drive to the edges of the known map (frontiers) until the reachable space is mapped.

::

    the SLAM's map so far (unknown cells are walls to the planner)
      -> frontiers: free cells next to unknown ones, grouped (8-connected), groups of at least
         ``min_cells``; each group's goal is the cell where the robot can stand nearest its centre,
         within ``reach`` of it
      -> the goal with the shortest planned path (grid planner, a few nearest tried)
      -> goto's go_to on that map (loose tolerances: it only has to get there to see more)
      -> the map grows; again, until no frontier is left (explored), the time limit passes, or
         every frontier left has failed (unreachable)

A goal is gone to once: one the robot could not reach (no path, blocked, stalled) is given up, and
one it reached that is still a frontier (behind furniture, beyond the scanner's range) is left. The map and the
pose come from the caller: a :class:`~omnibot.mapping.session.MappingSink` on the same runtime.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from omnibot.errors import PlanningError
from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.planner import CostMap, inflate, plan_path
from omnibot.motion import Pose2D
from omnibot.navigation.goto import GotoOptions, GotoResult, PoseProvider, go_to
from omnibot.robot.description import RobotDescription
from omnibot.runtime.runtime import Runtime

FloatArray = NDArray[np.float64]
Outcome = Literal["explored", "time limit", "unreachable"]

REACH = 0.6
"""m from a frontier's centre within which its goal is sought."""
MIN_CELLS = 6
"""Frontier cells a group needs to be worth a visit (one unknown cell in the open makes 4)."""
FREE = 49
"""Known cells below even odds of being occupied count as free here (one pass of a ray leaves a
cell at 40: map_server's 25 would need several before a frontier appears)."""
CANDIDATES = 4
"""Nearest frontier goals planned to before choosing the shortest way."""
FORGET = 0.3
"""m: a frontier goal this close to one that failed is not tried again."""
GOTO = GotoOptions(
    tolerance=0.25,
    heading_tolerance=math.pi,
    corrections=0,
    max_replans=3,
    heading="goal",
    aim=1.0,
)
"""How each frontier is gone to: near enough to see past it, any heading; what the scanner sees
that the map so far does not have stops the robot and is planned around. When no frontier can be
reached through known free space, the way is planned through unknown cells as if free (a doorway
half seen is a way on)."""


def frontier_goals(
    grid: OccupancyGrid, cmap: CostMap, *, min_cells: int = MIN_CELLS, reach: float = REACH
) -> list[tuple[float, float, int]]:
    """(x, y, size) of each frontier group's goal (map frame, m) and its size in cells, largest first."""
    known_free = grid.free(FREE)
    unknown = grid.data < 0
    near_unknown = ndimage.binary_dilation(unknown, structure=np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]]))
    frontier = known_free & near_unknown
    labels, count = ndimage.label(frontier, structure=np.ones((3, 3), dtype=int))
    standable = ~cmap.blocked & known_free
    stand_rc = np.argwhere(standable)
    if count == 0 or len(stand_rc) == 0:
        return []
    stand_xy = grid.cell_to_world(stand_rc)
    goals: list[tuple[float, float, int]] = []
    for k in range(1, count + 1):
        cells = np.argwhere(labels == k)
        if len(cells) < min_cells:
            continue
        centre = grid.cell_to_world(cells).mean(axis=0)
        d = np.hypot(*(stand_xy - centre).T)
        best = int(np.argmin(d))
        if d[best] <= reach:
            goals.append((float(stand_xy[best, 0]), float(stand_xy[best, 1]), len(cells)))
    goals.sort(key=lambda g: -g[2])
    return goals


@dataclass
class ExploreResult:
    """What exploring did: why it ended, the frontiers visited and those given up."""

    outcome: Outcome
    visits: list[GotoResult] = field(default_factory=list)
    done: list[tuple[float, float]] = field(default_factory=list)
    """Frontier goals gone to or given up: not chosen again."""
    failed: list[tuple[float, float]] = field(default_factory=list)
    duration: float = 0.0

    @property
    def reached(self) -> int:
        """Frontier goals reached."""
        return sum(1 for v in self.visits if v.arrived)

    def summary(self) -> str:
        """One line for a terminal."""
        why = {
            "explored": "no frontier left: the reachable space is mapped",
            "time limit": "the time limit passed",
            "unreachable": "the frontiers left could not be reached",
        }[self.outcome]
        return f"{why} ({self.reached} frontiers reached, {len(self.failed)} given up, {self.duration:.0f} s)"


def explore(
    runtime: Runtime,
    robot: RobotDescription,
    grid_now: Callable[[], OccupancyGrid],
    pose: PoseProvider,
    *,
    scan: Callable[[], FloatArray | None] | None = None,
    time_limit: float = 300.0,
    options: GotoOptions = GOTO,
    say: Callable[[str], object] = lambda text: None,
) -> ExploreResult:
    """Explore through a running ``runtime`` (see the module docstring): ``grid_now()`` is the map so
    far, ``pose()`` the robot's pose in it and ``scan()`` the latest scan's points in it (the
    obstacle watch); at most ``time_limit`` s of the link's clock."""
    clock = runtime.client.clock
    t0 = clock.now()
    radius = robot.footprint.bounding_radius
    result = ExploreResult("explored")
    while True:
        left = time_limit - (clock.now() - t0)
        if left <= 0:
            result.outcome = "time limit"
            break
        here = pose()
        if here is None:
            runtime.step()
            runtime.client.sleep(runtime.period)
            continue
        grid = grid_now()
        cmap = inflate(grid, robot_radius=radius, margin=options.margin)
        goals = [
            g
            for g in frontier_goals(grid, cmap)
            if all(math.hypot(g[0] - fx, g[1] - fy) > FORGET for fx, fy in result.done)
        ]
        if not goals:
            result.outcome = "unreachable" if result.failed else "explored"
            break
        how = options
        target = _nearest_by_path(cmap, here, goals)
        if target is None:  # no way through known free space: through the unknown, as if free
            how = replace(options, allow_unknown=True)
            optimistic = inflate(grid, robot_radius=radius, margin=options.margin, allow_unknown=True)
            target = _nearest_by_path(optimistic, here, goals)
        if target is None:
            unreachable = [(g[0], g[1]) for g in goals[:CANDIDATES]]
            result.failed.extend(unreachable)
            result.done.extend(unreachable)
            continue
        goal = Pose2D(target[0], target[1], here.theta)
        through = " (through unknown space)" if how.allow_unknown else ""
        say(f"to the frontier at ({goal.x:.2f}, {goal.y:.2f}){through}, {len(goals)} left")
        visit = go_to(runtime, robot, grid, goal, replace(how, timeout=left), pose=pose, scan=scan)
        result.visits.append(visit)
        # a frontier the robot stood at and still sees as one (behind furniture, past the range) is
        # not gone to again, nor one it could not reach
        result.done.append((goal.x, goal.y))
        if not visit.arrived:
            result.failed.append((goal.x, goal.y))
            say(f"frontier at ({goal.x:.2f}, {goal.y:.2f}) given up: {visit.reason or visit.outcome}")
    result.duration = clock.now() - t0
    return result


def _nearest_by_path(
    cmap: CostMap, here: Pose2D, goals: list[tuple[float, float, int]]
) -> tuple[float, float] | None:
    """The goal with the shortest planned way among the :data:`CANDIDATES` nearest (None: no way)."""
    near = sorted(goals, key=lambda g: math.hypot(g[0] - here.x, g[1] - here.y))[:CANDIDATES]
    best: tuple[float, tuple[float, float]] | None = None
    for gx, gy, _ in near:
        try:
            plan = plan_path(cmap, here, Pose2D(gx, gy, here.theta))
        except PlanningError:
            continue
        if best is None or plan.length < best[0]:
            best = (plan.length, (gx, gy))
    return None if best is None else best[1]
