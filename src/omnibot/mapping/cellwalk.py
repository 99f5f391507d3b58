"""The cells a straight run crosses, walked exactly: the largest value it meets or its cost.

The planner checks its straight runs with it (a run is free when it crosses no blocked cell, its
clearance is the least of the cells it crosses) and the any-angle shortcuts price a run as A*
prices its steps (:mod:`omnibot.mapping.astar`). Cell units: cell (i, j) spans [i, i+1) x [j, j+1)
in (row, col), its centre at (i + 0.5, j + 0.5).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


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


def line_max(values: FloatArray, r0: float, c0: float, r1: float, c1: float) -> float:
    """The largest of ``values`` over the cells a straight run crosses (inf off the grid)."""
    return float(_traverse(values, r0, c0, r1, c1, 0.0, False))


def line_cost(values: FloatArray, r0: float, c0: float, r1: float, c1: float, weight: float) -> float:
    """A straight run's cost (cell units): its length in each cell times ``1 + weight x`` its value."""
    return float(_traverse(values, r0, c0, r1, c1, weight, True))
