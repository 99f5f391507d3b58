"""The correlative search (Olson's CSM, cartographer's real-time CSM): the best pose of a lattice.

Every pose of an x, y, theta lattice around the initial guess (steps of one cell of the target's
likelihood grid and of the angle that moves the farthest source point by one cell) is scored by
the mean likelihood of the moved source points (a compiled loop), with a slight preference for
poses near the guess so that a flat score (a featureless corridor) keeps the guess.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from omnibot.mapping.se2 import wrap
from omnibot.mapping.target import Target
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@njit(cache=True)
def _correlate(
    grid: FloatArray,
    cells: IntArray,
    nxy: int,
    dtheta: float,
    weight_xy: float,
    weight_theta: float,
    res: float,
) -> FloatArray:  # pragma: no cover - compiled
    """Score of every lattice pose: cells (A, n, 2) are the moved points' (col, row) per angle."""
    n_a = cells.shape[0]
    n = cells.shape[1]
    rows = grid.shape[0]
    cols = grid.shape[1]
    side = 2 * nxy + 1
    out = np.zeros((n_a, side, side))
    half = n_a // 2
    for a in range(n_a):
        rot_pen = weight_theta * abs(a - half) * dtheta
        for i in range(side):
            dx = i - nxy
            for j in range(side):
                dy = j - nxy
                total = 0.0
                for k in range(n):
                    c = cells[a, k, 0] + dx
                    r = cells[a, k, 1] + dy
                    if 0 <= r < rows and 0 <= c < cols:
                        total += grid[r, c]
                pen = rot_pen + weight_xy * math.sqrt(float(dx * dx + dy * dy)) * res
                out[a, i, j] = total / n * math.exp(-pen)
    return out


def correlative_search(
    src: FloatArray,
    tgt: Target,
    initial: Pose2D,
    search_xy: float,
    search_theta: float,
    weight_xy: float,
    weight_theta: float,
) -> tuple[Pose2D, float]:
    """The best pose of the lattice around ``initial`` (half-widths ``search_xy`` m, ``search_theta``
    rad; both 0: ``initial`` itself, score 0) and its score, a pose's mean likelihood discounted by
    ``exp(-(weight_xy * distance + weight_theta * turn))`` from ``initial``."""
    if search_xy <= 0 and search_theta <= 0:
        return initial, 0.0
    res = tgt.resolution
    reach = float(np.max(np.hypot(src[:, 0], src[:, 1])))
    step = math.acos(max(-1.0, 1.0 - res * res / (2.0 * max(reach, res) ** 2)))
    n_theta = round(search_theta / step) if search_theta > 0 else 0
    nxy = round(search_xy / res)
    thetas = initial.theta + step * np.arange(-n_theta, n_theta + 1)
    c, s = np.cos(thetas), np.sin(thetas)
    x = c[:, None] * src[None, :, 0] - s[:, None] * src[None, :, 1] + initial.x
    y = s[:, None] * src[None, :, 0] + c[:, None] * src[None, :, 1] + initial.y
    cells = np.empty((len(thetas), len(src), 2), dtype=np.int64)
    cells[..., 0] = np.floor((x - tgt.origin[0]) / res)
    cells[..., 1] = np.floor((y - tgt.origin[1]) / res)
    scores = _correlate(tgt.grid, cells, nxy, step, weight_xy, weight_theta, res)
    a, i, j = np.unravel_index(int(np.argmax(scores)), scores.shape)
    best = Pose2D(initial.x + (i - nxy) * res, initial.y + (j - nxy) * res, wrap(float(thetas[a])))
    return best, float(scores[a, i, j])
