"""Exploring: drive to the edges of the known map (frontiers) until the reachable space is mapped.

::

    the SLAM's map so far, made afresh before every choice
      -> frontiers: free cells next to unknown ones, grouped (8-connected), groups of at least
         ``min_cells``; each group's goal is the cell where the robot can stand nearest its centre,
         within ``reach`` of it: clear of the walls and of the unknown if there is one, else clear
         of the walls alone (a room seen through a doorway: the unknown beyond may be floor)
      -> the nearest goals by straight line, each planned to: through known free space, else
         through unknown cells as if free (optimistic; such a way counts 1.5 times its length);
         a goal with no way even so is unreachable on the map as it is (re-checked on every map)
      -> goto's go_to to the goal with the shortest way (loose tolerances: it only has to get there
         to see more); the scanner watches the way and an obstacle the map did not have ends the
         leg, so the next choice is made on the map that now has it (re-planning as the map fills)
      -> again, until no frontier is left (explored), the time limit passes, or no frontier left
         has a way to it (unreachable, each one's reason said)

Walls the scans saw that the map does not mark (returns beyond the hit range, or a wall seen
edge-on: :func:`~omnibot.navigation.frontiers.unmarked_walls`) are gone to as frontiers are, to a
place within the hit range that sees them (:func:`~omnibot.navigation.frontiers.wall_goals`; the
map's frontiers, their goals and the choice among them are :mod:`omnibot.navigation.frontiers`);
each is gone to once. When no frontier is left with a way to it, the robot goes where it sees the
most of the surface the map still lacks, square on and within the hit range
(:mod:`omnibot.navigation.views`: a face seen only edge-on or from afar), until no
place sees enough of it; the cells a view was chosen for are not chosen for again.

A goal reached is not gone to again, even if it is still a frontier (behind furniture, beyond the
scanner's range). One the robot set out for and did not reach (stalled, blocked, timed out) is tried
again on the next map, and given up after :data:`ATTEMPTS` tries, the last reason said. Where the
map has the robot overlapping a wall (noise, or a pose a little off), no path can leave it: the
robot first backs off to the nearest spot clear by its radius and margin (the cells it stands on
count as free: it is there). The map and the pose come from the caller: a
:class:`~omnibot.mapping.session.MappingSink` on the same runtime.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import PlanningError
from omnibot.mapping import CostMap, OccupancyGrid, check_start, inflate
from omnibot.motion import Pose2D
from omnibot.navigation.frontiers import (
    FREE,
    choose_frontier,
    choose_view,
    frontiers,
    wall_goals,
)
from omnibot.navigation.goal import GotoOptions, GotoResult, PoseProvider
from omnibot.navigation.goto import go_to
from omnibot.navigation.views import VIEW_RANGE, View, stands, unseen_surface, views
from omnibot.robot import RobotDescription
from omnibot.runtime import Runtime

FloatArray = NDArray[np.float64]
Outcome = Literal["explored", "time limit", "unreachable", "stuck"]

FORGET = 0.3
"""m: a frontier goal this close to one reached or given up is not chosen again."""
ATTEMPTS = 3
"""Tries at a frontier goal that end without reaching it before it is given up."""
SCAN_STEP = 0.04
"""m the robot moves at most per revolution of its scanner while exploring (0.4 m/s at 10 Hz):
scans close together match well and a revolution's motion distortion stays small."""
BACK_OFF = 1.0
"""m within which the robot looks for a clear spot when the map has it overlapping a wall."""
BACK_OFFS = 2
"""Back-offs in a row that leave the robot still overlapping a wall before exploring ends (stuck)."""
GOTO = GotoOptions(
    tolerance=0.25,
    heading_tolerance=math.pi,
    corrections=0,
    max_replans=0,
    heading="goal",
    aim=1.0,
)
"""How each frontier is gone to: near enough to see past it, any heading; what the scanner sees
that the map so far does not have ends the leg (no re-plan on a marked copy of the map: the next
choice is made on the SLAM's map, which has it)."""
VIEW_TOLERANCE = 0.1
"""m within which a view goal is reached (its line of sight may pass a narrow gap)."""
DWELL = 1.0
"""s the robot stays at a view goal it reached, scanning (ten revolutions at 10 Hz: a surface
grazed by many rays before needs many hits to be marked; :data:`~omnibot.navigation.views.INCIDENCE`)."""


