"""A registration target: points thinned, their local lines' normals, a likelihood grid.

Made once (:meth:`Target.build`) and matched against many times: the scan matcher's correlative
search scores poses on its grid (``exp(-d^2 / 2 sigma^2)`` of the distance to the nearest point),
its ICP pairs points with its points' lines (:mod:`omnibot.mapping.icp`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import distance_transform_edt
from scipy.spatial import cKDTree

from omnibot.errors import ConfigError
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]

NORMAL_NEIGHBOURS = 24
NORMAL_RADIUS = 0.3
"""Neighbours (how many, how far, m) whose line gives a target point its normal."""
LINE_SPREAD = 0.1
"""Largest ratio of the neighbours' spread across to along their line (variances) that is still a line."""


def as_points(data: Scan | ArrayLike, key: str = "points") -> FloatArray:
    """The (n, 2) base-frame points of a scan, or an (n, 2) array checked and made float."""
    if isinstance(data, Scan):
        return data.points("base")
    pts = np.asarray(data, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ConfigError(f"needs an (n, 2) array of points or a Scan, not shape {pts.shape}", key)
    if not np.isfinite(pts).all():
        raise ConfigError("points must be finite", key)
    return pts


def voxel_downsample(points: FloatArray, size: float) -> FloatArray:
    """One point (the mean) per ``size`` x ``size`` cell, in the order the cells are first met."""
    if len(points) == 0:
        return points
    keys = np.floor(points / size).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    sums = np.zeros((len(first), 2))
    np.add.at(sums, inverse, points)
    counts = np.bincount(inverse, minlength=len(first)).astype(np.float64)
    means = sums / counts[:, None]
    out: FloatArray = means[np.argsort(first)]
    return out


def _normals(points: FloatArray, tree: cKDTree) -> FloatArray:
    """Unit normals of the local lines through each point, zero where the neighbourhood is no line.

    The neighbours are the :data:`NORMAL_NEIGHBOURS` nearest within :data:`NORMAL_RADIUS`; a point
    with fewer than four, or whose neighbours spread across as well as along (a corner, a curve
    tighter than the radius, two walls), gets no normal and takes no part in ICP.
    """
    k = min(NORMAL_NEIGHBOURS, len(points))
    dist, idx = tree.query(points, k=k, distance_upper_bound=NORMAL_RADIUS)
    dist, idx = np.asarray(dist).reshape(len(points), k), np.asarray(idx).reshape(len(points), k)
    ok = np.isfinite(dist)
    nb = points[np.where(ok, idx, 0)]
    w = ok.astype(np.float64)[..., None]
    count = w.sum(axis=1)
    mean = (nb * w).sum(axis=1) / np.maximum(count, 1.0)
    d = (nb - mean[:, None, :]) * w
    cov = np.einsum("nki,nkj->nij", d, d)
    vals, vecs = np.linalg.eigh(cov)
    line = (count[:, 0] >= 4) & (vals[:, 0] <= LINE_SPREAD * vals[:, 1])
    normals: FloatArray = np.where(line[:, None], vecs[:, :, 0], 0.0)
    return np.ascontiguousarray(normals)


@dataclass(frozen=True)
class Target:
    """A registration target made once and matched against many times: points, tree, normals, grid."""

    points: FloatArray
    tree: cKDTree = field(repr=False)
    normals: FloatArray = field(repr=False)
    """Unit normal of each point's local line; zero where there is none (see :attr:`lines`)."""
    lines: NDArray[np.bool_] = field(repr=False)
    """Which points lie on a line (have a normal)."""
    grid: FloatArray = field(repr=False)
    """Likelihood of a point in each cell, [row = y, col = x]."""
    origin: tuple[float, float]
    """Map-frame position of cell (0, 0)'s lower-left corner."""
    resolution: float

    @classmethod
    def build(cls, points: FloatArray, resolution: float, sigma: float, margin: float) -> Target:
        """A target from (n, 2) points: thinned to half a cell, gridded ``margin`` beyond them."""
        pts = voxel_downsample(points, resolution / 2.0)
        tree = cKDTree(pts)
        normals = _normals(pts, tree) if len(pts) >= 2 else np.zeros_like(pts)
        lines = np.any(normals != 0.0, axis=1)
        if len(pts):
            lo = pts.min(axis=0) - margin
            hi = pts.max(axis=0) + margin
        else:
            lo, hi = np.zeros(2), np.ones(2)
        cols, rows = (np.ceil((hi - lo) / resolution).astype(np.int64) + 1).tolist()
        hit = np.zeros((rows, cols), dtype=bool)
        cells = np.floor((pts - lo) / resolution).astype(np.int64)
        hit[cells[:, 1], cells[:, 0]] = True
        if hit.any():
            dist = np.asarray(distance_transform_edt(~hit)) * resolution
            grid = np.exp(-0.5 * (dist / sigma) ** 2)
        else:
            grid = np.zeros((rows, cols))
        return cls(
            pts, tree, normals, lines, np.ascontiguousarray(grid), (float(lo[0]), float(lo[1])), resolution
        )
