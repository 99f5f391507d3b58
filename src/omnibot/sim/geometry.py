"""Plane geometry of the simulated world (numpy, or the compiled kernels of :mod:`omnibot.sim.kernels`):
polygons packed for the kernels, outlines placed at a pose, closed edges, orientation and convexity,
convex hulls, a sonar cone's nearest edge and points in a polygon."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.sim import jit

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
Point = tuple[float, float]


def pack_polygons(polygons: list[FloatArray]) -> tuple[FloatArray, IntArray]:
    """Polygons packed for the kernels: all vertices (V, 2) and offsets (K+1,) of each polygon's first."""
    sizes = [len(p) for p in polygons]
    verts = np.vstack(polygons) if polygons else np.zeros((0, 2))
    offsets = np.concatenate(([0], np.cumsum(sizes))).astype(np.int64)
    return np.ascontiguousarray(verts, dtype=float), offsets


def cone_range(
    segments: FloatArray, x: float, y: float, heading: float, cone: float, max_range: float = math.inf
) -> float:
    """Distance from (x, y) to the nearest point of any edge ``(K, 4)`` within ``heading +- cone/2``.

    inf if none within ``max_range``; ``cone`` (rad) must be below pi. Exact: each edge is clipped
    to the cone, then its point nearest the apex is taken (:func:`omnibot.sim.kernels.cone_distance`).
    """
    if not 0 < cone < math.pi:
        raise ValueError(f"cone must be in (0, pi), got {cone}")
    edges = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    return float(
        jit.active.cone_distance(edges, float(x), float(y), float(heading), float(cone), float(max_range))
    )


def placed(outline: FloatArray, x: float, y: float, theta: float) -> FloatArray:
    """A body-frame outline (V, 2) placed at pose (x, y, theta): its world-frame vertices."""
    c, s = math.cos(theta), math.sin(theta)
    return np.asarray(outline @ np.array([[c, s], [-s, c]]) + np.array([x, y]), dtype=float)


def closed_edges(vertices: FloatArray) -> FloatArray:
    """The edges ``(V, 4)`` of a closed polygon, ``x0, y0, x1, y1``."""
    return np.hstack((vertices, np.roll(vertices, -1, axis=0)))


def ccw(v: FloatArray) -> FloatArray:
    """The polygon in counter-clockwise order."""
    x, y = v[:, 0], v[:, 1]
    area2 = float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    return v if area2 >= 0 else v[::-1].copy()


def is_convex(v: FloatArray) -> bool:
    """True if the closed polygon (V, 2) is convex."""
    e = np.roll(v, -1, axis=0) - v
    cross = e[:, 0] * np.roll(e, -1, axis=0)[:, 1] - e[:, 1] * np.roll(e, -1, axis=0)[:, 0]
    return bool(np.all(cross >= -1e-12) or np.all(cross <= 1e-12))


def convex_hull(points: ArrayLike) -> FloatArray:
    """Counter-clockwise convex hull (Andrew's monotone chain) of (P, 2) points."""
    pts = sorted({(float(x), float(y)) for x, y in np.asarray(points, dtype=float).reshape(-1, 2)})
    if len(pts) < 3:
        return np.array(pts, dtype=float)

    def half(seq: list[Point]) -> list[Point]:
        out: list[Point] = []
        for p in seq:
            while len(out) >= 2 and (
                (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def points_in_polygon(points: ArrayLike, polygon: ArrayLike) -> NDArray[np.bool_]:
    """Crossing-number test of (P, 2) points against a closed (V, 2) polygon."""
    flat = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
    verts, offsets = pack_polygons([np.asarray(polygon, dtype=float)])
    ids = np.zeros(len(flat), dtype=np.int64)
    jit.active.surface_probe(flat, verts, offsets, np.ones(1, dtype=np.int64), ids)
    return np.asarray(ids == 1, dtype=bool)