@dataclass
class ExploreResult:
    """What exploring did: why it ended, the frontiers visited and those given up."""

    outcome: Outcome
    visits: list[GotoResult] = field(default_factory=list)
    done: list[tuple[float, float]] = field(default_factory=list)
    """Frontier goals reached or given up: not chosen again."""
    failed: list[tuple[float, float]] = field(default_factory=list)
    """Frontier goals given up after :data:`ATTEMPTS` tries."""
    unreachable: list[tuple[float, float, str]] = field(default_factory=list)
    """Frontier goals left with no way to them at the end, and why (the planner's line)."""
    reason: str = ""
    """Why exploring ended ``stuck``."""
    duration: float = 0.0
    views: int = 0
    """Legs to a view goal (:mod:`omnibot.navigation.views`), reached or not."""

    @property
    def reached(self) -> int:
        """Goals reached (frontiers, unmarked walls and views)."""
        return sum(1 for v in self.visits if v.arrived)

    def summary(self) -> str:
        """One line for a terminal."""
        why = {
            "explored": "no frontier left: the reachable space is mapped",
            "time limit": "the time limit passed",
            "unreachable": f"the {len(self.unreachable)} frontier(s) left have no way to them",
            "stuck": f"stuck: {self.reason}",
        }[self.outcome]
        return (
            f"{why} ({self.reached} goals reached, {self.views} of the legs to views, "
            f"{len(self.failed)} given up, {self.duration:.0f} s)"
        )


def explore(
    runtime: Runtime,
    robot: RobotDescription,
    grid_now: Callable[[], OccupancyGrid],
    pose: PoseProvider,
    *,
    scan: Callable[[], FloatArray | None] | None = None,
    returns: Callable[[OccupancyGrid], NDArray[np.integer]] | None = None,
    time_limit: float = 300.0,
    options: GotoOptions = GOTO,
    view_range: float | None = VIEW_RANGE,
    say: Callable[[str], object] = lambda text: None,
) -> ExploreResult:
    """Explore through a running ``runtime`` (see the module docstring): ``grid_now()`` is the map so
    far, ``pose()`` the robot's pose in it and ``scan()`` the latest scan's points in it (the
    obstacle watch); ``returns(grid)`` the scans' returns per cell of that map (at every range):
    walls they saw that the map does not mark are gone to as frontiers are (:func:`wall_goals`);
    at most ``time_limit`` s of the link's clock. ``options.speed`` None: the
    :func:`exploring_speed` of the robot. ``view_range``: how far a view goal sees the surface the
    map lacks (within the scanner's hit range; None: no view goals)."""
    if options.speed is None:
        options = replace(options, speed=exploring_speed(robot))
    exploration = _Exploration(runtime, robot, grid_now, pose, scan, returns, options, say)
    exploration.view_range = view_range
    return exploration.run(time_limit)


