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

The parts, each in its module: the target (:mod:`~omnibot.mapping.target`: points, normals,
likelihood grid), the correlative search (:mod:`~omnibot.mapping.correlative`), the ICP and its
result (:mod:`~omnibot.mapping.icp`), which directions are constrained and the covariance
(:mod:`~omnibot.mapping.degeneracy`); :class:`ScanMatcher` holds the options and runs them in turn.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import ConfigError
from omnibot.mapping.correlative import correlative_search
from omnibot.mapping.degeneracy import UNCONSTRAINED_VARIANCE
from omnibot.mapping.icp import MatchResult, PointToLine
from omnibot.mapping.target import Target, as_points, voxel_downsample
from omnibot.motion import Pose2D
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]


class ScanMatcher(PointToLine):
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
        return correlative_search(
            src, tgt, initial, search_xy, search_theta, self.weight_xy, self.weight_theta
        )

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
