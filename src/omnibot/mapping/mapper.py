"""An occupancy-grid mapper: (scan, pose) pairs -> log-odds grid -> :class:`OccupancyGrid`.

Each ray of a :class:`~omnibot.scan.Scan` taken at a robot pose (map frame) updates the cells it
crosses in log-odds: ``l_free`` on every cell between the scanner and the return, ``l_occ`` on the
cell holding the return. A ray without a return (``inf``, or a range beyond ``range_max``) clears
free space up to ``min(range_max, max_clear)`` and marks nothing occupied; a range below
``range_min`` is ignored. Within one scan a cell is updated at most once and a hit wins over a free
pass (near the scanner dozens of rays cross the same cells; counting each would make one scan
certain). Log-odds are clamped to ``[l_min, l_max]`` so the map can change its mind.

The ray traversal (Amanatides & Woo's grid walk) is compiled with numba; the vectorised numpy
alternative, :func:`ray_cells_numpy`, is kept for the benchmark that picked the compiled one
(``benchmarks/mapping_mapper.py``, BENCHMARKS.md).

The grid grows to fit what the scans reach (in steps of ``grow`` metres, its origin on a multiple of
the resolution) unless fixed ``bounds`` are given, in which case returns outside are clipped to
the free rays inside. :func:`build_map` rebuilds a map from a list of (scan, pose) pairs in one go
(the bounds taken first, so the grid is allocated once): what a SLAM does after a loop closure.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.mapping.grid import UNKNOWN, OccupancyGrid
from omnibot.mapping.se2 import compose
from omnibot.motion import Pose2D
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]


def logit(p: float) -> float:
    """log(p / (1 - p))."""
    return math.log(p / (1.0 - p))


def ray_ends(
    scan: Scan, pose: Pose2D, max_clear: float
) -> tuple[float, float, FloatArray, NDArray[np.bool_]]:
    """Scanner origin (x, y), (n, 2) ray end points in the map frame and which of them are hits.

    Returns end at their range; rays without one end at ``min(range_max, max_clear)`` (not hits);
    rays shorter than ``range_min`` are dropped.
    """
    sp = compose(pose, scan.mount)
    r = scan.ranges
    hit = scan.valid
    clear = min(scan.range_max, max_clear)
    keep = hit | ((~np.isfinite(r) | (r > scan.range_max)) & (clear > 0.0))
    dist = np.where(hit, r, clear)[keep]
    a = scan.angles[keep] + sp.theta
    ends = np.column_stack((sp.x + dist * np.cos(a), sp.y + dist * np.sin(a)))
    return sp.x, sp.y, ends, hit[keep]


@numba.njit(cache=True, nogil=True)
def _integrate(
    logodds: NDArray[np.float32],
    stamp: NDArray[np.int32],
    counts: NDArray[np.int32],
    ox: float,
    oy: float,
    ends: FloatArray,
    hits: NDArray[np.bool_],
    weights: FloatArray,
    walks: FloatArray,
    res: float,
    l_free: float,
    l_occ: float,
    l_min: float,
    l_max: float,
    scan_id: int,
) -> None:
    rows, cols = logodds.shape
    # hits first: a hit cell is not cleared by another ray of the same scan
    for k in range(ends.shape[0]):
        if not hits[k]:
            continue
        c = math.floor(ends[k, 0] / res)
        r = math.floor(ends[k, 1] / res)
        if 0 <= r < rows and 0 <= c < cols and stamp[r, c] != scan_id:
            stamp[r, c] = scan_id
            counts[r, c, 0] += 1
            v = logodds[r, c] + l_occ * weights[k]
            logodds[r, c] = min(v, l_max)
    fx, fy = ox / res, oy / res
    for k in range(ends.shape[0]):
        tx, ty = walks[k, 0] / res, walks[k, 1] / res
        c, r = math.floor(fx), math.floor(fy)
        ce, re = math.floor(tx), math.floor(ty)
        dx, dy = tx - fx, ty - fy
        sx = 1 if dx > 0 else -1
        sy = 1 if dy > 0 else -1
        inf = 1e30
        tdx = abs(1.0 / dx) if dx != 0 else inf
        tdy = abs(1.0 / dy) if dy != 0 else inf
        tmx = ((c + 1 - fx) if dx > 0 else (fx - c)) * tdx if dx != 0 else inf
        tmy = ((r + 1 - fy) if dy > 0 else (fy - r)) * tdy if dy != 0 else inf
        steps = abs(ce - c) + abs(re - r)
        last = hits[k]  # a miss ray clears its last cell too; a hit ray stops short of its walk's end
        for i in range(steps + 1):
            if i == steps and last:
                break
            if 0 <= r < rows and 0 <= c < cols and stamp[r, c] != scan_id:
                stamp[r, c] = scan_id
                counts[r, c, 1] += 1
                v = logodds[r, c] + l_free
                logodds[r, c] = max(v, l_min)
            if tmx < tmy:
                tmx += tdx
                c += sx
            else:
                tmy += tdy
                r += sy


def ray_cells_numpy(
    ox: float, oy: float, ends: FloatArray, hits: NDArray[np.bool_], res: float, shape: tuple[int, int]
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Flat indices of the cells the rays pass and of the cells their hits fall in (grid-local
    coordinates: the grid's lower-left corner at 0, 0).

    The vectorised alternative to the compiled walk (no per-ray Python loop): every ray sampled at
    a third of a cell, cells deduplicated; a hit ray's end cell is not among its free cells. It may
    miss a cell a ray only clips at a corner.
    """
    rows, cols = shape
    d = ends - (ox, oy)
    length = np.hypot(d[:, 0], d[:, 1])
    n = np.maximum(np.ceil(length / (res / 3.0)).astype(np.int64), 1) + 1
    ray = np.repeat(np.arange(len(ends)), n)
    start = np.cumsum(n) - n
    t = (np.arange(int(n.sum())) - np.repeat(start, n)) / np.repeat(n - 1, n)
    c = np.floor((ox + d[ray, 0] * t) / res).astype(np.int64)
    r = np.floor((oy + d[ray, 1] * t) / res).astype(np.int64)
    ce = np.floor(ends[:, 0] / res).astype(np.int64)
    re = np.floor(ends[:, 1] / res).astype(np.int64)
    own_end = hits[ray] & (r == re[ray]) & (c == ce[ray])
    keep = (r >= 0) & (r < rows) & (c >= 0) & (c < cols) & ~own_end
    inside = hits & (re >= 0) & (re < rows) & (ce >= 0) & (ce < cols)
    return np.unique(r[keep] * cols + c[keep]), np.unique(re[inside] * cols + ce[inside])