class _Exploration:
    """One run of :func:`explore`: its result so far and what it tried, said and went to."""

    def __init__(
        self,
        runtime: Runtime,
        robot: RobotDescription,
        grid_now: Callable[[], OccupancyGrid],
        pose: PoseProvider,
        scan: Callable[[], FloatArray | None] | None,
        returns: Callable[[OccupancyGrid], NDArray[np.integer]] | None,
        options: GotoOptions,
        say: Callable[[str], object],
    ) -> None:
        self.runtime, self.robot, self.options, self.say = runtime, robot, options, say
        self.grid_now, self.pose, self.scan, self.returns = grid_now, pose, scan, returns
        self.radius = robot.footprint.bounding_radius
        self.result = ExploreResult("explored")
        self.tries: list[list[float]] = []  # [x, y, tries] of goals set out for and not reached
        self.told: list[tuple[float, float]] = []  # unreachable goals already said
        self.walls_seen: list[tuple[float, float]] = []  # the middles of unmarked walls gone to
        self.viewed = np.zeros((0, 2))  # unseen cells a view was chosen for: not chosen for again
        self.view_range: float | None = VIEW_RANGE
        self.backed_off = 0

    def run(self, time_limit: float) -> ExploreResult:
        """Leg after leg until exploring ends, within ``time_limit`` s of the link's clock."""
        clock = self.runtime.client.clock
        t0 = clock.now()
        while not self._leg(time_limit - (clock.now() - t0)):
            pass
        self.result.duration = clock.now() - t0
        return self.result

    def _leg(self, left: float) -> bool:
        """Choose a goal and go to it (or wait for a pose, or back off); True when exploring is over
        (``result.outcome`` says why). ``left``: the time left, s."""
        if left <= 0:
            self.result.outcome = "time limit"
            return True
        here = self.pose()
        if here is None:
            self.runtime.step()
            self.runtime.client.sleep(self.runtime.period)
            return False
        grid = self.grid_now()
        margin = self.options.margin
        cmap = inflate(grid, robot_radius=self.radius, margin=margin)
        optimistic = inflate(grid, robot_radius=self.radius, margin=margin, allow_unknown=True)
        hemmed = self._hemmed_in(grid, optimistic, here, left)
        if hemmed is not None:
            return hemmed
        goals, walls = self._goals(grid, cmap, optimistic)
        choice, unreachable = choose_frontier(cmap, optimistic, here, goals)
        self._tell_unreachable(unreachable)
        if choice is not None:
            self._visit(grid, here, choice, walls, len(goals), left)
            return False
        view = self._view(grid, cmap, here)
        if view is not None:
            self._look(grid, here, view, left)
            return False
        self.result.outcome = "unreachable" if goals else "explored"
        self.result.unreachable = unreachable
        return True

    def _hemmed_in(self, grid: OccupancyGrid, optimistic: CostMap, here: Pose2D, left: float) -> bool | None:
        """None when a way leaves where the robot stands; else it backs off (False: go on) up to
        :data:`BACK_OFFS` times in a row, then gives up (True: ``stuck``)."""
        try:
            check_start(optimistic, here)
        except PlanningError as exc:
            if self.backed_off >= BACK_OFFS:
                self.result.outcome, self.result.reason = "stuck", str(exc)
                return True
            self.backed_off += 1
            self.say(f"no way leaves where the robot stands ({exc}): backing off to clear space")
            _back_off(self.runtime, self.robot, grid, optimistic, here, self.options, left, self.pose)
            return False
        self.backed_off = 0
        return None

    def _goals(
        self, grid: OccupancyGrid, cmap: CostMap, optimistic: CostMap
    ) -> tuple[list[tuple[float, float]], dict[tuple[float, float], tuple[float, float]]]:
        """The goals not yet done: the frontiers' and the unmarked walls' not yet gone to (each of
        those by its middle: a wall gone to once is not gone to again)."""
        done = self.result.done
        goals = [
            f.goal
            for f in frontiers(grid, cmap, optimistic)
            if f.goal is not None and not _near(f.goal, done)
        ]
        walls = {}
        if self.returns is not None:
            walls = {
                g: c
                for g, c in wall_goals(grid, cmap, self.returns(grid))
                if not _near(g, done) and not _near(c, self.walls_seen)
            }
            goals += list(walls)
        return goals, walls

    def _view(self, grid: OccupancyGrid, cmap: CostMap, here: Pose2D) -> tuple[View, bool] | None:
        """The view goal to go to next and whether its way needs the radius alone
        (:func:`choose_view`); None: none left (or none wanted)."""
        if self.view_range is None:
            return None
        res = grid.resolution
        returns = None if self.returns is None else self.returns(grid)
        surface = unseen_surface(grid, returns).without(self.viewed, 0.75 * res)
        tight = inflate(grid, robot_radius=self.radius, margin=0.0)
        places = stands(grid, cmap, (here.x, here.y), way=tight)
        return choose_view(cmap, here, views(grid, surface, places, view_range=self.view_range), tight=tight)

    def _look(self, grid: OccupancyGrid, here: Pose2D, choice: tuple[View, bool], left: float) -> None:
        """Go to the view's stand (by a way clear by the radius alone if ``choice`` says so); its
        cells are not chosen for again, whether it got there or not (from the nearest place it could
        reach they may be as hidden); there, it scans for :data:`DWELL` s."""
        view, narrow = choice
        gx, gy = view.stand
        self.say(f"to a view of {view.size} cells the map lacks, from ({gx:.2f}, {gy:.2f})")
        margin = 0.0 if narrow else self.options.margin
        how = replace(self.options, tolerance=VIEW_TOLERANCE, timeout=left, margin=margin)
        visit = go_to(
            self.runtime, self.robot, grid, Pose2D(gx, gy, here.theta), how, pose=self.pose, scan=self.scan
        )
        self.result.visits.append(visit)
        self.result.views += 1
        self.viewed = np.concatenate((self.viewed, view.seen))
        if not visit.arrived:
            self.say(f"view at ({gx:.2f}, {gy:.2f}) not reached: {visit.reason or visit.outcome}")
            return
        for _ in range(round(DWELL / self.runtime.period)):  # scanning where it stands
            self.runtime.step()
            self.runtime.client.sleep(self.runtime.period)

    def _tell_unreachable(self, unreachable: list[tuple[float, float, str]]) -> None:
        """Say each unreachable goal once."""
        for x, y, why in unreachable:
            if not _near((x, y), self.told):
                self.told.append((x, y))
                self.say(f"frontier at ({x:.2f}, {y:.2f}) has no way to it now: {why}")

    def _visit(
        self,
        grid: OccupancyGrid,
        here: Pose2D,
        choice: tuple[tuple[float, float], bool],
        walls: dict[tuple[float, float], tuple[float, float]],
        n_goals: int,
        left: float,
    ) -> None:
        """Go to the chosen goal and keep the score: done when reached, else one more try of
        :data:`ATTEMPTS` before it is given up."""
        (gx, gy), through = choice
        goal = Pose2D(gx, gy, here.theta)
        how = replace(self.options, allow_unknown=through, timeout=left)
        way = " (through unknown space)" if through else ""
        what = "a wall the map does not mark, from" if (gx, gy) in walls else "the frontier at"
        self.say(f"to {what} ({gx:.2f}, {gy:.2f}){way}, {n_goals} left")
        visit = go_to(self.runtime, self.robot, grid, goal, how, pose=self.pose, scan=self.scan)
        self.result.visits.append(visit)
        if (gx, gy) in walls:
            self.walls_seen.append(walls[(gx, gy)])  # reached or not: another place may not see it either
        if visit.arrived:
            self.result.done.append((gx, gy))
            return
        n = _count_try(self.tries, (gx, gy))
        if n < ATTEMPTS:
            self.say(
                f"frontier at ({gx:.2f}, {gy:.2f}) not reached ({visit.reason}): tried {n} of {ATTEMPTS}"
            )
            return
        self.result.failed.append((gx, gy))
        self.result.done.append((gx, gy))
        self.say(
            f"frontier at ({gx:.2f}, {gy:.2f}) given up after {n} tries: {visit.reason or visit.outcome}"
        )


