"""The grid planner: A* on the cost map's cells, then any-angle shortcuts.

A* on the 8-connected cells (compiled with numba; no corner cutting), each step costing its length
times ``1 + weight * cost``, so the path keeps away from walls where there is room; then
line-of-sight shortcutting: a straight run replaces a stretch of the A* path when it crosses no
blocked cell and comes no closer to a wall (no higher cost) than that stretch did. Deterministic.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from omnibot.mapping.cellwalk import line_cost
from omnibot.mapping.costmap import CostMap

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


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


def shortcut(
    cmap: CostMap,
    cells: NDArray[np.int64],
    first: tuple[float, float],
    last: tuple[float, float],
    weight: float,
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
    local = np.array([cmap.local((float(x), float(y))) for x, y in centres])
    field = np.where(cmap.blocked, np.inf, cmap.cost)
    c = field[cells[:, 0], cells[:, 1]]
    steps = np.hypot(*np.diff(local, axis=0).T) * (1.0 + weight * 0.5 * (c[:-1] + c[1:]))
    along = np.concatenate(([0.0], np.cumsum(steps)))  # the chain's cost to each cell
    kept = [0]
    i, n = 0, len(cells)
    while i < n - 1:
        j_best = i + 1
        for j in range(n - 1, i + 1, -1):
            run = line_cost(field, local[i, 0], local[i, 1], local[j, 0], local[j, 1], weight)
            if run <= (along[j] - along[i]) * (1.0 + 1e-9) + 1e-9:
                j_best = j
                break
        kept.append(j_best)
        i = j_best
    return np.asarray(centres[kept], dtype=np.float64)