class OccupancyMapper:
    """Integrates (scan, pose) pairs into a log-odds occupancy grid (see the module docstring).

    ``bounds`` ``(x_min, y_min, x_max, y_max)`` fixes the grid; without it the grid grows to fit.
    ``p_occ``/``p_free`` are the probabilities one hit / one free pass stand for, ``p_min``/``p_max``
    the clamps; ``max_clear`` (m) how far a ray without a return clears. ``reflect``: a cell that
    at least ``reflect_hits`` scans hit, and that was hit by at least this share of the scans that
    reached it (hit or passed through it), is at least ``reflect_level`` whatever its log-odds (a
    counting, "reflection" model beside the log-odds: a wall on a cell boundary, which the rays
    grazing past it along its face pass through far more often than they end in it, stays
    marked); None: the log-odds alone.
    """

    def __init__(
        self,
        resolution: float = 0.05,
        *,
        bounds: tuple[float, float, float, float] | None = None,
        p_occ: float = 0.7,
        p_free: float = 0.4,
        p_min: float = 0.12,
        p_max: float = 0.97,
        max_clear: float = 4.0,
        grow: float = 2.0,
        frame: str = "map",
        reflect: float | None = None,
        reflect_hits: int = 2,
        reflect_level: int = 65,
    ) -> None:
        if not (math.isfinite(resolution) and resolution > 0):
            raise ValueError(f"resolution must be a positive length, not {resolution}")
        for name, p in (("p_occ", p_occ), ("p_free", p_free), ("p_min", p_min), ("p_max", p_max)):
            if not 0.0 < p < 1.0:
                raise ValueError(f"{name} must lie in (0, 1), not {p}")
        if not (p_free < 0.5 < p_occ and p_min < 0.5 < p_max):
            raise ValueError("need p_free < 0.5 < p_occ and p_min < 0.5 < p_max")
        if reflect is not None and not 0.0 < reflect <= 1.0:
            raise ValueError(f"reflect must lie in (0, 1], not {reflect}")
        self.reflect, self.reflect_hits, self.reflect_level = reflect, int(reflect_hits), int(reflect_level)
        self.resolution = float(resolution)
        self.l_occ, self.l_free = logit(p_occ), logit(p_free)
        self.l_min, self.l_max = logit(p_min), logit(p_max)
        self.max_clear = float(max_clear)
        self.grow = max(float(grow), resolution)
        self.frame = frame
        self._fixed = bounds is not None
        self._col0 = self._row0 = 0  # grid cell (0, 0) is world cell (row0, col0) of the resolution lattice
        self._logodds = np.zeros((0, 0), dtype=np.float32)
        self._stamp = np.zeros((0, 0), dtype=np.int32)
        self._counts = np.zeros((0, 0, 2), dtype=np.int32)  # per cell: scans that hit it, that passed it
        self._scans = 0
        if bounds is not None:
            x0, y0, x1, y1 = bounds
            if not (x1 > x0 and y1 > y0):
                raise ValueError(f"bounds must be (x_min, y_min, x_max, y_max) with max > min, not {bounds}")
            self._resize(x0, y0, x1, y1, exact=True)

    # ------------------------------------------------------------------ grid extent

    def _resize(self, x0: float, y0: float, x1: float, y1: float, exact: bool = False) -> None:
        res = self.resolution
        pad = 0.0 if exact else self.grow
        c0 = math.floor((x0 - pad) / res)
        r0 = math.floor((y0 - pad) / res)
        c1 = math.ceil((x1 + pad) / res)
        r1 = math.ceil((y1 + pad) / res)
        if self._logodds.size:
            c0, r0 = min(c0, self._col0), min(r0, self._row0)
            c1 = max(c1, self._col0 + self._logodds.shape[1])
            r1 = max(r1, self._row0 + self._logodds.shape[0])
        shape = (r1 - r0, c1 - c0)
        lo, st, se = np.zeros(shape, np.float32), np.zeros(shape, np.int32), np.zeros((*shape, 2), np.int32)
        if self._logodds.size:
            dr, dc = self._row0 - r0, self._col0 - c0
            h, w = self._logodds.shape
            lo[dr : dr + h, dc : dc + w] = self._logodds
            st[dr : dr + h, dc : dc + w] = self._stamp
            se[dr : dr + h, dc : dc + w] = self._counts
        self._logodds, self._stamp, self._counts = lo, st, se
        self._row0, self._col0 = r0, c0

    def _fit(self, x0: float, y0: float, x1: float, y1: float) -> None:
        if self._fixed:
            return
        res = self.resolution
        if self._logodds.size:
            h, w = self._logodds.shape
            gx0, gy0 = self._col0 * res, self._row0 * res
            if x0 >= gx0 and y0 >= gy0 and x1 < gx0 + w * res and y1 < gy0 + h * res:
                return
        self._resize(x0, y0, x1, y1)

    # ------------------------------------------------------------------ integration

    def add(self, scan: Scan, pose: Pose2D) -> None:
        """Integrate one scan taken with the robot at ``pose`` (map frame)."""
        ox, oy, ends, hits = ray_ends(scan, pose, self.max_clear)
        if len(ends) == 0:
            return
        self._fit(
            min(ox, float(ends[:, 0].min())),
            min(oy, float(ends[:, 1].min())),
            max(ox, float(ends[:, 0].max())),
            max(oy, float(ends[:, 1].max())),
        )
        self._integrate(ox, oy, ends, hits)

    def add_points(
        self,
        origin: tuple[float, float],
        points: ArrayLike,
        clear: ArrayLike | None = None,
        weights: ArrayLike | None = None,
        short: ArrayLike | float = 0.0,
    ) -> None:
        """Integrate returns given as (n, 2) map-frame ``points`` seen from ``origin`` (the scanner's
        position, map frame): free from the origin to each point, occupied at it; ``clear`` (m, 2)
        end points of rays that only clear (returns too uncertain to mark a cell, shortened by their
        uncertainty); ``weights`` (n,) scale each hit's evidence (1: a hit as :meth:`add` counts it),
        e.g. less for a far, noisier return; ``short`` (m, one for all or (n,)) how far short of
        its return each hit ray stops clearing: the cell of a point ``short`` before the return and
        those beyond it are not cleared by that ray (a return an uncertain distance behind a wall's
        face, or a wall seen from both sides, must not clear the wall's own cells). For returns
        already corrected for the scanner's motion (:func:`omnibot.mapping.deskew.scan_points`)."""
        hit = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        free = np.zeros((0, 2)) if clear is None else np.asarray(clear, dtype=np.float64).reshape(-1, 2)
        ends = np.concatenate((hit, free))
        if len(ends) == 0:
            return
        ox, oy = float(origin[0]), float(origin[1])
        self._fit(
            min(ox, float(ends[:, 0].min())),
            min(oy, float(ends[:, 1].min())),
            max(ox, float(ends[:, 0].max())),
            max(oy, float(ends[:, 1].max())),
        )
        hits = np.zeros(len(ends), dtype=np.bool_)
        hits[: len(hit)] = True
        w = np.ones(len(ends))
        if weights is not None:
            w[: len(hit)] = np.asarray(weights, dtype=np.float64).reshape(-1)
        walks = ends.copy()
        cut = np.broadcast_to(np.asarray(short, dtype=np.float64), (len(hit),))
        if len(hit) and np.any(cut > 0):
            rays = hit - (ox, oy)
            length = np.hypot(rays[:, 0], rays[:, 1])
            keep = np.maximum(length - cut, 0.0) / np.maximum(length, 1e-12)
            walks[: len(hit)] = (ox, oy) + rays * keep[:, None]
        self._integrate(ox, oy, ends, hits, w, walks)

    def _integrate(
        self,
        ox: float,
        oy: float,
        ends: FloatArray,
        hits: NDArray[np.bool_],
        weights: FloatArray | None = None,
        walks: FloatArray | None = None,
    ) -> None:
        """Each ray marks its ``ends`` (hits) and clears up to its ``walks`` point (None: its end)."""
        self._scans += 1
        if weights is None:
            weights = np.ones(len(ends))
        if walks is None:
            walks = ends
        shift = np.array([self._col0, self._row0], dtype=np.float64) * self.resolution
        _integrate(
            self._logodds,
            self._stamp,
            self._counts,
            ox - shift[0],
            oy - shift[1],
            np.ascontiguousarray(ends - shift),
            np.ascontiguousarray(hits),
            np.ascontiguousarray(weights, dtype=np.float64),
            np.ascontiguousarray(walks - shift),
            self.resolution,
            self.l_free,
            self.l_occ,
            self.l_min,
            self.l_max,
            self._scans,
        )

    def extend(self, pairs: Iterable[tuple[Scan, Pose2D]]) -> None:
        """Integrate every (scan, pose) pair, sizing the grid once for all of them first."""
        rays = [(s, p, ray_ends(s, p, self.max_clear)) for s, p in pairs]
        rays = [r for r in rays if len(r[2][2])]
        if not rays:
            return
        lo = np.min([np.minimum(e.min(axis=0), (x, y)) for _, _, (x, y, e, _) in rays], axis=0)
        hi = np.max([np.maximum(e.max(axis=0), (x, y)) for _, _, (x, y, e, _) in rays], axis=0)
        self._fit(float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
        for _, _, (x, y, e, h) in rays:
            self._integrate(x, y, e, h)

    def rebuild(self, pairs: Iterable[tuple[Scan, Pose2D]]) -> None:
        """Forget every scan and integrate ``pairs`` afresh (e.g. their poses after a loop closure)."""
        self.clear()
        self.extend(pairs)

    def clear(self) -> None:
        """Forget every scan (the grid's extent is kept)."""
        self._logodds[:] = 0.0
        self._stamp[:] = 0
        self._counts[:] = 0
        self._scans = 0

    @property
    def scans(self) -> int:
        """Scans integrated so far."""
        return self._scans

    @property
    def logodds(self) -> NDArray[np.float32]:
        """The log-odds of every cell (rows bottom-up, as the grid); a view, do not write."""
        return self._logodds

    @property
    def origin(self) -> Pose2D:
        """Lower-left corner of cell (0, 0) in the map frame."""
        return Pose2D(self._col0 * self.resolution, self._row0 * self.resolution, 0.0)

    def to_grid(self) -> OccupancyGrid:
        """The map: occupancy 0..100 (the probability in %) where any ray reached, -1 elsewhere."""
        if not self._logodds.size:
            raise ValueError("the mapper has no grid yet: add a scan or give bounds")
        p = 1.0 / (1.0 + np.exp(-self._logodds.astype(np.float64)))
        data = np.where(self._counts.any(axis=2), np.rint(100.0 * p), UNKNOWN).astype(np.int8)
        if self.reflect is not None:
            hits, passes = self._counts[..., 0], self._counts[..., 1]
            struck = (hits >= self.reflect_hits) & (hits >= self.reflect * (hits + passes))
            data[struck] = np.maximum(data[struck], self.reflect_level)
        return OccupancyGrid(data, self.resolution, self.origin, self.frame)


def build_map(pairs: Sequence[tuple[Scan, Pose2D]], resolution: float = 0.05) -> OccupancyGrid:
    """A map from scratch out of (scan, pose) pairs with the default settings."""
    mapper = OccupancyMapper(resolution)
    mapper.extend(pairs)
    return mapper.to_grid()
