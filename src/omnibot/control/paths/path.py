"""A path: poses (x, y, theta) in order, with optional time stamps and speeds, and its geometry.

``theta`` is the body heading to hold at each point (unwrapped on construction, so interpolation
never turns the long way). Whether the heading follows the path or stays fixed is simply what the
file says: a constant theta column holds the heading, a tangent one turns with the path.

Projection (closest point, signed cross-track error, arc length) works on the polyline; consecutive
points at the same place (a turn in place) are zero-length segments and are skipped by it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Projection:
    """The closest point of a path to a position."""

    s: float
    """Arc length of the closest point, m."""
    index: int
    """Segment index (the closest point lies between points index and index + 1)."""
    cross: float
    """Signed distance, m: positive when the position is left of the path's direction."""
    x: float
    y: float
    tangent: tuple[float, float]
    """Unit direction of the segment."""


@dataclass(frozen=True, eq=False)
class Path:
    """Poses along a path; ``t`` (s) and ``v`` (m/s) optional, as in the CSV file."""

    x: FloatArray
    y: FloatArray
    theta: FloatArray
    t: FloatArray | None = None
    v: FloatArray | None = None
    s: FloatArray = field(init=False)
    """Cumulative arc length, m (s[0] = 0)."""

    def __post_init__(self) -> None:
        n = len(self.x)
        cols = {"x": self.x, "y": self.y, "theta": self.theta, "t": self.t, "v": self.v}
        for name, col in cols.items():
            if col is None:
                continue
            arr = np.asarray(col, dtype=float)
            if arr.ndim != 1 or len(arr) != n:
                raise ValueError(f"path column {name} has {arr.size} values, x has {n}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"path column {name} has a value that is not a finite number")
            object.__setattr__(self, name, arr)
        if n < 1:
            raise ValueError("a path needs at least one point")
        object.__setattr__(self, "theta", np.unwrap(self.theta) if n > 1 else self.theta)
        steps = np.hypot(np.diff(self.x), np.diff(self.y))
        object.__setattr__(self, "s", np.concatenate(([0.0], np.cumsum(steps))))

    @classmethod
    def from_points(
        cls,
        points: FloatArray | list[tuple[float, float]],
        theta: FloatArray | float | None = None,
        t: FloatArray | None = None,
        v: FloatArray | None = None,
    ) -> Path:
        """From (x, y) rows; ``theta`` an array, one fixed heading, or None for the tangent heading."""
        xy = np.asarray(points, dtype=float).reshape(-1, 2)
        if theta is None:
            th = tangent_headings(xy[:, 0], xy[:, 1])
        elif np.ndim(theta) == 0:
            th = np.full(len(xy), float(theta))
        else:
            th = np.asarray(theta, dtype=float)
        return cls(xy[:, 0].copy(), xy[:, 1].copy(), th, t, v)

    def __len__(self) -> int:
        return len(self.x)

    @property
    def length(self) -> float:
        """Total arc length, m."""
        return float(self.s[-1])

    @property
    def points(self) -> FloatArray:
        """(n, 2) x, y."""
        return np.column_stack((self.x, self.y))

    @property
    def start(self) -> tuple[float, float, float]:
        """The first pose ``(x, y, theta)`` (m, m, rad)."""
        return float(self.x[0]), float(self.y[0]), float(self.theta[0])

    @property
    def end(self) -> tuple[float, float, float]:
        """The last pose ``(x, y, theta)`` (m, m, rad)."""
        return float(self.x[-1]), float(self.y[-1]), float(self.theta[-1])

    def with_columns(
        self, *, theta: FloatArray | None = None, t: FloatArray | None = None, v: FloatArray | None = None
    ) -> Path:
        """A copy with some columns replaced (``t``/``v`` set to None are dropped only if given)."""
        return Path(
            self.x,
            self.y,
            self.theta if theta is None else theta,
            self.t if t is None else t,
            self.v if v is None else v,
        )

    def without_speed(self) -> Path:
        """The same path without its speed column (timestamps kept)."""
        return Path(self.x, self.y, self.theta, self.t, None)

    def at(self, s: float) -> tuple[float, float, float]:
        """Pose at arc length ``s`` (clamped to the path), linear between points."""
        if len(self) == 1:
            return self.start
        sv = min(max(s, 0.0), self.length)
        i = int(np.searchsorted(self.s, sv, side="right")) - 1
        i = min(max(i, 0), len(self) - 2)
        # skip zero-length segments (turns in place): take the heading at their end
        ds = self.s[i + 1] - self.s[i]
        f = 0.0 if ds <= 0 else (sv - self.s[i]) / ds
        return (
            float(self.x[i] + f * (self.x[i + 1] - self.x[i])),
            float(self.y[i] + f * (self.y[i + 1] - self.y[i])),
            float(self.theta[i] + f * (self.theta[i + 1] - self.theta[i])),
        )

    def index_at(self, s: float) -> int:
        """Index of the segment containing arc length ``s`` (clamped)."""
        i = int(np.searchsorted(self.s, s, side="right")) - 1
        return min(max(i, 0), max(len(self) - 2, 0))

    def project_near(
        self, x: float, y: float, s: float, behind: float = 0.1, ahead: float = 0.5
    ) -> Projection:
        """The closest point among the segments from ``s - behind`` to ``s + ahead`` (arc length)."""
        return self.project(x, y, self.index_at(s - behind), self.index_at(s + ahead) + 2)

    def heading_at(self, s: float) -> float:
        """Heading at arc length ``s``, rad (clamped to the path, linear between points)."""
        return self.at(s)[2]

    def direction_at(self, s: float) -> tuple[float, float]:
        """Unit direction of travel at arc length ``s``."""
        if len(self) < 2 or self.length <= 0:
            return (math.cos(self.theta[0]), math.sin(self.theta[0]))
        sv = min(max(s, 0.0), self.length)
        i = int(np.searchsorted(self.s, sv, side="right")) - 1
        i = min(max(i, 0), len(self) - 2)
        while i < len(self) - 2 and self.s[i + 1] - self.s[i] <= 0:
            i += 1
        while i > 0 and self.s[i + 1] - self.s[i] <= 0:
            i -= 1
        dx, dy = self.x[i + 1] - self.x[i], self.y[i + 1] - self.y[i]
        n = math.hypot(dx, dy)
        if n <= 0:
            return (math.cos(self.theta[i]), math.sin(self.theta[i]))
        return (float(dx / n), float(dy / n))

    def project(self, x: float, y: float, lo: int = 0, hi: int | None = None) -> Projection:
        """The closest point to (x, y) among segments lo..hi-1 (default: all)."""
        n = len(self)
        if n == 1:
            return Projection(0.0, 0, 0.0, float(self.x[0]), float(self.y[0]), (1.0, 0.0))
        hi = n - 1 if hi is None else min(hi, n - 1)
        lo = min(max(lo, 0), hi - 1)
        x0, y0 = self.x[lo:hi], self.y[lo:hi]
        dx, dy = self.x[lo + 1 : hi + 1] - x0, self.y[lo + 1 : hi + 1] - y0
        L2 = dx * dx + dy * dy
        safe = np.where(L2 > 0, L2, 1.0)
        f = np.clip(((x - x0) * dx + (y - y0) * dy) / safe, 0.0, 1.0)
        f = np.where(L2 > 0, f, 0.0)
        px, py = x0 + f * dx, y0 + f * dy
        d2 = (x - px) ** 2 + (y - py) ** 2
        d2 = np.where(L2 > 0, d2, np.inf) if np.any(L2 > 0) else d2
        k = int(np.argmin(d2))
        i = lo + k
        L = math.sqrt(float(L2[k]))
        tx, ty = (float(dx[k]) / L, float(dy[k]) / L) if L > 0 else (1.0, 0.0)
        cross = tx * (y - float(py[k])) - ty * (x - float(px[k]))
        return Projection(float(self.s[i] + f[k] * L), i, cross, float(px[k]), float(py[k]), (tx, ty))

    def distances(self, xy: ArrayLike) -> FloatArray:
        """Unsigned distance from each (x, y) row to the path (the whole polyline)."""
        return self.nearest(xy)[0]

    def nearest(self, xy: ArrayLike, chunk: int = 256) -> tuple[FloatArray, FloatArray]:
        """For each (x, y) row: the distance to the path (whole polyline) and the arc length there."""
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        if len(self) == 1:
            return np.hypot(pts[:, 0] - self.x[0], pts[:, 1] - self.y[0]), np.zeros(len(pts))
        x0, y0 = self.x[:-1], self.y[:-1]
        dx, dy = np.diff(self.x), np.diff(self.y)
        L2 = dx * dx + dy * dy
        safe = np.where(L2 > 0, L2, 1.0)
        dist = np.empty(len(pts))
        arc = np.empty(len(pts))
        for a in range(0, len(pts), chunk):
            p = pts[a : a + chunk]
            rx = p[:, :1] - x0[None, :]
            ry = p[:, 1:2] - y0[None, :]
            f = np.clip((rx * dx + ry * dy) / safe, 0.0, 1.0)
            ex, ey = rx - f * dx, ry - f * dy
            d2 = ex * ex + ey * ey
            k = np.argmin(d2, axis=1)
            rows = np.arange(len(p))
            dist[a : a + chunk] = np.sqrt(d2[rows, k])
            arc[a : a + chunk] = self.s[k] + f[rows, k] * np.sqrt(L2[k])
        return dist, arc


def tangent_headings(x: FloatArray, y: FloatArray) -> FloatArray:
    """Direction of travel at each point (central differences; ends one-sided), unwrapped."""
    n = len(x)
    if n < 2:
        return np.zeros(n)
    gx, gy = np.gradient(np.asarray(x, float)), np.gradient(np.asarray(y, float))
    th = np.arctan2(gy, gx)
    return np.unwrap(th)
