"""Planning a collision-free path for a holonomic base on an occupancy grid.

::

    OccupancyGrid --inflate()--> CostMap: clearance (m, exact distance transform), blocked cells
        (clearance < robot radius + margin; unknown cells count as walls unless allowed), and a
        cost that decays away from the walls (nav2's inflation layer: exp(-decay (d - r)))
      --plan_path(start, goal)--> PlannedPath (map-frame waypoints, the goal's heading)

Two planners (``planner=``):

* ``"grid"`` (the default): A* on the 8-connected cells (compiled with numba), each step costing
  its length times ``1 + weight * cost``, so the path keeps away from walls where there is room;
  then line-of-sight shortcutting (any-angle): a straight run replaces a stretch of the A* path
  when it crosses no blocked cell and comes no closer to a wall (no higher cost) than that stretch
  did. Deterministic.
* ``"rrtstar"``, ``"prmstar"``, ``"bitstar"``: OMPL's sampling planners in R2 (its Python
  bindings, imported on first use) with the blocked cells as the validity checker, for
  ``time_limit`` s (longer only while it has no path yet, up to :data:`FIRST_PATH_WAIT` s: A* has
  told first that there is one), then OMPL's path simplification; seeded (``seed``) for repeatable
  runs.

The robot is a disc (its footprint's bounding radius), so any heading fits wherever its centre
may go. The clearance is measured from a cell's centre to the nearest wall cell's edge; a centre
anywhere in the cell may be up to ``resolution / sqrt(2)`` closer, which the margin covers.
Errors (:mod:`omnibot.errors`): :class:`~omnibot.errors.OffMapError`,
:class:`~omnibot.errors.BlockedError` (the goal, or the start, in a wall, in unknown space or too
near a wall), :class:`~omnibot.errors.NoPathError`, each one line in the map frame's metres.
A start inside the inflated margin (but clear of the walls themselves) is allowed: the path first
climbs the clearance out of it.
"""

from __future__ import annotations

import importlib
import itertools
import math
import time
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numba import njit
from numpy.typing import NDArray

from omnibot.errors import BlockedError, ConfigError, NoPathError, OffMapError
from omnibot.mapping.grid import OccupancyGrid
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

MARGIN = 0.05
"""m kept free beyond the robot's radius (tracking error, odometry drift, the grid's cells)."""
COST_DECAY = 6.0
"""1/m: how fast the wall cost falls beyond the inflated radius (nav2's cost_scaling_factor)."""
COST_RANGE = 0.6
"""m beyond the inflated radius where the cost ends (nav2's inflation_radius less the robot's)."""
COST_WEIGHT = 3.0
"""How much a step at the highest cost counts beyond its length: 1 + weight x cost per metre."""
OCCUPIED = 65
"""Occupancy at or above which a cell is a wall (map_server's occupied_thresh 0.65)."""
FIRST_PATH_WAIT = 10.0
"""s an OMPL planner may run in all (at least its ``time_limit``) while it has no path yet: there is
one, the grid planner found it first. The time limit is for improving a path; on a loaded machine
the sampling slows, and a plan that exists is not refused for it."""
FIRST_PATH_SLICE = 0.02
"""s of each further solve while an OMPL planner has no path yet (OMPL's planners report a path at the
end of a solve; each further solve carries on from the tree or roadmap it has)."""
Planner = Literal["grid", "rrtstar", "prmstar", "bitstar"]
PLANNERS: tuple[str, ...] = ("grid", "rrtstar", "prmstar", "bitstar")


