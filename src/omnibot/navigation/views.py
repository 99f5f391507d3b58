"""View goals: where to stand to see, square on and within the hit range, the surfaces the map lacks.

Frontier exploration stops when no free cell borders reachable unknown space, yet the map can
still lack surfaces: a face behind furniture seen only edge-on (its returns too few against the
rays grazing along it to mark it), or seen only from beyond the scanner's hit range (where a
return marks nothing). Both leave the same trace on the map alone::

    unseen surface: cells bounding the known free space that the map does not mark
      (unknown or undecided cells beside a known free one, or cells where returns fell; no marked
      cell among their 4 neighbours), each with its normal: the way the known free space lies
      from it
      -> stands: where the robot fits (clear of walls and unknown by its radius and margin), on a
         lattice, joined to where it stands (the planner could reach them)
      -> each stand's view: the unseen cells within ``view_range`` whose normal it lies within
         ``incidence`` of (square on enough for the rays to strike rather than graze), with a line
         of sight through known free cells to within a cell of the cell's free side
      -> the stands that see the most, best first

The explorer (:mod:`omnibot.navigation.explore`) goes to them once its frontiers run out, and
retires the cells a view was chosen for whether or not they were marked from there. The world's
geometry is never read: only the map and where the robot stands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage
from scipy.spatial import cKDTree

from omnibot.mapping import CostMap, OccupancyGrid

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

FREE = 49
"""Known cells below even odds of being occupied count as free (as exploring counts them)."""
MARKED = 65
"""Cells at or above this are surfaces the map has marked (map_server's occupied threshold)."""
VIEW_SHARE = 0.9
"""Of the scanner's hit range, the range within which a stand sees a cell: room for the SLAM's error
and the goal's tolerance."""
VIEW_RANGE = VIEW_SHARE * 2.0
"""m from a stand within which it sees a cell: an RPLIDAR A1's (2 m hit range)."""
NEAREST = 0.3
"""m: cells nearer a stand than this are not counted (the robot's own footprint hides them)."""
INCIDENCE = math.radians(70.0)
"""Largest angle between a cell's normal and the way to the stand that still sees it (square on
is 0; at 90 degrees the rays graze it). A wall grazed for 2 m of a pass, then seen from 1.5 m for
ten revolutions: all its cells within 0.5 m marked up to 70 degrees, 80 % at 75, 70 % at 80
(one revolution: 10-20 % at any angle; so the robot stays a while where it looks)."""
MIN_CELLS = 8
"""Unseen cells a stand must see to be worth a visit (4 on 2026-12-07 made omni4 look into the
house's 20 cm gaps from 24 stands on a SLAM 2 cm off and thicken its walls: 97.0 / 94.7 %; 8: 98.1 /
96.5 %, main 99.0 / 96.6 %)."""
LATTICE = 2
"""Cells between stands considered (10 cm at 5 cm cells)."""
SMOOTH = 1.0
"""Cells: the spread of the free-space field (1 free, 0 not) whose gradient gives each cell's normal."""
SLOPE = 0.1
"""Per cell: the least slope of that field on an edge of the free space (a straight edge's is 0.32 on
the cells either side of it; a lone cell's in the open 0, its neighbours' 0.07 or less)."""
RETURNS = 2
"""Returns in an unmarked cell that make it part of the surface the map lacks (one may be a stray)."""


@dataclass(frozen=True)
class Surface:
    """The unseen surface of a map: its cells' centres and unit normals (map frame)."""

    points: FloatArray
    """(n, 2) centres, m."""
    normals: FloatArray
    """(n, 2) unit vectors from each cell into the known free space."""

    def __len__(self) -> int:
        return len(self.points)

    def without(self, places: FloatArray, radius: float) -> Surface:
        """The surface less its cells within ``radius`` m of any of ``places`` ((k, 2))."""
        if len(places) == 0 or len(self) == 0:
            return self
        d, _ = cKDTree(places).query(self.points, k=1)
        keep = d > radius
        return Surface(self.points[keep], self.normals[keep])


@dataclass(frozen=True)
class View:
    """A place to stand and the unseen cells it sees from there."""

    stand: tuple[float, float]
    seen: FloatArray
    """(k, 2) the centres of the unseen cells it sees, m."""

    @property
    def size(self) -> int:
        """How many unseen cells it sees."""
        return len(self.seen)


def unseen_surface(grid: OccupancyGrid, returns: NDArray[np.integer] | None = None) -> Surface:
    """The cells of ``grid`` bounding its known free space that it does not mark: not free, beside
    (4-neighbour) a free cell, and neither they nor their 4 neighbours marked (a cell within one of
    a mark is mapped to within a cell: see the module docstring);
    with ``returns`` (the scans' returns per cell) also the unmarked cells where at least
    :data:`RETURNS` fell beside a cell not free, free or not themselves (a face the rays grazing
    along it cleared, the unknown behind it). Only cells on an
    edge of the free space count (the free field's slope at least :data:`SLOPE`: a stray return or
    a one-cell hole in the open has none)."""
    free = grid.free(FREE)
    cross = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=bool)
    marked = ndimage.binary_dilation(grid.occupied(MARKED), structure=cross)
    beside = ndimage.binary_dilation(free, structure=cross)
    lacking = beside & ~free
    if returns is not None:
        edge = ndimage.binary_dilation(~free, structure=np.ones((3, 3), dtype=bool))
        lacking |= (np.asarray(returns) >= RETURNS) & edge
    cells = np.argwhere(lacking & ~marked)
    field = ndimage.gaussian_filter(free.astype(np.float64), SMOOTH)
    d_row, d_col = np.gradient(field)
    local = np.column_stack((d_col[cells[:, 0], cells[:, 1]], d_row[cells[:, 0], cells[:, 1]]))
    c, s = math.cos(grid.origin.theta), math.sin(grid.origin.theta)
    normals = local @ np.array([[c, s], [-s, c]])
    slope = np.hypot(normals[:, 0], normals[:, 1])
    ok = slope >= SLOPE
    return Surface(grid.cell_to_world(cells[ok]), normals[ok] / slope[ok, None])


