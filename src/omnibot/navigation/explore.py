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
edge-on: :func:`unmarked_walls`) are gone to as frontiers are, to a place within the hit range
that sees them (:func:`wall_goals`); each is gone to once. When no frontier is left with a way to
it, the robot goes where it sees the most of the surface the map still lacks, square on and within
the hit range (:mod:`omnibot.navigation.views`: a face seen only edge-on or from afar), until no
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
from scipy import ndimage

from omnibot.errors import PlanningError
from omnibot.mapping import CostMap, OccupancyGrid, check_start, inflate, plan_path
from omnibot.motion import Pose2D
from omnibot.navigation.goal import GotoOptions, GotoResult, PoseProvider
from omnibot.navigation.goto import go_to
from omnibot.navigation.views import VIEW_RANGE, View, line_of_sight, stands, unseen_surface, views
from omnibot.robot import RobotDescription
from omnibot.runtime import Runtime

FloatArray = NDArray[np.float64]
Outcome = Literal["explored", "time limit", "unreachable", "stuck"]

REACH = 0.6
"""m from a frontier's centre within which its goal is sought."""
MIN_CELLS = 6
"""Frontier cells a group needs to be worth a visit (one unknown cell in the open makes 4)."""
FREE = 49
"""Known cells below even odds of being occupied count as free here (one pass of a ray leaves a
cell at 40: map_server's 25 would need several before a frontier appears)."""
CANDIDATES = 4
"""Nearest frontier goals with a way to them among which the shortest way is chosen."""
FORGET = 0.3
"""m: a frontier goal this close to one reached or given up is not chosen again."""
ATTEMPTS = 3
"""Tries at a frontier goal that end without reaching it before it is given up."""
UNKNOWN_PENALTY = 1.5
"""A way through unknown cells counts this many times its length when choosing (it may be walled)."""
STANDOFF = 0.1
"""m of clearance beyond the robot's radius and margin a frontier's goal keeps where there is room
(the map grows after the goal is chosen: a wall nearer than it seemed, thickened by noise)."""
SCAN_STEP = 0.04
"""m the robot moves at most per revolution of its scanner while exploring (0.4 m/s at 10 Hz):
scans close together match well and a revolution's motion distortion stays small."""
BACK_OFF = 1.0
"""m within which the robot looks for a clear spot when the map has it overlapping a wall."""
BACK_OFFS = 2
"""Back-offs in a row that leave the robot still overlapping a wall before exploring ends (stuck)."""
OCCUPIED = 65
"""Cells at or above this are walls the map has marked (map_server's occupied threshold)."""
WALL_RETURNS = 2
"""Returns in a cell the map does not mark (nor a neighbour) that make it a wall to see closer."""
WALL_CELLS = 4
"""Such cells a group needs to be worth a visit."""
WALL_VIEW = (0.4, 1.2)
"""m from an unmarked wall's middle within which the robot stands to see it (within an RPLIDAR
A1's 2 m hit range, with room for the SLAM's error and a slanted view)."""
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
VIEW_WALK = 2.0
"""m of way that halve a view's worth when choosing among the best (a view twice as far must see
twice as much)."""


@dataclass(frozen=True)
class Frontier:
    """A group of frontier cells: its centre and size, and where the robot can stand to see it."""

    centre: tuple[float, float]
    size: int
    """Cells in the group."""
    goal: tuple[float, float] | None
    """The standing cell nearest the centre within ``reach`` (None: none)."""
    in_known: bool
    """The goal is clear of the unknown too (else only of the walls)."""