@dataclass(frozen=True)
class CostMap:
    """A grid made ready for planning a robot of ``robot_radius`` with ``margin`` (see the module)."""

    grid: OccupancyGrid
    robot_radius: float
    margin: float
    allow_unknown: bool
    clearance: FloatArray
    """m from each cell's centre to the nearest wall cell's edge (unknown cells are walls unless
    allowed; 0 on a wall)."""
    blocked: BoolArray
    """Cells the robot's centre may not be in: clearance < radius + margin."""
    cost: FloatArray
    """0..1: 1 at the inflated radius, decaying to 0 ``COST_RANGE`` beyond it (0 on blocked cells)."""

    @property
    def inflated(self) -> float:
        """The radius the walls are inflated by, m (robot radius + margin)."""
        return self.robot_radius + self.margin

    def cell_of(self, x: float, y: float) -> tuple[int, int] | None:
        """(row, col) of the cell holding map point (x, y); None off the map."""
        rc = self.grid.world_to_cell([(x, y)])
        if not bool(self.grid.inside(rc)[0]):
            return None
        return int(rc[0, 0]), int(rc[0, 1])

    def clearance_at(self, x: float, y: float) -> float:
        """The clearance of the cell holding (x, y), m (0 off the map)."""
        cell = self.cell_of(x, y)
        return 0.0 if cell is None else float(self.clearance[cell])

    def segment_free(self, a: tuple[float, float], b: tuple[float, float]) -> bool:
        """True when the straight run from ``a`` to ``b`` (map frame) crosses no blocked cell."""
        fa, fb = self._local(a), self._local(b)
        return _line_max(np.where(self.blocked, np.inf, 0.0), fa[0], fa[1], fb[0], fb[1]) < 0.5

    def _local(self, p: tuple[float, float]) -> tuple[float, float]:
        """(row, col) as floats (cell units, cell centres at +0.5) of a map point."""
        o = self.grid.origin
        dx, dy = p[0] - o.x, p[1] - o.y
        c, s = math.cos(o.theta), math.sin(o.theta)
        res = self.grid.resolution
        return ((-s * dx + c * dy) / res, (c * dx + s * dy) / res)


def inflate(
    grid: OccupancyGrid,
    *,
    robot_radius: float,
    margin: float = MARGIN,
    allow_unknown: bool = False,
    occupied: int = OCCUPIED,
    decay: float = COST_DECAY,
    cost_range: float = COST_RANGE,
) -> CostMap:
    """The grid's walls inflated by ``robot_radius + margin`` with a cost beyond (see the module)."""
    if not (math.isfinite(robot_radius) and robot_radius > 0):
        raise ConfigError(f"the robot radius must be a positive length, not {robot_radius}")
    if not (math.isfinite(margin) and margin >= 0):
        raise ConfigError(f"the safety margin must be a length >= 0, not {margin}")
    walls = grid.data >= occupied
    if not allow_unknown:
        walls = walls | (grid.data < 0)
    res = grid.resolution
    if walls.any():
        dist = np.sqrt(distance_squared(walls)) * res
        clearance = np.maximum(dist - 0.5 * res, 0.0)
        clearance[walls] = 0.0
    else:
        clearance = np.full(grid.shape, math.inf)
    inflated = robot_radius + margin
    blocked = clearance < inflated
    beyond = clearance - inflated
    cost = np.where(blocked | (beyond > cost_range), 0.0, np.exp(-decay * np.clip(beyond, 0.0, None)))
    return CostMap(grid, robot_radius, margin, allow_unknown, clearance, blocked, cost)


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
    s_cell = _check_end(cmap, start, "start")
    g_cell = _check_end(cmap, goal, "goal")
    escape = _escape(cmap, s_cell)
    climb = cmap.grid.cell_to_world(escape[1:]) if len(escape) > 1 else np.zeros((0, 2))
    head = np.vstack([[(start.x, start.y)], climb])
    cells = astar(~cmap.blocked, cmap.cost, escape[-1], g_cell, weight)
    if cells is None:
        raise NoPathError(f"no path from {_xy(start)} to {_xy(goal)}: {_why_no_path(cmap)}")
    if planner == "grid":
        tail = shortcut(cmap, cells, (float(head[-1, 0]), float(head[-1, 1])), (goal.x, goal.y), weight)
    else:
        tail = _ompl_plan(
            cmap, (float(head[-1, 0]), float(head[-1, 1])), start, goal, planner, time_limit, seed
        )
    points = np.vstack([head[:-1], tail])
    clearance = min(
        (_segment_clearance(cmap, a, b) for a, b in itertools.pairwise(points)),
        default=cmap.clearance_at(goal.x, goal.y),
    )
    return PlannedPath(points, goal, planner, clearance, time.perf_counter() - t0)


# --------------------------------------------------------------------------- ends


def check_goal(cmap: CostMap, goal: Pose2D) -> None:
    """OffMapError or BlockedError when the robot cannot stand at ``goal`` on ``cmap`` (what
    :func:`plan_path` checks first), so a command can refuse a bad goal before it moves."""
    _check_end(cmap, goal, "goal")


