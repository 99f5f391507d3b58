"""The walls of an occupancy grid as local lines: what a scan's returns are matched to, below a cell.

A grid knows a surface only to its cells: a wall is a band of occupied cells, one or two thick (a
rasterised segment marks the cells within half a diagonal of it; a mapped wall, the cells its
returns fell in). A distance field to the nearest occupied cell's centre, bilinearly interpolated,
is zero across the band and half a cell off a wall one cell thick: a scan matched on it is free to
sit anywhere its returns stay in the bands (a robot at rest wandered 1-3 cm scan to scan, issue
25). :class:`SurfaceField` gives every cell the line of the wall nearest to it instead: the
occupied cells on a band's faces (beside a cell that is not occupied) within a ``(2 window + 1)``
square of the nearest such cell, their mean and principal direction; the band's middle, to a
fraction of a cell. A point's residual is its signed distance to that line (the gradient its
normal); where the cells around are no line (a corner, a post, a wall's end) it is the distance to
the nearest face cell's centre.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from omnibot.mapping.grid import OccupancyGrid

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

LINE_SPREAD = 0.15
"""Largest ratio of the face cells' spread across to along their line (variances) that is a line
(a band two cells thick along a 7-cell window: 0.25 / 4 = 0.06; an L's corner: about 1)."""


def faces(occupied: BoolArray) -> BoolArray:
    """Occupied cells with a 4-neighbour that is not (a band's faces: all of a band 1-2 thick)."""
    inner = ndimage.binary_erosion(
        occupied, structure=ndimage.generate_binary_structure(2, 1), border_value=1
    )
    out: BoolArray = occupied & ~inner
    return out


def window_moments(cells: BoolArray, window: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Over the ``(2 window + 1)`` square around each cell: how many ``cells`` (n), their mean offset
    (n, 2: columns, rows) and their covariance (n, 2, 2), in cells from the centre."""
    rows, cols = cells.shape
    padded = np.pad(cells, window).astype(np.float64)
    count = np.zeros((rows, cols))
    first = np.zeros((rows, cols, 2))
    second = np.zeros((rows, cols, 2, 2))
    for dv in range(-window, window + 1):
        for du in range(-window, window + 1):
            hit = padded[window + dv : window + dv + rows, window + du : window + du + cols]
            off = np.array([du, dv], dtype=np.float64)
            count += hit
            first += hit[..., None] * off
            second += hit[..., None, None] * np.outer(off, off)
    mean = first / np.maximum(count, 1.0)[..., None]
    cov = second / np.maximum(count, 1.0)[..., None, None] - mean[..., :, None] * mean[..., None, :]
    return count, mean, cov


def cell_coordinates(grid: OccupancyGrid, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Map-frame points -> continuous cell coordinates (col, row), measured from cell (0, 0)'s centre."""
    o, res = grid.origin, grid.resolution
    c, s = math.cos(o.theta), math.sin(o.theta)
    dx, dy = x - o.x, y - o.y
    return (c * dx + s * dy) / res - 0.5, (-s * dx + c * dy) / res - 0.5


class SurfaceField:
    """The wall nearest to every cell of ``grid`` as a line (see the module docstring)."""

    def __init__(
        self, grid: OccupancyGrid, occupied: int = 65, window: int = 3, max_dist: float = 1.0
    ) -> None:
        face = faces(grid.occupied(occupied))
        if not face.any():
            raise ValueError("the map has no occupied cell to localise against")
        gap, nearest = ndimage.distance_transform_edt(~face, return_indices=True)
        self.grid = grid
        self.reach = np.asarray(gap, dtype=np.float64) * grid.resolution < max_dist
        """Cells within ``max_dist`` of a face: elsewhere a point has no residual."""
        self._nearest = (np.asarray(nearest[0]), np.asarray(nearest[1]))
        count, mean, cov = window_moments(face, window)
        vals, vecs = np.linalg.eigh(cov[face])
        self.line: BoolArray = face.copy()
        """Face cells whose neighbourhood is a line."""
        self.line[face] = (count[face] >= 3) & (vals[:, 0] <= LINE_SPREAD * vals[:, 1])
        rows, cols = np.indices(face.shape)
        # each cell's anchor (the line's mean, or the cell's own centre) and normal, in cells (col, row)
        self.anchor = np.stack((cols, rows), axis=-1).astype(np.float64)
        self.anchor[self.line] += mean[self.line]
        self.normal = np.zeros_like(self.anchor)
        self.normal[self.line] = vecs[self.line[face], :, 0]
        o = grid.origin
        self._c, self._s = math.cos(o.theta), math.sin(o.theta)

    def residuals(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        """At 1-D map-frame points: each one's distance (m; signed along the normal on a line) to
        its nearest wall, that distance's gradient (d/dx, d/dy in the map frame) and whether the
        point is near enough a wall to have one."""
        u, v = cell_coordinates(self.grid, x, y)
        col, row = np.floor(u + 0.5).astype(np.int64), np.floor(v + 0.5).astype(np.int64)
        rows, cols = self.reach.shape
        ok = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
        ok[ok] = self.reach[row[ok], col[ok]]
        r, ku, kv = np.zeros(len(x)), np.zeros(len(x)), np.zeros(len(x))
        fr, fc = self._nearest[0][row[ok], col[ok]], self._nearest[1][row[ok], col[ok]]
        a = self.anchor[fr, fc]
        n = self.normal[fr, fc]
        du, dv = u[ok] - a[:, 0], v[ok] - a[:, 1]
        on_line = self.line[fr, fc]
        dist = np.hypot(du, dv)
        safe = np.maximum(dist, 1e-12)
        r[ok] = np.where(on_line, n[:, 0] * du + n[:, 1] * dv, dist) * self.grid.resolution
        ku[ok] = np.where(on_line, n[:, 0], du / safe)
        kv[ok] = np.where(on_line, n[:, 1], dv / safe)
        gx = self._c * ku - self._s * kv
        gy = self._s * ku + self._c * kv
        return r, gx, gy, ok


__all__ = ["LINE_SPREAD", "SurfaceField", "cell_coordinates", "faces", "window_moments"]