def stands(
    grid: OccupancyGrid,
    cmap: CostMap,
    here: tuple[float, float],
    lattice: int = LATTICE,
    *,
    way: CostMap | None = None,
) -> FloatArray:
    """(n, 2) places the robot can stand (known free, not blocked on ``cmap``) on a lattice of
    ``lattice`` cells, joined (8-connected, through cells known free and not blocked on ``way``,
    default ``cmap``) to the free place nearest ``here``: the ones it can reach without crossing
    unknown space. Empty when there is none."""
    open_ = grid.free(FREE) & ~(cmap if way is None else way).blocked
    labels, count = ndimage.label(open_, structure=np.ones((3, 3), dtype=int))
    if count == 0:
        return np.zeros((0, 2))
    cells = np.argwhere(open_)
    xy = grid.cell_to_world(cells)
    nearest = int(np.argmin(np.hypot(xy[:, 0] - here[0], xy[:, 1] - here[1])))
    mine = labels == labels[cells[nearest, 0], cells[nearest, 1]]
    on_lattice = np.zeros(grid.shape, dtype=bool)
    on_lattice[::lattice, ::lattice] = True
    return grid.cell_to_world(np.argwhere(mine & on_lattice & grid.free(FREE) & ~cmap.blocked))


def views(
    grid: OccupancyGrid,
    surface: Surface,
    places: FloatArray,
    *,
    view_range: float = VIEW_RANGE,
    incidence: float = INCIDENCE,
    min_cells: int = MIN_CELLS,
) -> list[View]:
    """What each of ``places`` sees of ``surface`` (see the module docstring), those seeing at
    least ``min_cells`` cells, the most first (ties: the order of ``places``)."""
    if len(surface) == 0 or len(places) == 0:
        return []
    near = cKDTree(surface.points).query_ball_point(places, view_range)
    stand = np.repeat(np.arange(len(places)), [len(n) for n in near])
    cell = np.fromiter((j for n in near for j in n), dtype=np.int64, count=len(stand))
    way = places[stand] - surface.points[cell]
    dist = np.hypot(way[:, 0], way[:, 1])
    facing = np.einsum("ij,ij->i", way, surface.normals[cell]) >= math.cos(incidence) * dist
    keep = facing & (dist >= NEAREST)
    stand, cell = stand[keep], cell[keep]
    res = grid.resolution
    face = surface.points[cell] + 0.5 * res * surface.normals[cell]  # the cell's edge on the free side
    sees = line_of_sight(grid, grid.free(FREE), places[stand], face, stop=res)
    stand, cell = stand[sees], cell[sees]
    counts = np.bincount(stand, minlength=len(places))
    out: list[View] = []
    for k in np.argsort(-counts, kind="stable"):
        if counts[k] < min_cells:
            break
        out.append(View((float(places[k, 0]), float(places[k, 1])), surface.points[cell[stand == k]]))
    return out


def line_of_sight(
    grid: OccupancyGrid, clear: BoolArray, starts: FloatArray, ends: FloatArray, stop: float
) -> BoolArray:
    """Which segments ``starts`` -> ``ends`` (each (n, 2), or ``ends`` one point) pass through
    ``clear`` cells only: sampled every half cell, up to ``stop`` m before their end."""
    if len(starts) == 0:
        return np.zeros(0, dtype=bool)
    step = grid.resolution / 2.0
    way = np.broadcast_to(ends, starts.shape) - starts
    span = np.hypot(way[:, 0], way[:, 1])
    ok = np.ones(len(starts), dtype=bool)
    for f in np.linspace(0.0, 1.0, int(np.ceil(float(span.max()) / step)) + 1):
        cells = grid.world_to_cell(starts + way * f)
        inside = grid.inside(cells)
        free = np.zeros(len(starts), dtype=bool)
        free[inside] = clear[cells[inside, 0], cells[inside, 1]]
        ok &= free | (f * span > span - stop)
    return ok
