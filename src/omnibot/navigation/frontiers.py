"""Where exploring goes next on a map: its frontiers (free cells beside unknown ones, grouped:
:func:`frontiers`) and the walls the scans saw that it does not mark (:func:`unmarked_walls`), the
places to see each from (:func:`frontier_goals`, :func:`wall_goals`), and which goal or view to go to
(:func:`choose_frontier`, :func:`choose_view`: the shortest way, the most seen for the way). The
exploring itself: :mod:`omnibot.navigation.explore`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from omnibot.errors import PlanningError
from omnibot.mapping import CostMap, OccupancyGrid, plan_path
from omnibot.motion import Pose2D
from omnibot.navigation.views import View, line_of_sight

REACH = 0.6
"""m from a frontier's centre within which its goal is sought."""
MIN_CELLS = 6
"""Frontier cells a group needs to be worth a visit (one unknown cell in the open makes 4)."""
FREE = 49
"""Known cells below even odds of being occupied count as free here (one pass of a ray leaves a
cell at 40: map_server's 25 would need several before a frontier appears)."""
CANDIDATES = 4
"""Nearest frontier goals with a way to them among which the shortest way is chosen."""
UNKNOWN_PENALTY = 1.5
"""A way through unknown cells counts this many times its length when choosing (it may be walled)."""
STANDOFF = 0.1
"""m of clearance beyond the robot's radius and margin a frontier's goal keeps where there is room
(the map grows after the goal is chosen: a wall nearer than it seemed, thickened by noise)."""
OCCUPIED = 65
"""Cells at or above this are walls the map has marked (map_server's occupied threshold)."""
WALL_RETURNS = 2
"""Returns in a cell the map does not mark (nor a neighbour) that make it a wall to see closer."""
WALL_CELLS = 4
"""Such cells a group needs to be worth a visit."""
WALL_VIEW = (0.4, 1.2)
"""m from an unmarked wall's middle within which the robot stands to see it (within an RPLIDAR
A1's 2 m hit range, with room for the SLAM's error and a slanted view)."""
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
