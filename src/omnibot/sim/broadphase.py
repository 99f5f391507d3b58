"""A fleet's broad phase: which robots may touch, and every robot's footprint placed at once.

:class:`NearPairs` finds the pairs of bodies whose bounding circles meet by sweep and prune along x,
but sweeps only when a body has moved more than half a skin since the last sweep (a Verlet list):
the sweep keeps the pairs within a skin of touching, and between sweeps only those are tested. At
1 kHz a robot at 1 m/s sweeps every 25 steps, so a fleet spread over a room costs one distance test
per body and step. :class:`Footprints` places every body's convex outline with one matrix product
per outline size, the same numbers as :func:`~omnibot.sim.geometry.placed` and
:func:`~omnibot.sim.geometry.closed_edges` body by body.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from math import hypot

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
Row = Sequence[float]
"""A body's pose (x, y, theta)."""

SKIN = 0.05
"""m: how much farther apart than touching a pair may be and still be kept by a sweep."""
_SLACK = 1e-9
"""m: the bounding circles' margin (as the exact test's), and again to absorb rounding in the skin."""


class NearPairs:
    """The pairs of bodies (of reaches ``reaches``, m: their bounding circles' radii) that may touch."""

    def __init__(self, reaches: Sequence[float], skin: float = SKIN) -> None:
        self._reach = [float(r) for r in reaches]
        self._skin = skin
        self._half = skin / 2
        self._anchors: list[tuple[float, float]] = []
        self._candidates: list[tuple[int, int, float]] = []
        """(i, j, squared distance below which their circles meet) of the pairs the last sweep kept."""
        self.sweeps = 0
        """How many sweeps were made."""

    def pairs(self, rows: Sequence[Row]) -> list[tuple[int, int]]:
        """The pairs (i < j, sorted) of bodies at ``rows`` whose bounding circles meet: their centres
        are closer than the sum of their reaches plus 1e-9 m. Conservative; an exact test follows."""
        if len(rows) < 2:
            return []
        if self._stale(rows):
            self._sweep(rows)
        out = []
        for i, j, r2 in self._candidates:
            dx, dy = rows[j][0] - rows[i][0], rows[j][1] - rows[i][1]
            if dx * dx + dy * dy < r2:
                out.append((i, j))
        return out

    def _stale(self, rows: Sequence[Row]) -> bool:
        """True when a body has moved more than half a skin since the last sweep (or none was made)."""
        if len(self._anchors) != len(rows):
            return True
        half = self._half
        for (x, y, _), (x0, y0) in zip(rows, self._anchors, strict=True):
            moved = hypot(x - x0, y - y0)
            if moved > half:
                return True
        return False

    def _sweep(self, rows: Sequence[Row]) -> None:
        """Keep the pairs within a skin of touching: bodies sorted by x, each compared only with those
        after it within its reach plus the largest reach plus the skin."""
        self.sweeps += 1
        self._anchors = [(row[0], row[1]) for row in rows]
        reach, pad = self._reach, self._skin + 2 * _SLACK
        widest = max(reach)
        keyed = sorted((row[0], k) for k, row in enumerate(rows))
        kept = []
        for a in range(len(keyed) - 1):
            xi, i = keyed[a]
            limit = reach[i] + widest + pad
            yi = rows[i][1]
            for xj, j in keyed[a + 1 :]:
                dx = xj - xi
                if dx > limit:
                    break
                dy, r = rows[j][1] - yi, reach[i] + reach[j] + pad
                if dx * dx + dy * dy < r * r:
                    touch = reach[i] + reach[j] + _SLACK
                    kept.append((min(i, j), max(i, j), touch * touch))
        kept.sort()
        self._candidates = kept


class Footprints:
    """Convex outlines (each (V, 2), in its body's frame) placed in the world all at once."""

    def __init__(self, outlines: Sequence[FloatArray]) -> None:
        self.bounds = np.cumsum([0, *(len(o) for o in outlines)])
        """Body k's edges are rows bounds[k]:bounds[k + 1] of :meth:`place`'s array."""
        by_size: dict[int, list[int]] = {}
        for k, outline in enumerate(outlines):
            by_size.setdefault(len(outline), []).append(k)
        self._groups = [
            (
                members,
                np.stack([np.asarray(outlines[k], dtype=np.float64) for k in members]),
                np.concatenate([np.arange(self.bounds[k], self.bounds[k + 1]) for k in members]),
                np.roll(np.arange(size), -1),
            )
            for size, members in by_size.items()
        ]
        self._edges = np.zeros((int(self.bounds[-1]), 4))

    def place(self, rows: Sequence[Row]) -> FloatArray:
        """The edges ``(E, 4)`` (x0, y0, x1, y1) of every outline with its body at ``rows[k]`` (x, y,
        theta), body after body; a new array. Body k's rows are, bit for bit,
        ``closed_edges(placed(outline, x, y, theta))``: the same product of the same numbers."""
        edges = self._edges.copy()
        for members, outlines, at, following in self._groups:
            turns, shifts = [], []
            for k in members:
                x, y, theta = rows[k][:3]
                c, s = math.cos(theta), math.sin(theta)
                turns.append((c, s, -s, c))
                shifts.append((x, y))
            n, size = outlines.shape[:2]
            vertices = outlines @ np.array(turns).reshape(n, 2, 2) + np.array(shifts).reshape(n, 1, 2)
            edges[at] = np.concatenate((vertices, vertices[:, following]), axis=2).reshape(n * size, 4)
        return edges
