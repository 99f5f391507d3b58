"""A map scored against the world's own geometry: precision and recall of its occupied cells.

The truth is the world's wall and obstacle edges (:attr:`omnibot.sim.world.World.segments`),
rasterised into the map's own cells: every cell an edge passes through (edges sampled every quarter
cell). Distances are between cell centres (``scipy.ndimage.distance_transform_edt``), so at 5 cm
cells and the default 5 cm tolerance a map cell counts as on the truth when it is a true cell or
one of its four neighbours.

* **precision**: the share of the map's occupied cells (``>= occupied``, 65 by default, map_server's
  threshold) within ``tolerance`` of a true cell. What the map claims, is it there?
* **recall**: the share of the *observable* true cells with an occupied map cell within
  ``tolerance``. A true cell is observable when a known-free map cell lies within ``seen`` (default
  three cells, 0.15 m at 5 cm) of it: the robot's scans reached the space right in front of it. The
  far side of a cabinet the robot never drove round, walls outside the rooms it entered and edges
  off the map do not count against the map; a wall the scans cleared up to but did not mark does.

Both are defined on cells, not metres of edge: a wall counts by the cells it crosses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from omnibot.mapping.grid import OccupancyGrid
from omnibot.motion import Pose2D
from omnibot.sim import World, points_in_polygon


@dataclass(frozen=True)
class MapScore:
    """Precision and recall of a map's occupied cells against the truth (see the module docstring)."""

    precision: float
    """Share of the occupied cells within tolerance of the truth (1.0 for a map with none)."""
    recall: float
    """Share of the observable true cells the map has occupied within tolerance (1.0 if none)."""
    occupied: int
    """Occupied cells in the map."""
    observable: int
    """True cells that were observable."""
    true_cells: int
    """True cells on the map's grid."""
    tolerance: float
    """The tolerance, m."""

    @property
    def f1(self) -> float:
        """Harmonic mean of precision and recall."""
        total = self.precision + self.recall
        return 0.0 if total == 0 else 2.0 * self.precision * self.recall / total


def rasterise(world: World, grid: OccupancyGrid) -> NDArray[np.bool_]:
    """The cells of ``grid`` that the world's walls and obstacle edges pass through."""
    truth = np.zeros(grid.shape, dtype=bool)
    seg = world.segments
    if len(seg) == 0:
        return truth
    step = grid.resolution / 4.0
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    n = np.ceil(length / step).astype(np.int64) + 1
    which = np.repeat(np.arange(len(seg)), n)
    t = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n - 1, n)
    pts = seg[which, :2] + (seg[which, 2:] - seg[which, :2]) * t[:, None]
    cells = grid.world_to_cell(pts)
    cells = cells[grid.inside(cells)]
    truth[cells[:, 0], cells[:, 1]] = True
    return truth


def _distance(mask: NDArray[np.bool_], resolution: float) -> NDArray[np.float64]:
    """Distance (m, centre to centre) from every cell to the nearest cell of ``mask`` (inf if none)."""
    if not mask.any():
        return np.full(mask.shape, np.inf)
    dist: NDArray[np.float64] = ndimage.distance_transform_edt(~mask, sampling=resolution)
    return dist


def score_map(
    grid: OccupancyGrid,
    world: World,
    *,
    tolerance: float = 0.05,
    seen: float | None = None,
    occupied: int = 65,
    free: int = 25,
) -> MapScore:
    """Precision and recall of ``grid``'s occupied cells against ``world`` within ``tolerance`` (m).

    ``seen`` (m, default three cells) is how near a known-free cell (``0..free``) must be for a
    true cell to count as observable.
    """
    if tolerance < 0:
        raise ValueError(f"tolerance must not be negative, not {tolerance}")
    res = grid.resolution
    near = tolerance + 1e-9 * res  # a neighbour exactly one cell away is within a one-cell tolerance
    reach = (3.0 * res if seen is None else seen) + 1e-9 * res
    truth = rasterise(world, grid)
    occ = grid.occupied(occupied)
    known_free = grid.free(free)
    to_truth = _distance(truth, res)
    to_occ = _distance(occ, res)
    to_free = _distance(known_free, res)
    n_occ = int(occ.sum())
    observable = truth & (to_free <= reach)
    n_obs = int(observable.sum())
    good = int((occ & (to_truth <= near)).sum())
    found = int((observable & (to_occ <= near)).sum())
    return MapScore(
        precision=good / n_occ if n_occ else 1.0,
        recall=found / n_obs if n_obs else 1.0,
        occupied=n_occ,
        observable=n_obs,
        true_cells=int(truth.sum()),
        tolerance=tolerance,
    )


def world_grid(world: World, resolution: float = 0.05, pad: float = 0.1) -> OccupancyGrid:
    """The world's own map: its walls and obstacles as an occupancy grid (0 free, 100 wall) covering
    its bounds plus ``pad`` m, what a perfect mapper would make (the planner's map in tests and
    benchmarks, a map to localise in on the simulator): a cell is a wall where an edge passes within half its diagonal of its centre,
    or where its centre lies inside an obstacle."""
    bounds = world.bounds
    if bounds is None:
        raise ValueError(f"world {world.name} has no walls or obstacles to rasterise")
    x0, y0, x1, y1 = bounds[0] - pad, bounds[1] - pad, bounds[2] + pad, bounds[3] + pad
    cols, rows = math.ceil((x1 - x0) / resolution), math.ceil((y1 - y0) / resolution)
    cx = x0 + (np.arange(cols) + 0.5) * resolution
    cy = y0 + (np.arange(rows) + 0.5) * resolution
    px, py = np.meshgrid(cx, cy)  # (rows, cols)
    pts = np.column_stack((px.ravel(), py.ravel()))
    occupied = np.zeros(len(pts), dtype=bool)
    reach = resolution * math.sqrt(0.5)
    for seg in world.segments:
        a, e = seg[:2], seg[2:] - seg[:2]
        ee = float(e @ e)
        t = np.clip(((pts - a) @ e) / ee, 0.0, 1.0) if ee > 0 else np.zeros(len(pts))
        d = np.hypot(*(pts - (a + t[:, None] * e)).T)
        occupied |= d <= reach
    for obstacle in world.spec.obstacles:
        occupied |= points_in_polygon(pts, obstacle.vertices())
    data = np.where(occupied.reshape(rows, cols), 100, 0).astype(np.int8)
    return OccupancyGrid(data, resolution, Pose2D(x0, y0, 0.0))