def exploring_speed(robot: RobotDescription) -> float:
    """The speed cap for exploring, m/s: :data:`SCAN_STEP` per revolution of the robot's scanner
    (its rate; 10 Hz without one), within the robot's own limit."""
    rate = robot.scanner.rate_hz if robot.scanner is not None else 10.0
    return min(robot.limits.speed_max, SCAN_STEP * rate)


def _near(p: tuple[float, float], places: list[tuple[float, float]]) -> bool:
    return any(math.hypot(p[0] - x, p[1] - y) <= FORGET for x, y in places)


def _count_try(tries: list[list[float]], p: tuple[float, float]) -> int:
    """One more try at the goal ``p`` (or one within :data:`FORGET` of it); the tries so far."""
    for t in tries:
        if math.hypot(p[0] - t[0], p[1] - t[1]) <= FORGET:
            t[2] += 1
            return int(t[2])
    tries.append([p[0], p[1], 1.0])
    return 1


def _back_off(
    runtime: Runtime,
    robot: RobotDescription,
    grid: OccupancyGrid,
    optimistic: CostMap,
    here: Pose2D,
    options: GotoOptions,
    left: float,
    pose: PoseProvider,
) -> GotoResult | None:
    """Go to the nearest spot within :data:`BACK_OFF` clear of the walls by the robot's radius and
    margin, on the map with the cells the robot stands on free, the way planned clear by the radius
    alone (it may lead out of a gap narrower than the margin allows); None: no such spot."""
    known_free = grid.free(FREE)
    cells = np.argwhere(~optimistic.blocked & known_free)
    if len(cells) == 0:
        return None
    xy = grid.cell_to_world(cells)
    d = np.hypot(xy[:, 0] - here.x, xy[:, 1] - here.y)
    best = int(np.argmin(d))
    if d[best] > BACK_OFF:
        return None
    res = grid.resolution
    rc = np.argwhere(np.ones(grid.shape, dtype=bool))
    centres = grid.cell_to_world(rc)
    under = np.hypot(centres[:, 0] - here.x, centres[:, 1] - here.y) <= optimistic.robot_radius + 2 * res
    data = grid.data.copy()
    data[rc[under, 0], rc[under, 1]] = 0
    cleared = OccupancyGrid(data, grid.resolution, grid.origin, grid.frame)
    target = Pose2D(float(xy[best, 0]), float(xy[best, 1]), here.theta)
    how = replace(
        options,
        tolerance=min(options.tolerance, 0.03),
        margin=0.0,
        allow_unknown=True,
        timeout=min(left, 10.0),
    )
    return go_to(runtime, robot, cleared, target, how, pose=pose)
