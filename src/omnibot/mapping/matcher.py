"""Planar scan registration: where a scan (the source) lies in another scan or a local submap (the target).

Two stages, chosen on measurements (benchmarks/scan_matching.py, BENCHMARKS.md):

1. **Correlative search** (Olson's CSM, cartographer's real-time CSM): the target is rasterised into
   a likelihood grid (``exp(-d^2 / 2 sigma^2)`` of the distance ``d`` to the nearest target point);
   every pose of an x, y, theta lattice around the initial guess (steps of one cell and of the
   angle that moves the farthest source point by one cell) is scored by the mean likelihood of the
   moved source points (a compiled loop), with a slight preference for poses near the guess so that
   a flat score (a featureless corridor) keeps the guess. Finds the basin even from a guess
   0.2 m / 10 degrees off.
2. **Point-to-line ICP** (Gauss-Newton on the distances to the target's local lines, Huber
   weighted) from the best lattice pose, down to sub-centimetre accuracy. Directions the geometry
   does not constrain (eigenvalues of the normal equations far below the largest, rotation scaled
   to a length by the points' spread) are not moved: there the result keeps the initial guess.

The result's covariance is ``sigma^2 H^-1`` of the point-to-line problem at the solution (``H``
the normal matrix, ``sigma`` the residual's spread, never below the sensor's), scaled by
``covariance_scale`` for the correlation between neighbouring rays; unconstrained directions get
a variance of :data:`UNCONSTRAINED_VARIANCE`. So a corridor's axis shows up as a huge variance
along it, and a pose graph weighting the match by this covariance falls back on odometry there.

``weighted=True`` weighs each source point by its own range noise (``range_noise``: ``std +
fraction * range``, the scanner's 1 sigma; the A1's 1 % by default) instead of one spread for all:
the normal matrix is then an information matrix (1/m^2) and the covariance its inverse (scaled as
above), and a direction is unconstrained when it is fixed no better than :data:`DEGENERATE_SIGMA`
rather than relative to the best one. A wall 10 m away (10 cm noise per return) then constrains
what it can (a few centimetres from a dozen returns) with its honest weight, where the relative
test (and one spread for all: Censi's Hessian covariance assumes equal noise) would either drop
it or trust it as if it were 1 m away. Each correspondence then informs only the direction its
Jacobian lies along (localisability, as X-ICP's): along a corridor the side walls' slightly tilted
normals neither count as information on the axis nor pull it, the end wall's returns alone do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import distance_transform_edt
from scipy.spatial import cKDTree

from omnibot.errors import ConfigError
from omnibot.mapping.se2 import transform, wrap
from omnibot.motion import Pose2D
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

UNCONSTRAINED_VARIANCE = 1.0e4
"""Variance (m^2 or rad^2) given to a direction the scans do not constrain."""
DEGENERATE_RATIO = 1.0e-2
"""An eigenvalue of the normal matrix (its rotation scaled by the points' spread to a length) below
this fraction of the largest marks an unconstrained direction."""
DEGENERATE_SIGMA = 0.3
"""A weighted match (``weighted=True``) leaves a direction unconstrained when it fixes it no better
than this, 1 sigma (m; rotation scaled by the points' spread to a length)."""
ALIGNED = math.cos(math.radians(45.0))
"""A correspondence supports a direction when its Jacobian lies within this angle's cosine of it."""
SETTLED = 0.1
"""A weighted match has settled when its step is below this many sigmas (its information's)."""
HUBER_SIGMAS = 3.0
"""Residuals beyond this many sigmas of the range noise are down-weighted (Huber)."""
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


@dataclass(frozen=True)
class MatchResult:
    """A registration: the source's pose in the target's frame and how far to trust it."""

    pose: Pose2D
    covariance: FloatArray
    """3x3 covariance of (x, y, theta) in the target's frame (m^2, rad^2)."""
    fitness: float
    """Fraction of the source's (thinned) points within ``inlier_distance`` of the target's lines (or
    of its points off any line)."""
    rmse: float
    """Root mean square point-to-line distance of those inliers, m."""
    converged: bool
    """ICP settled with enough inliers."""
    score: float
    """Best mean likelihood of the correlative search (0..1; 0 without one)."""
    unconstrained: int = 0
    """How many directions the geometry left unconstrained (degenerate; kept at the guess)."""
    free: FloatArray = field(default_factory=lambda: np.zeros((3, 0)), repr=False)
    """(3, unconstrained) unit vectors of those directions in (x, y, theta), the target's frame."""

    @property
    def information(self) -> FloatArray:
        """The inverse of :attr:`covariance`."""
        return np.asarray(np.linalg.inv(self.covariance), dtype=np.float64)


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


@dataclass(frozen=True)
class _Support:
    """A weighted match's normal equations as its correspondences support them (localisability, as
    X-ICP's): each correspondence informs only the eigen-direction of the full normal matrix its
    Jacobian lies within 45 degrees of, in the information it gives that direction and in the pull.

    Along a corridor the slight tilt of many lines' estimated normals adds up to information along
    its axis that no return measured, and their residuals across the walls to a pull along it: a
    far end wall's dozen returns would share the axis with side walls' metres of noise. Here the
    axis is decided and estimated by the end wall's returns alone."""

    vecs: FloatArray
    """Eigen-directions of the full normal matrix (scaled units), as columns."""
    info: FloatArray
    """The information each direction gets from the correspondences aligned with it."""
    pull: FloatArray
    """Their gradient along it."""
    keep: NDArray[np.bool_]
    """Directions whose information exceeds the floor: constrained."""

    @classmethod
    def of(
        cls,
        jac: FloatArray,
        weights: FloatArray,
        residuals: FloatArray,
        hessian: FloatArray,
        scale: FloatArray,
        floor: float,
    ) -> _Support:
        """From the correspondences' Jacobian rows, weights and residuals and their full normal matrix."""
        _, vecs = np.linalg.eigh(hessian * np.outer(scale, scale))
        js = jac * scale
        proj = js @ vecs
        aligned = proj * (np.abs(proj) >= ALIGNED * np.linalg.norm(js, axis=1)[:, None])
        info = (weights[:, None] * aligned * aligned).sum(axis=0)
        return cls(vecs, info, aligned.T @ (weights * residuals), info > floor)

    def normal(self, scale: FloatArray) -> FloatArray:
        """The supported normal matrix in (x, y, theta) units."""
        out: FloatArray = (self.vecs * self.info) @ self.vecs.T / np.outer(scale, scale)
        return out

    def step(self, scale: FloatArray) -> FloatArray:
        """The Gauss-Newton step along the constrained directions, each from its own correspondences."""
        inv = np.where(self.keep, 1.0 / np.where(self.keep, self.info, 1.0), 0.0)
        out: FloatArray = scale * (self.vecs @ (inv * self.pull))
        return out


def _eigen(
    hessian: FloatArray, scale: FloatArray, support: _Support | None = None
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Eigen-decomposition of the normal matrix in scaled units, and which directions are constrained.

    Without ``support``: eigenvalues above :data:`DEGENERATE_RATIO` of the largest. With it: the
    supported information of each direction, above the weighted match's floor (:class:`_Support`)."""
    if support is not None:
        return support.info, support.vecs, support.keep
    vals, vecs = np.linalg.eigh(hessian * np.outer(scale, scale))
    keep = vals > DEGENERATE_RATIO * max(float(vals[-1]), 1e-12)
    return vals, vecs, keep


def _solve(hessian: FloatArray, grad: FloatArray, scale: FloatArray) -> FloatArray:
    """The Gauss-Newton step ``H^-1 g`` restricted to the constrained directions."""
    vals, vecs, keep = _eigen(hessian, scale)
    inv = np.where(keep, 1.0 / np.where(keep, vals, 1.0), 0.0)
    step: FloatArray = scale * (vecs @ (inv * (vecs.T @ (scale * grad))))
    return step


def _linearise(
    tgt: Target, idx: IntArray, p: FloatArray, x: float, y: float, spread: FloatArray, weighted: bool
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The paired points ``p`` (placed at ``x, y``) against their target points ``idx``: each one's
    point-to-line residual, its Jacobian against (x, y, theta) and its Huber weight (in ``spread``s;
    ``weighted``: over its variance too)."""
    n = tgt.normals[idx]
    q = tgt.points[idx]
    r = np.einsum("ij,ij->i", n, p - q)
    jac = np.column_stack((n[:, 0], n[:, 1], -n[:, 0] * (p[:, 1] - y) + n[:, 1] * (p[:, 0] - x)))
    a = np.abs(r)
    huber = HUBER_SIGMAS * spread
    weights = np.where(a <= huber, 1.0, huber / np.maximum(a, 1e-12))
    if weighted:
        weights = weights / (spread * spread)
    return r, jac, weights


def _hold_unconstrained(pose: FloatArray, initial: Pose2D, scale: FloatArray, free: FloatArray) -> FloatArray:
    """``pose`` (x, y, theta) with its move from ``initial`` along the ``free`` directions (in
    ``scale``d units) taken back: what the geometry leaves unconstrained stays at the caller's guess."""
    moved = (
        np.array(
            [pose[0] - initial.x, pose[1] - initial.y, math.remainder(pose[2] - initial.theta, 2 * math.pi)]
        )
        / scale
    )
    return pose - scale * (free @ (free.T @ moved))


class ScanMatcher:
    """Correlative search then point-to-line ICP (see the module docstring); one instance, many matches.

    ``resolution`` is the search lattice's cell (m), ``search_xy`` / ``search_theta`` the default
    half-widths of the searched window (m, rad; 0 skips the search), ``inlier_distance`` the
    point-to-line distance that counts a point as matched, ``max_correspondence`` the farthest
    neighbour ICP pairs a point with, ``range_sigma`` the sensor's range noise (the floor of the
    residual spread), ``covariance_scale`` the factor for correlated rays. The source is thinned
    to half a cell and at most ``max_points``; fewer than ``min_points`` matched points is a failed
    match. ``weight_xy`` (1/m) and ``weight_theta`` (1/rad) discount a lattice pose's score by
    ``exp(-(weight_xy * distance + weight_theta * turn))`` from the guess (ties go to the guess).
    ``range_noise`` (std m, fraction of the range) is the scanner's range noise, 1 sigma, that a
    ``weighted`` match weighs each source point by (its range: its distance from the base).
    """

    def __init__(
        self,
        *,
        resolution: float = 0.05,
        search_xy: float = 0.25,
        search_theta: float = math.radians(12.0),
        inlier_distance: float = 0.05,
        max_correspondence: float = 0.3,
        range_sigma: float = 0.01,
        covariance_scale: float = 10.0,
        max_iterations: int = 30,
        min_points: int = 20,
        max_points: int = 400,
        weight_xy: float = 0.05,
        weight_theta: float = 0.05,
        range_noise: tuple[float, float] = (0.0, 0.01),
    ) -> None:
        for key, value in (
            ("resolution", resolution),
            ("inlier_distance", inlier_distance),
            ("max_correspondence", max_correspondence),
            ("range_sigma", range_sigma),
            ("covariance_scale", covariance_scale),
        ):
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"must be a positive number, not {value}", key)
        for key, value in (("search_xy", search_xy), ("search_theta", search_theta)):
            if not (math.isfinite(value) and value >= 0):
                raise ConfigError(f"must be zero or positive, not {value}", key)
        if len(range_noise) != 2 or not all(math.isfinite(v) and v >= 0 for v in range_noise):
            raise ConfigError(f"must be two numbers >= 0 (std m, fraction), not {range_noise}", "range_noise")
        if max_iterations < 1 or min_points < 3 or max_points < min_points:
            raise ConfigError(
                f"needs max_iterations >= 1 and 3 <= min_points <= max_points, not "
                f"{max_iterations}, {min_points}, {max_points}",
                "max_iterations",
            )
        self.resolution = resolution
        self.search_xy = search_xy
        self.search_theta = search_theta
        self.inlier_distance = inlier_distance
        self.max_correspondence = max_correspondence
        self.range_sigma = range_sigma
        self.covariance_scale = covariance_scale
        self.max_iterations = max_iterations
        self.min_points = min_points
        self.max_points = max_points
        self.weight_xy = weight_xy
        self.weight_theta = weight_theta
        self.range_noise = (float(range_noise[0]), float(range_noise[1]))

    def target(self, data: Scan | ArrayLike | Target, margin: float | None = None) -> Target:
        """A prepared target from a scan or (n, 2) points (a :class:`Target` is returned as it is)."""
        if isinstance(data, Target):
            return data
        pts = as_points(data, "target")
        grid_margin = self.search_xy + 1.0 if margin is None else margin
        return Target.build(pts, self.resolution, self.resolution, grid_margin)

    def match(
        self,
        source: Scan | ArrayLike,
        target: Scan | ArrayLike | Target,
        initial: Pose2D = Pose2D(0.0, 0.0, 0.0),  # noqa: B008 - a frozen dataclass
        *,
        search_xy: float | None = None,
        search_theta: float | None = None,
        weighted: bool = False,
        range_max: float = math.inf,
    ) -> MatchResult:
        """The pose of ``source``'s frame in ``target``'s frame, starting from ``initial``.

        ``weighted``: each source point weighed by its range noise (see the module docstring);
        then with the scanner's ``range_max`` a pair whose target point lies farther than 3 sigma
        short of it is left out: the scanner drops returns beyond ``range_max``, so of a wall near
        it only the returns whose noise fell short are left, biased short."""
        if not all(math.isfinite(v) for v in (initial.x, initial.y, initial.theta)):
            raise ConfigError(f"must be finite, not {initial}", "initial")
        tgt = self.target(target)
        src = voxel_downsample(as_points(source, "source"), self.resolution / 2.0)
        if len(src) > self.max_points:
            src = src[np.linspace(0, len(src) - 1, self.max_points).astype(np.int64)]
        if len(src) < self.min_points or len(tgt.points) < self.min_points:
            return self._failed(initial)
        sxy = self.search_xy if search_xy is None else search_xy
        sth = self.search_theta if search_theta is None else search_theta
        start, score = self.search(src, tgt, initial, sxy, sth)
        sigma = None
        reach = math.inf
        if weighted:
            spread = self.range_noise[0] + self.range_noise[1] * np.hypot(src[:, 0], src[:, 1])
            sigma = np.maximum(spread, self.range_sigma)
            reach = range_max - 3.0 * (self.range_noise[0] + self.range_noise[1] * range_max)
        return self._refine(src, tgt, initial, start, score, sigma, reach)

    def search(
        self, src: FloatArray, tgt: Target, initial: Pose2D, search_xy: float, search_theta: float
    ) -> tuple[Pose2D, float]:
        """The best pose of the correlative search around ``initial`` and its score."""
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
        scores = _correlate(tgt.grid, cells, nxy, step, self.weight_xy, self.weight_theta, res)
        a, i, j = np.unravel_index(int(np.argmax(scores)), scores.shape)
        best = Pose2D(initial.x + (i - nxy) * res, initial.y + (j - nxy) * res, wrap(float(thetas[a])))
        return best, float(scores[a, i, j])

    def _refine(
        self,
        src: FloatArray,
        tgt: Target,
        initial: Pose2D,
        start: Pose2D,
        score: float,
        sigma: FloatArray | None = None,
        reach: float = math.inf,
    ) -> MatchResult:
        """Point-to-line Gauss-Newton from ``start``; covariance from its normal matrix.

        ``sigma``: each source point's range noise (m), which weighs it (None: one spread for all)."""
        x, y, th = start.x, start.y, start.theta
        scale = np.array([1.0, 1.0, 1.0 / max(float(np.sqrt(np.mean(np.sum(src * src, axis=1)))), 0.1)])
        converged = False
        # unweighted: residuals in m against the sensor's floor; weighted: in sigmas of each point
        spread = np.full(len(src), self.range_sigma) if sigma is None else sigma
        floor = self.covariance_scale / DEGENERATE_SIGMA**2
        support: _Support | None = None
        hessian = np.zeros((3, 3))
        previous = np.zeros(3)
        for _ in range(self.max_iterations):
            p = transform(Pose2D(x, y, th), src)
            ok, idx = self._pairs(p, tgt, x, y, reach)
            if ok.sum() < self.min_points:
                break
            r, jac, weights = _linearise(tgt, idx[ok], p[ok], x, y, spread[ok], sigma is not None)
            hessian = jac.T @ (weights[:, None] * jac)
            if sigma is None:
                delta = -_solve(hessian, jac.T @ (weights * r), scale)
            else:
                support = _Support.of(jac, weights, r, hessian, scale, floor)
                hessian = support.normal(scale)
                delta = -support.step(scale)
            if np.all(np.abs(delta + previous) < 1e-7):  # a point flips in and out: settle between
                delta = 0.5 * delta
            elif sigma is not None and float(delta @ hessian @ previous) < 0:
                delta = 0.5 * delta  # far returns change partners back and forth: damp the swing
            x, y, th = x + delta[0], y + delta[1], th + delta[2]
            small = math.hypot(delta[0], delta[1]) < 1e-4 and abs(delta[2]) < 1e-4
            # weighted, H is an information matrix: a step a tenth of its direction's sigma is settled
            if small or (sigma is not None and float(delta @ hessian @ delta) < SETTLED**2):
                converged = True
                break
            previous = delta
        else:  # out of iterations: still settled if only a point or two keep flipping, by a hair
            converged = math.hypot(previous[0], previous[1]) < 1e-3 and abs(previous[2]) < 1e-3
        # what the geometry leaves unconstrained stays where the caller's guess put it
        _, vecs, keep = _eigen(hessian, scale, support)
        if converged and not keep.all():
            x, y, th = _hold_unconstrained(np.array([x, y, th]), initial, scale, vecs[:, ~keep])
        pose = Pose2D(float(x), float(y), wrap(float(th)))
        fitness, rmse, sigma2, inliers = self._fit(pose, src, tgt, sigma)
        converged = converged and inliers >= self.min_points
        covariance = self._covariance(hessian, sigma2, scale, support)
        free = scale[:, None] * vecs[:, ~keep]
        free = free / np.linalg.norm(free, axis=0)
        return MatchResult(pose, covariance, fitness, rmse, converged, score, int((~keep).sum()), free)

    def _pairs(
        self, p: FloatArray, tgt: Target, x: float, y: float, reach: float
    ) -> tuple[NDArray[np.bool_], IntArray]:
        """Which points ``p`` (the source placed at ``x, y``) pair with a target line within the
        correspondence distance (and, with a finite ``reach``, a target point within it), and each
        one's nearest target point."""
        dist, idx = tgt.tree.query(p, distance_upper_bound=self.max_correspondence)
        ok = np.isfinite(dist)
        ok[ok] = tgt.lines[idx[ok]]
        if reach < math.inf:  # pairs the scanner's cut-off would have biased
            far = tgt.points[idx[ok]] - np.array([x, y])
            ok[ok] = np.hypot(far[:, 0], far[:, 1]) <= reach
        return ok, idx

    def _fit(
        self, pose: Pose2D, src: FloatArray, tgt: Target, sigma: FloatArray | None
    ) -> tuple[float, float, float, int]:
        """How ``src`` at ``pose`` lies on ``tgt``: (fitness: the share of inliers, their RMSE in m,
        the residuals' variance the covariance scales by, the inliers). A point's distance is to its
        partner's line where it has one, else to the point."""
        p = transform(pose, src)
        dist, idx = tgt.tree.query(p, distance_upper_bound=self.max_correspondence)
        ok = np.isfinite(dist)
        line = np.full(len(src), np.inf)
        gap = p[ok] - tgt.points[idx[ok]]
        along = np.abs(np.einsum("ij,ij->i", tgt.normals[idx[ok]], gap))
        line[ok] = np.where(tgt.lines[idx[ok]], along, np.hypot(gap[:, 0], gap[:, 1]))
        inl = line <= self.inlier_distance
        rmse = float(math.sqrt(np.mean(line[inl] ** 2))) if inl.any() else math.inf
        if sigma is None:
            sigma2 = max(rmse if math.isfinite(rmse) else 0.0, self.range_sigma) ** 2
        else:  # the inliers' spread in sigmas, never below the noise model's
            sigma2 = max(float(np.mean((line[inl] / sigma[inl]) ** 2)) if inl.any() else 0.0, 1.0)
        return float(inl.mean()), rmse, sigma2, int(inl.sum())

    def _covariance(
        self, hessian: FloatArray, sigma2: float, scale: FloatArray, support: _Support | None = None
    ) -> FloatArray:
        """``covariance_scale * sigma2 * H^-1``, unconstrained directions at :data:`UNCONSTRAINED_VARIANCE`."""
        vals, vecs, keep = _eigen(hessian, scale, support)
        var = np.where(
            keep, self.covariance_scale * sigma2 / np.where(keep, vals, 1.0), UNCONSTRAINED_VARIANCE
        )
        scaled = (vecs * var) @ vecs.T  # in the scaled coordinates (x, y, theta * length)
        cov: FloatArray = scaled * np.outer(scale, scale)
        return 0.5 * (cov + cov.T)

    def _failed(self, initial: Pose2D) -> MatchResult:
        return MatchResult(
            initial, np.eye(3) * UNCONSTRAINED_VARIANCE, 0.0, math.inf, False, 0.0, 3, np.eye(3)
        )


def match(
    source: Scan | ArrayLike,
    target: Scan | ArrayLike | Target,
    initial: Pose2D = Pose2D(0.0, 0.0, 0.0),  # noqa: B008 - a frozen dataclass
    matcher: ScanMatcher | None = None,
) -> MatchResult:
    """Register ``source`` on ``target`` with ``matcher`` (a default :class:`ScanMatcher` if None)."""
    return (matcher or ScanMatcher()).match(source, target, initial)