def check_start(cmap: CostMap, start: Pose2D) -> None:
    """OffMapError, BlockedError or NoPathError when no path can leave ``start`` on ``cmap`` whatever
    the goal (what :func:`plan_path` checks of the start: on the map, not overlapping a wall, not
    hemmed in where the clearance cannot climb)."""
    _escape(cmap, _check_end(cmap, start, "start"))


def _xy(p: Pose2D) -> str:
    return f"({p.x:.2f}, {p.y:.2f})"


def _check_end(cmap: CostMap, pose: Pose2D, name: str) -> tuple[int, int]:
    """The cell of a start or goal, or the error that says why the robot cannot be there."""
    grid = cmap.grid
    cell = cmap.cell_of(pose.x, pose.y)
    if cell is None:
        o = grid.origin
        raise OffMapError(
            f"{name} {_xy(pose)} is off the map (it spans {grid.width:.2f} m x {grid.height:.2f} m "
            f"from ({o.x:.2f}, {o.y:.2f}))"
        )
    value = int(grid.data[cell])
    if value < 0 and not cmap.allow_unknown:
        raise BlockedError(f"{name} {_xy(pose)} is in unmapped space (unknown on the map)")
    clearance = float(cmap.clearance[cell])
    if value >= OCCUPIED or clearance <= 0.0:
        raise BlockedError(f"{name} {_xy(pose)} is inside a wall or obstacle")
    need = cmap.inflated
    if name == "goal" and clearance < need:
        raise BlockedError(
            f"goal {_xy(pose)} is too close to a wall: {100 * clearance:.0f} cm from it, the robot needs "
            f"{100 * need:.0f} cm (radius {100 * cmap.robot_radius:.0f} + margin {100 * cmap.margin:.0f})"
        )
    if name == "start" and clearance < cmap.robot_radius:
        raise BlockedError(
            f"start {_xy(pose)} overlaps a wall on the map: {100 * clearance:.0f} cm from it, the "
            f"robot's radius is {100 * cmap.robot_radius:.0f} cm"
        )
    return cell