def frontiers(
    grid: OccupancyGrid,
    cmap: CostMap,
    optimistic: CostMap | None = None,
    *,
    min_cells: int = MIN_CELLS,
    reach: float = REACH,
    standoff: float = STANDOFF,
) -> list[Frontier]:
    """The frontier groups of ``grid`` (largest first) with their goals: known free cells that
    ``cmap`` does not block (clear of walls and unknown), else that ``optimistic`` (the same map
    planned with unknown cells as free) does not block; with ``standoff`` m of clearance more if
    there is such a cell within ``reach``."""
    known_free = grid.free(FREE)
    unknown = grid.data < 0
    near_unknown = ndimage.binary_dilation(unknown, structure=np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]]))
    labels, count = ndimage.label(known_free & near_unknown, structure=np.ones((3, 3), dtype=int))
    maps = [(cmap, True)] if optimistic is None else [(cmap, True), (optimistic, False)]
    stands = [
        (grid.cell_to_world(np.argwhere(known_free & (m.clearance >= m.inflated + extra))), known)
        for extra in (standoff, 0.0)
        for m, known in maps
    ]
    out: list[Frontier] = []
    for k in range(1, count + 1):
        cells = np.argwhere(labels == k)
        if len(cells) < min_cells:
            continue
        cx, cy = grid.cell_to_world(cells).mean(axis=0)
        goal: tuple[float, float] | None = None
        in_known = False
        for stand_xy, known in stands:
            if len(stand_xy) == 0:
                continue
            d = np.hypot(stand_xy[:, 0] - cx, stand_xy[:, 1] - cy)
            best = int(np.argmin(d))
            if d[best] <= reach:
                goal, in_known = (float(stand_xy[best, 0]), float(stand_xy[best, 1])), known
                break
        out.append(Frontier((float(cx), float(cy)), len(cells), goal, in_known))
    out.sort(key=lambda f: -f.size)
    return out


def frontier_goals(
    grid: OccupancyGrid,
    cmap: CostMap,
    optimistic: CostMap | None = None,
    *,
    min_cells: int = MIN_CELLS,
    reach: float = REACH,
) -> list[tuple[float, float, int]]:
    """(x, y, size) of each frontier group's goal (map frame, m) and its size in cells, largest
    first; groups with nowhere to stand within ``reach`` are left out (see :func:`frontiers`)."""
    return [
        (f.goal[0], f.goal[1], f.size)
        for f in frontiers(grid, cmap, optimistic, min_cells=min_cells, reach=reach)
        if f.goal is not None
    ]


def unmarked_walls(
    grid: OccupancyGrid, returns: NDArray[np.integer], *, min_returns: int = WALL_RETURNS
) -> NDArray[np.bool_]:
    """Cells where the scanner saw something (``returns``: returns per cell, at every range) that
    the map does not mark, nor any neighbour: walls seen only from beyond the hit range or edge-on
    (single hits cleared by the rays grazing past). Cells the map holds free with confidence are
    left out (a stray return in the open)."""
    marked: NDArray[np.bool_] = ndimage.binary_dilation(
        grid.occupied(OCCUPIED), structure=np.ones((3, 3), dtype=bool)
    )
    seen: NDArray[np.bool_] = np.asarray(returns) >= min_returns
    return seen & ~marked & ~grid.free(25)


def wall_goals(
    grid: OccupancyGrid,
    cmap: CostMap,
    returns: NDArray[np.integer],
    *,
    min_cells: int = WALL_CELLS,
    view: tuple[float, float] = WALL_VIEW,
) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """(where to stand, the group's middle) for each group of :func:`unmarked_walls` (8-connected, at least
    ``min_cells``) within the hit range: a cell clear of the walls and the unknown (``cmap``) between
    ``view`` m of the group's middle with a line of sight to it through known free cells, facing the
    group square on where it can (a long group's axis across the view) and about a metre away;
    groups with no such place are left out."""
    labels, count = ndimage.label(unmarked_walls(grid, returns), structure=np.ones((3, 3), dtype=int))
    if count == 0:
        return []
    stand_cells = np.argwhere(grid.free(FREE) & ~cmap.blocked)
    if len(stand_cells) == 0:
        return []
    stands = grid.cell_to_world(stand_cells)
    see_through = grid.free(FREE)
    res = grid.resolution
    goals: list[tuple[tuple[float, float], tuple[float, float]]] = []
    for k in range(1, count + 1):
        cells = np.argwhere(labels == k)
        if len(cells) < min_cells:
            continue
        xy = grid.cell_to_world(cells)
        centre = xy.mean(axis=0)
        d = np.hypot(*(stands - centre).T)
        near = (d >= view[0]) & (d <= view[1])
        if not near.any():
            continue
        cand, dist = stands[near], d[near]
        seen = line_of_sight(grid, see_through, cand, centre, stop=2.0 * res)
        if not seen.any():
            continue
        cand, dist = cand[seen], dist[seen]
        across = np.zeros(len(cand))
        if len(cells) >= 3:
            _, vectors = np.linalg.eigh(np.cov((xy - centre).T))
            axis = vectors[:, -1]  # the group's long direction
            across = np.abs(((cand - centre) @ axis) / np.maximum(dist, 1e-9))  # |cos|: 0 square on
        best = int(np.argmin(across + np.abs(dist - 1.0)))
        goals.append(((float(cand[best, 0]), float(cand[best, 1])), (float(centre[0]), float(centre[1]))))
    return goals


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


