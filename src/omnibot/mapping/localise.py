"""Localisation in a saved map: a likelihood-field particle filter, refined by scan-to-map matching.

:class:`Localiser` tracks the robot's pose in an :class:`OccupancyGrid` from odometry poses and
scans (AMCL-like):

* **motion**: each update moves every particle by the odometry's step since the last update (its
  body-frame dx, dy, dtheta: a holonomic base moves sideways too), with Gaussian noise of standard
  deviation ``alpha_xy * |step| + alpha_xy_turn * |dtheta|`` on x and y and
  ``alpha_turn * |dtheta| + alpha_turn_xy * |step|`` on theta;
* **measurement** (likelihood field): the scan's returns in the base frame at its first ray (a
  spinning scanner's motion distortion undone with the base's ``twist`` over the revolution,
  :mod:`omnibot.mapping.deskew`: raw, a moving robot's scan matches where it was half a revolution
  later, and the pose led the truth by ``speed x period / 2``, 5 cm at 1 m/s and 10 Hz); ``beams`` returns of the scan, evenly picked, are projected
  from every particle; each scores ``z_hit * exp(-d^2 / 2 sigma_hit^2) + z_rand`` where ``d`` is the
  distance (the grid's Euclidean distance transform, capped at ``max_dist``) from its end point to
  the nearest occupied cell. A particle's log-weight gains ``beam_weight`` times the sum over
  beams (``beam_weight < 1`` tempers the product of beams that are not independent, as AMCL's
  cubes do);
* **resampling**: low-variance (systematic), when the effective sample size falls below half the
  particles; a fixed count;
* **refinement** (``refine=True``): the particles' weighted mean is the start of a Gauss-Newton
  scan-to-map match on the walls' local lines (:mod:`omnibot.mapping.surface`: each return's
  signed distance to the line through the band of occupied cells nearest it, a fraction of a cell
  from the wall; on the distance to the cells' centres, zero across a band one or two cells thick,
  a robot at rest wandered up to 4 cm scan to scan, issue 25), the valid returns thinned to one
  per map cell, so a nearby obstacle's dense returns do not outweigh the far walls; Huber-
  weighted: the returned pose is the match's, and the cloud is shifted by the correction so the
  next prediction starts from it. ``benchmarks/mapping_localise.py`` measured the refined pose
  several times more accurate than the filter's mean (BENCHMARKS.md).

The covariance is the particles' weighted covariance (x, y, theta); ``converged`` is true when their
spread is below ``converged_xy`` (m, each axis's standard deviation) and ``converged_theta`` (rad).
:attr:`Localiser.map_to_odom` is the transform a ROS ``map -> odom`` publishes: the map pose of the
odometry frame's origin. The random draws come from ``numpy.random.default_rng(seed)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.se2 import compose, inverse, wrap
from omnibot.mapping.surface import SurfaceField, cell_coordinates
from omnibot.motion import Pose2D
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LocalisedPose:
    """The localiser's answer: the pose in the map, its 3x3 covariance (x, y, theta) and whether the
    filter has converged."""

    pose: Pose2D
    covariance: FloatArray
    converged: bool


class LikelihoodField:
    """Distance (m) from every cell of a grid to its nearest occupied cell, capped at ``max_dist``
    (unknown cells too, as AMCL's field: the cells just behind a wall are unknown, and a field that
    jumped there would pull matches off the wall); everything off the map is ``max_dist`` away: the
    particles' weights. The walls as lines (:attr:`surface`) are what a pose is refined on."""

    def __init__(self, grid: OccupancyGrid, max_dist: float = 1.0, occupied: int = 65) -> None:
        occ = grid.occupied(occupied)
        if not occ.any():
            raise ValueError("the map has no occupied cell to localise against")
        dist = np.minimum(ndimage.distance_transform_edt(~occ, sampling=grid.resolution), max_dist)
        self.dist: FloatArray = np.asarray(dist, dtype=np.float64)
        self.grid = grid
        self.max_dist = float(max_dist)
        self.surface = SurfaceField(grid, occupied, max_dist=max_dist)
        """The walls as local lines: what :func:`refine_pose` matches to."""

    def nearest(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """Distance at the cells holding the points (any shape)."""
        u, v = cell_coordinates(self.grid, x, y)
        col = np.floor(u + 0.5).astype(np.int64)
        row = np.floor(v + 0.5).astype(np.int64)
        rows, cols = self.dist.shape
        inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
        out = np.full(np.shape(x), self.max_dist)
        out[inside] = self.dist[row[inside], col[inside]]
        return out


def refine_pose(
    field: LikelihoodField, points: FloatArray, start: Pose2D, *, iterations: int = 10, huber: float = 0.05
) -> tuple[Pose2D, float]:
    """Gauss-Newton match of base-frame ``points`` (n, 2) onto the field's walls (its
    :class:`~omnibot.mapping.surface.SurfaceField`) from ``start``: the pose minimising the
    Huber-weighted sum of squared distances, and the RMS distance there."""
    x, y, th = start.x, start.y, start.theta
    rms = math.inf
    for _ in range(iterations):
        c, s = math.cos(th), math.sin(th)
        px = x + c * points[:, 0] - s * points[:, 1]
        py = y + s * points[:, 0] + c * points[:, 1]
        d, gx, gy, ok = field.surface.residuals(px, py)
        if ok.sum() < 3:
            break
        d, gx, gy = d[ok], gx[ok], gy[ok]
        dth = gx * (-s * points[ok, 0] - c * points[ok, 1]) + gy * (c * points[ok, 0] - s * points[ok, 1])
        jac = np.column_stack((gx, gy, dth))
        w = np.where(np.abs(d) <= huber, 1.0, huber / np.maximum(np.abs(d), 1e-12))
        h = (jac * w[:, None]).T @ jac + 1e-9 * np.eye(3)
        step = np.linalg.solve(h, -(jac * w[:, None]).T @ d)
        x, y, th = x + step[0], y + step[1], th + step[2]
        rms = float(np.sqrt(np.mean(d**2)))
        if abs(step[0]) + abs(step[1]) < 1e-5 and abs(step[2]) < 1e-5:
            break
    return Pose2D(float(x), float(y), wrap(float(th))), rms


def thin(points: FloatArray, cell: float) -> FloatArray:
    """One point per ``cell``-sized square (the mean of those in it): even density along surfaces."""
    key = np.floor(points / cell).astype(np.int64)
    _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    out = np.zeros((len(counts), 2))
    np.add.at(out, inv.reshape(-1), points)
    thinned: FloatArray = out / counts[:, None]
    return thinned


class Localiser:
    """Particle filter localisation in ``grid``, refined by scan-to-map matching (module docstring)."""

    def __init__(
        self,
        grid: OccupancyGrid,
        *,
        seed: int = 0,
        particles: int = 500,
        beams: int = 60,
        sigma_hit: float = 0.05,
        z_hit: float = 0.95,
        z_rand: float = 0.05,
        max_dist: float = 1.0,
        beam_weight: float = 0.3,
        alpha_xy: float = 0.2,
        alpha_xy_turn: float = 0.02,
        alpha_turn: float = 0.2,
        alpha_turn_xy: float = 0.1,
        jitter: tuple[float, float] = (0.002, 0.002),
        refine: bool = True,
        converged_xy: float = 0.05,
        converged_theta: float = 0.05,
        occupied: int = 65,
    ) -> None:
        if particles < 1 or beams < 1:
            raise ValueError(f"particles and beams must be positive, not {particles} and {beams}")
        self.field = LikelihoodField(grid, max_dist, occupied)
        self.grid = grid
        self.rng = np.random.default_rng(seed)
        self.count = particles
        self.beams = beams
        self.sigma_hit, self.z_hit, self.z_rand = sigma_hit, z_hit, z_rand
        self.beam_weight = beam_weight
        self.alpha = (alpha_xy, alpha_xy_turn, alpha_turn, alpha_turn_xy)
        self.jitter = jitter
        self.refine = refine
        self.converged_xy, self.converged_theta = converged_xy, converged_theta
        self.particles: FloatArray = np.zeros((particles, 3))
        self.logw: FloatArray = np.zeros(particles)
        self._odom: Pose2D | None = None
        self._pose = Pose2D(0.0, 0.0, 0.0)
        self._map_to_odom = Pose2D(0.0, 0.0, 0.0)
        self._initialised = False

    # ------------------------------------------------------------------ state

    def reset(self, pose: Pose2D, spread: tuple[float, float] = (0.3, 0.3)) -> None:
        """Start again around ``pose``: particles drawn with standard deviations ``spread`` =
        (xy in m, theta in rad); the next update's odometry pose is taken as the matching one."""
        sxy, sth = spread
        n = self.count
        self.particles = np.column_stack(
            (
                pose.x + self.rng.normal(0.0, sxy, n),
                pose.y + self.rng.normal(0.0, sxy, n),
                pose.theta + self.rng.normal(0.0, sth, n),
            )
        )
        self.logw = np.zeros(n)
        self._odom = None
        self._pose = pose
        self._initialised = True

    @property
    def pose(self) -> Pose2D:
        """The last estimate of the robot's pose in the map."""
        return self._pose

    @property
    def map_to_odom(self) -> Pose2D:
        """The odometry frame's pose in the map (ROS's map -> odom transform)."""
        return self._map_to_odom

    # ------------------------------------------------------------------ the filter

    def _predict(self, odom: Pose2D) -> None:
        if self._odom is None:
            return
        step = compose(inverse(self._odom), odom)
        trans = math.hypot(step.x, step.y)
        rot = abs(wrap(step.theta))
        a1, a2, a3, a4 = self.alpha
        sxy = a1 * trans + a2 * rot + self.jitter[0]
        sth = a3 * rot + a4 * trans + self.jitter[1]
        n = self.count
        dx = step.x + self.rng.normal(0.0, sxy, n)
        dy = step.y + self.rng.normal(0.0, sxy, n)
        dth = wrap(step.theta) + self.rng.normal(0.0, sth, n)
        th = self.particles[:, 2]
        c, s = np.cos(th), np.sin(th)
        self.particles[:, 0] += c * dx - s * dy
        self.particles[:, 1] += s * dx + c * dy
        self.particles[:, 2] = th + dth

    def _weigh(self, points: FloatArray) -> None:
        if len(points) == 0:
            return
        pick = points[np.linspace(0, len(points) - 1, min(self.beams, len(points))).astype(np.int64)]
        p = self.particles
        c, s = np.cos(p[:, 2])[:, None], np.sin(p[:, 2])[:, None]
        px = p[:, 0:1] + c * pick[:, 0] - s * pick[:, 1]
        py = p[:, 1:2] + s * pick[:, 0] + c * pick[:, 1]
        d = self.field.nearest(px, py)
        like = self.z_hit * np.exp(-0.5 * (d / self.sigma_hit) ** 2) + self.z_rand
        self.logw += self.beam_weight * np.log(like).sum(axis=1)
        self.logw -= self.logw.max()

    def _weights(self) -> FloatArray:
        w = np.exp(self.logw - self.logw.max())
        normed: FloatArray = w / w.sum()
        return normed

    def _resample(self, w: FloatArray) -> None:
        n = self.count
        if 1.0 / float(np.sum(w * w)) >= n / 2:
            return
        positions = (self.rng.random() + np.arange(n)) / n
        idx = np.minimum(np.searchsorted(np.cumsum(w), positions), n - 1)
        self.particles = self.particles[idx]
        self.logw = np.zeros(n)

    def _estimate(self, w: FloatArray) -> tuple[Pose2D, FloatArray]:
        p = self.particles
        mx, my = float(w @ p[:, 0]), float(w @ p[:, 1])
        mth = math.atan2(float(w @ np.sin(p[:, 2])), float(w @ np.cos(p[:, 2])))
        dev = np.column_stack(
            (p[:, 0] - mx, p[:, 1] - my, (p[:, 2] - mth + math.pi) % (2 * math.pi) - math.pi)
        )
        cov: FloatArray = (dev * w[:, None]).T @ dev
        return Pose2D(mx, my, mth), cov

    def update(self, odom_pose: Pose2D, scan: Scan, points: FloatArray | None = None) -> LocalisedPose:
        """Move the particles by the odometry's step since the last update, weigh them by ``scan``,
        resample, refine; the robot's pose in the map at the scan's first ray.

        ``odom_pose`` is the odometry's at the scan's first ray and ``points`` the scan's returns in
        the base frame there, its motion distortion undone with the base's twist over the scan
        (:func:`omnibot.mapping.deskew.scan_points`); None: the rays are taken as measured at one
        instant (a robot at rest)."""
        if not self._initialised:
            raise RuntimeError("Localiser.update before reset: give it a first pose")
        self._predict(odom_pose)
        self._odom = odom_pose
        if points is None:
            points = scan.points("base")
        self._weigh(points)
        w = self._weights()
        mean, cov = self._estimate(w)
        pose = mean
        if self.refine and len(points) >= 3:
            refined, _ = refine_pose(self.field, thin(points, self.grid.resolution), mean)
            shift = np.array([refined.x - mean.x, refined.y - mean.y, wrap(refined.theta - mean.theta)])
            if math.hypot(shift[0], shift[1]) < 3.0 * self.sigma_hit + 2.0 * math.sqrt(cov[0, 0] + cov[1, 1]):
                self.particles += shift
                pose = refined
        self._resample(w)
        self._pose = Pose2D(pose.x, pose.y, wrap(pose.theta))
        self._map_to_odom = compose(self._pose, inverse(odom_pose))
        converged = bool(
            math.sqrt(max(cov[0, 0], cov[1, 1])) < self.converged_xy
            and math.sqrt(cov[2, 2]) < self.converged_theta
        )
        return LocalisedPose(self._pose, cov, converged)