def _escape(cmap: CostMap, cell: tuple[int, int]) -> list[tuple[int, int]]:
    """Cells from ``cell`` up the clearance until one is not blocked (just ``[cell]`` if it is not)."""
    out = [cell]
    rows, cols = cmap.grid.shape

    def clearance(rc: tuple[int, int]) -> float:
        return float(cmap.clearance[rc]) if 0 <= rc[0] < rows and 0 <= rc[1] < cols else -1.0

    while cmap.blocked[out[-1]]:
        r, c = out[-1]
        best = max(((r + dr, c + dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc), key=clearance)
        if clearance(best) <= clearance((r, c)):
            raise NoPathError(
                f"no path: the start is hemmed in {100 * cmap.clearance[cell]:.0f} cm from a wall"
            )
        out.append(best)
    return out


def _why_no_path(cmap: CostMap) -> str:
    return (
        f"the free space between them is narrower than the robot needs "
        f"({100 * 2 * cmap.inflated:.0f} cm: radius {100 * cmap.robot_radius:.0f} cm + margin "
        f"{100 * cmap.margin:.0f} cm each side) or closed"
    )


# --------------------------------------------------------------------------- A* and shortcuts


def astar(
    passable: BoolArray, cost: FloatArray, start: tuple[int, int], goal: tuple[int, int], weight: float
) -> NDArray[np.int64] | None:
    """(n, 2) (row, col) cells of the cheapest 8-connected path from ``start`` to ``goal`` through
    ``passable`` cells, each step its length (cells) times ``1 + weight x`` the mean ``cost`` of
    its two cells; None when there is none."""
    cols = passable.shape[1]
    parent = _astar(
        np.ascontiguousarray(passable, dtype=np.uint8),
        np.ascontiguousarray(cost, dtype=np.float64),
        start[0] * cols + start[1],
        goal[0] * cols + goal[1],
        float(weight),
    )
    g = goal[0] * cols + goal[1]
    if parent[g] < 0:
        return None
    chain = [g]
    while chain[-1] != parent[chain[-1]]:
        chain.append(int(parent[chain[-1]]))
    idx = np.array(chain[::-1], dtype=np.int64)
    return np.column_stack((idx // cols, idx % cols))


@njit(cache=True)
def _heap_pop(heap_f, heap_i, size):  # type: ignore[no-untyped-def]  # numba kernel
    """The item of least key off the binary heap ``heap_f`` (keys), ``heap_i`` (items) of ``size``
    entries, which then holds ``size - 1``."""
    top = heap_i[0]
    size -= 1
    lf, li = heap_f[size], heap_i[size]
    k = 0
    while True:
        a = 2 * k + 1
        if a >= size:
            break
        if a + 1 < size and heap_f[a + 1] < heap_f[a]:
            a += 1
        if heap_f[a] >= lf:
            break
        heap_f[k], heap_i[k] = heap_f[a], heap_i[a]
        k = a
    heap_f[k], heap_i[k] = lf, li
    return top


@njit(cache=True)
def _heap_push(heap_f, heap_i, size, f, item):  # type: ignore[no-untyped-def]  # numba kernel
    """``item`` with key ``f`` onto the binary heap of ``size`` entries, which then holds ``size + 1``."""
    k = size
    while k > 0:
        p = (k - 1) // 2
        if heap_f[p] <= f:
            break
        heap_f[k], heap_i[k] = heap_f[p], heap_i[p]
        k = p
    heap_f[k], heap_i[k] = f, item


@njit(cache=True)
def _astar(passable, cost, start, goal, weight):  # type: ignore[no-untyped-def]  # numba kernel
    rows, cols = passable.shape
    n = rows * cols
    parent = np.full(n, -1, np.int64)
    gcost = np.full(n, np.inf)
    closed = np.zeros(n, np.uint8)
    cap = 8 * n + 16
    heap_f = np.empty(cap)
    heap_i = np.empty(cap, np.int64)
    size = 0
    gr, gc = goal // cols, goal % cols
    gcost[start] = 0.0
    parent[start] = start
    heap_f[0] = 0.0
    heap_i[0] = start
    size = 1
    dr = (-1, -1, -1, 0, 0, 1, 1, 1)
    dc = (-1, 0, 1, -1, 1, -1, 0, 1)
    sq2 = math.sqrt(2.0)
    while size > 0:
        cur = _heap_pop(heap_f, heap_i, size)
        size -= 1
        if closed[cur]:
            continue
        closed[cur] = 1
        if cur == goal:
            break
        r, c = cur // cols, cur % cols
        for m in range(8):
            nr, nc = r + dr[m], c + dc[m]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols or not passable[nr, nc]:
                continue
            if dr[m] != 0 and dc[m] != 0 and not (passable[r, nc] and passable[nr, c]):
                continue  # no corner cutting
            nxt = nr * cols + nc
            if closed[nxt]:
                continue
            step = sq2 if (dr[m] != 0 and dc[m] != 0) else 1.0
            g = gcost[cur] + step * (1.0 + weight * 0.5 * (cost[r, c] + cost[nr, nc]))
            if g < gcost[nxt]:
                gcost[nxt] = g
                parent[nxt] = cur
                f = g + math.hypot(nr - gr, nc - gc)
                _heap_push(heap_f, heap_i, size, f, nxt)
                size += 1
    return parent


@njit(cache=True)
def _traverse(values, r0, c0, r1, c1, weight, cost_mode):  # type: ignore[no-untyped-def]  # numba kernel
    """Walk the cells a straight run crosses (cell units, cell (i, j) spans [i, i+1) x [j, j+1)),
    exactly (Amanatides and Woo; where it passes a cell corner, both cells beside it count too).
    ``cost_mode``: the run's cost, its length in each cell times ``1 + weight x`` the cell's value;
    else the largest value it meets. inf when it leaves the grid or meets an infinite value."""
    rows, cols = values.shape
    dr, dc = r1 - r0, c1 - c0
    length = math.hypot(dr, dc)
    r, c = math.floor(r0), math.floor(c0)
    er, ec = math.floor(r1), math.floor(c1)
    step_r = 1 if dr > 0 else -1
    step_c = 1 if dc > 0 else -1
    t_dr = abs(1.0 / dr) if dr != 0 else np.inf
    t_dc = abs(1.0 / dc) if dc != 0 else np.inf
    next_r = ((r + 1 - r0) if dr > 0 else (r0 - r)) * t_dr if dr != 0 else np.inf
    next_c = ((c + 1 - c0) if dc > 0 else (c0 - c)) * t_dc if dc != 0 else np.inf
    t = 0.0
    total = 0.0
    best = -np.inf
    for _ in range(4 * (rows + cols) + 8):
        if r < 0 or r >= rows or c < 0 or c >= cols:
            return np.inf
        v = values[r, c]
        if not math.isfinite(v):
            return np.inf
        t_next = min(next_r, next_c, 1.0)
        total += (t_next - t) * length * (1.0 + weight * v)
        best = max(best, v)
        if (r == er and c == ec) or t_next >= 1.0:
            break
        t = t_next
        if abs(next_r - next_c) < 1e-12:  # through a corner: the cells beside it count too
            for rr, cc in ((r + step_r, c), (r, c + step_c)):
                if rr < 0 or rr >= rows or cc < 0 or cc >= cols or not math.isfinite(values[rr, cc]):
                    return np.inf
                best = max(best, values[rr, cc])
            r += step_r
            c += step_c
            next_r += t_dr
            next_c += t_dc
        elif next_r < next_c:
            r += step_r
            next_r += t_dr
        else:
            c += step_c
            next_c += t_dc
    return total if cost_mode else best


def _line_max(values: FloatArray, r0: float, c0: float, r1: float, c1: float) -> float:
    """The largest of ``values`` over the cells a straight run crosses (inf off the grid)."""
    return float(_traverse(values, r0, c0, r1, c1, 0.0, False))


def _line_cost(values: FloatArray, r0: float, c0: float, r1: float, c1: float, weight: float) -> float:
    """A straight run's cost (cell units): its length in each cell times ``1 + weight x`` its value."""
    return float(_traverse(values, r0, c0, r1, c1, weight, True))


def shortcut(
    cmap: CostMap,
    cells: NDArray[np.int64],
    first: tuple[float, float],
    last: tuple[float, float],
    weight: float = COST_WEIGHT,
) -> FloatArray:
    """Any-angle waypoints (map frame) from an A* chain of unblocked cells, starting at ``first``
    and ending at ``last`` (points in its first and last cells): from each kept point, the farthest
    later one reachable in a straight run that crosses no blocked cell and costs no more than the
    chain between them, by A*'s own measure (length times ``1 + weight x cost``), so a shortcut
    never trades the walls' berth for length."""
    if len(cells) == 1:
        return np.array([first, last], dtype=np.float64)
    centres = cmap.grid.cell_to_world(cells)
    centres[0] = first
    centres[-1] = last
    local = np.array([cmap._local((float(x), float(y))) for x, y in centres])
    field = np.where(cmap.blocked, np.inf, cmap.cost)
    c = field[cells[:, 0], cells[:, 1]]
    steps = np.hypot(*np.diff(local, axis=0).T) * (1.0 + weight * 0.5 * (c[:-1] + c[1:]))
    along = np.concatenate(([0.0], np.cumsum(steps)))  # the chain's cost to each cell
    kept = [0]
    i, n = 0, len(cells)
    while i < n - 1:
        j_best = i + 1
        for j in range(n - 1, i + 1, -1):
            run = _line_cost(field, local[i, 0], local[i, 1], local[j, 0], local[j, 1], weight)
            if run <= (along[j] - along[i]) * (1.0 + 1e-9) + 1e-9:
                j_best = j
                break
        kept.append(j_best)
        i = j_best
    return np.asarray(centres[kept], dtype=np.float64)


def _segment_clearance(cmap: CostMap, a: FloatArray, b: FloatArray) -> float:
    """The least clearance of the cells a straight run crosses, m."""
    la, lb = cmap._local((float(a[0]), float(a[1]))), cmap._local((float(b[0]), float(b[1])))
    worst = _line_max(-cmap.clearance, la[0], la[1], lb[0], lb[1])
    return float(-worst) if math.isfinite(worst) else 0.0


# --------------------------------------------------------------------------- distance transform


def distance_squared(walls: BoolArray) -> FloatArray:
    """Squared distance (cells) from each cell's centre to the nearest ``walls`` cell's centre
    (exact Euclidean, Felzenszwalb and Huttenlocher's two passes of lower envelopes)."""
    big = float((walls.shape[0] + walls.shape[1]) ** 2 + 1)
    f = np.where(walls, 0.0, big).astype(np.float64)
    return np.asarray(_edt2(f), dtype=np.float64)


@njit(cache=True)
def _edt1(f, out, v, z):  # type: ignore[no-untyped-def]  # numba kernel
    n = f.shape[0]
    k = 0
    v[0] = 0
    z[0] = -np.inf
    z[1] = np.inf
    for q in range(1, n):
        s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k])
        while s <= z[k]:
            k -= 1
            s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k])
        k += 1
        v[k] = q
        z[k] = s
        z[k + 1] = np.inf
    k = 0
    for q in range(n):
        while z[k + 1] < q:
            k += 1
        out[q] = (q - v[k]) ** 2 + f[v[k]]