def choose_frontier(
    cmap: CostMap, optimistic: CostMap, here: Pose2D, goals: list[tuple[float, float]]
) -> tuple[tuple[tuple[float, float], bool] | None, list[tuple[float, float, str]]]:
    """The goal with the shortest way from ``here`` among the :data:`CANDIDATES` nearest that have
    one (on ``cmap``, else on ``optimistic``: the same map with unknown cells free), and whether the
    way goes through unknown space; and the goals nearer than the last candidate that have no way
    even through the unknown (unreachable on this map), each with the planner's reason."""
    best: tuple[float, tuple[float, float], bool] | None = None
    unreachable: list[tuple[float, float, str]] = []
    found = 0
    for gx, gy in sorted(goals, key=lambda g: math.hypot(g[0] - here.x, g[1] - here.y)):
        target = Pose2D(gx, gy, here.theta)
        try:
            length, through = plan_path(cmap, here, target).length, False
        except PlanningError:
            try:
                length, through = UNKNOWN_PENALTY * plan_path(optimistic, here, target).length, True
            except PlanningError as exc:
                unreachable.append((gx, gy, str(exc)))
                continue
        if best is None or length < best[0]:
            best = (length, (gx, gy), through)
        found += 1
        if found >= CANDIDATES:
            break
    return (None if best is None else (best[1], best[2])), unreachable


def choose_view(
    cmap: CostMap,
    here: Pose2D,
    candidates: list[View],
    *,
    tight: CostMap | None = None,
    walk: float = VIEW_WALK,
) -> tuple[View, bool] | None:
    """Among the :data:`CANDIDATES` ``candidates`` worth most by straight line (cells seen over 1 +
    distance / ``walk``), the one worth most by the way planned on ``cmap``, else on ``tight`` (the
    same map inflated by the radius alone: a gap narrower than the margin, where a way planned
    before the map filled in may have led); and whether its way is ``tight``'s. None when none
    has a way (or there are none)."""

    def worth(view: View, length: float) -> float:
        return view.size / (1.0 + length / walk)

    ranked = sorted(candidates, key=lambda v: -worth(v, math.hypot(v.stand[0] - here.x, v.stand[1] - here.y)))
    best: tuple[float, View, bool] | None = None
    for view in ranked[:CANDIDATES]:
        goal = Pose2D(view.stand[0], view.stand[1], here.theta)
        way = _way(cmap, here, goal)
        narrow = way is None and tight is not None
        if narrow and tight is not None:
            way = _way(tight, here, goal)
        if way is not None and (best is None or worth(view, way) > best[0]):
            best = (worth(view, way), view, narrow)
    return None if best is None else (best[1], best[2])


def _way(cmap: CostMap, here: Pose2D, goal: Pose2D) -> float | None:
    """The length of the way planned on ``cmap`` from ``here`` to ``goal``, m (None: no way)."""
    try:
        return plan_path(cmap, here, goal).length
    except PlanningError:
        return None


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