@njit(cache=True)
def _edt2(f):  # type: ignore[no-untyped-def]  # numba kernel
    rows, cols = f.shape
    m = max(rows, cols)
    v = np.zeros(m, np.int64)
    z = np.zeros(m + 1)
    tmp = np.empty(m)
    out = np.empty_like(f)
    for c in range(cols):
        _edt1(f[:, c].copy(), tmp[:rows], v, z)
        out[:, c] = tmp[:rows]
    for r in range(rows):
        _edt1(out[r, :].copy(), tmp[:cols], v, z)
        out[r, :] = tmp[:cols]
    return out


# --------------------------------------------------------------------------- OMPL


def _ompl_plan(
    cmap: CostMap,
    first: tuple[float, float],
    start: Pose2D,
    goal: Pose2D,
    planner: str,
    time_limit: float,
    seed: int,
) -> FloatArray:
    """Waypoints from ``first`` to the goal by one of OMPL's planners in R2 (see the module);
    NoPathError without a solution."""
    # optional bindings without types, loaded on first use
    ob = importlib.import_module("ompl.base")
    og = importlib.import_module("ompl.geometric")
    ou = importlib.import_module("ompl.util")

    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(seed)
    grid = cmap.grid
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    corners = grid.cell_to_world([(0, 0), (grid.shape[0] - 1, grid.shape[1] - 1)])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    bounds.setLow(0, float(lo[0]))
    bounds.setLow(1, float(lo[1]))
    bounds.setHigh(0, float(hi[0]))
    bounds.setHigh(1, float(hi[1]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    blocked = cmap.blocked

    def valid(state: object) -> bool:
        cell = cmap.cell_of(state[0], state[1])  # type: ignore[index]
        return cell is not None and not bool(blocked[cell])

    setup.setStateValidityChecker(valid)
    a, b = space.allocState(), space.allocState()
    a[0], a[1] = float(first[0]), float(first[1])
    b[0], b[1] = goal.x, goal.y
    setup.setStartAndGoalStates(a, b)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(0.25 * grid.resolution / space.getMaximumExtent())
    made = {"rrtstar": og.RRTstar, "prmstar": og.PRMstar, "bitstar": og.BITstar}[planner](info)
    setup.setPlanner(made)
    end = time.monotonic() + max(time_limit, FIRST_PATH_WAIT)
    setup.solve(time_limit)
    while not setup.haveExactSolutionPath() and (left := end - time.monotonic()) > 0:
        setup.solve(min(left, max(time_limit, FIRST_PATH_SLICE)))  # the planner goes on where it was
    if not setup.haveExactSolutionPath():
        raise NoPathError(
            f"no path from {_xy(start)} to {_xy(goal)} found by OMPL's {planner} in "
            f"{max(time_limit, FIRST_PATH_WAIT):.2f} s"
        )
    setup.simplifySolution(min(1.0, time_limit))
    path = setup.getSolutionPath()
    points = [(path.getState(i)[0], path.getState(i)[1]) for i in range(path.getStateCount())]
    out = np.array([first, *points[1:-1], (goal.x, goal.y)], dtype=np.float64)
    keep = np.concatenate(([True], np.hypot(*np.diff(out, axis=0).T) > 1e-9))
    return _repaired(cmap, np.asarray(out[keep], dtype=np.float64))


def _repaired(cmap: CostMap, points: FloatArray) -> FloatArray:
    """``points`` with every straight run that clips a blocked cell (OMPL checks its motions at a
    resolution, the cells exactly) replaced by the grid planner's way between its ends."""
    out = [points[0]]
    for a, b in itertools.pairwise(points):
        pa, pb = (float(a[0]), float(a[1])), (float(b[0]), float(b[1]))
        ca, cb = cmap.cell_of(*pa), cmap.cell_of(*pb)
        if cmap.segment_free(pa, pb) or ca is None or cb is None:
            out.append(b)
            continue
        cells = astar(~cmap.blocked, cmap.cost, ca, cb, 0.0)
        if cells is None:
            raise NoPathError(f"no path: OMPL's run from {pa} to {pb} clips a wall and none goes round")
        out.extend(shortcut(cmap, cells, pa, pb, 0.0)[1:])
    return np.asarray(out, dtype=np.float64)
