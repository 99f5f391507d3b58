"""Point-to-line ICP: Gauss-Newton on the distances to the target's local lines, Huber weighted.

From the correlative search's best pose down to sub-centimetre accuracy. Directions the geometry
does not constrain are not moved (:mod:`omnibot.mapping.degeneracy`): there the result keeps the
initial guess. ``sigma`` given (a weighted match), each source point is weighed by its own range
noise and the normal matrix is an information matrix (1/m^2); each correspondence then informs only
the direction its Jacobian lies along (:class:`~omnibot.mapping.degeneracy.Support`).
:class:`PointToLine` is the scan matcher's part that does it; :class:`MatchResult` what a match gives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from omnibot.mapping.degeneracy import (
    DEGENERATE_SIGMA,
    Support,
    covariance,
    eigen,
    hold_unconstrained,
    solve,
)
from omnibot.mapping.se2 import transform, wrap
from omnibot.mapping.target import Target
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SETTLED = 0.1
"""A weighted match has settled when its step is below this many sigmas (its information's)."""
HUBER_SIGMAS = 3.0
"""Residuals beyond this many sigmas of the range noise are down-weighted (Huber)."""


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


class PointToLine:
    """The scan matcher's ICP (see the module docstring), on the options its matcher holds."""

    inlier_distance: float
    max_correspondence: float
    range_sigma: float
    covariance_scale: float
    max_iterations: int
    min_points: int

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
        support: Support | None = None
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
                delta = -solve(hessian, jac.T @ (weights * r), scale)
            else:
                support = Support.of(jac, weights, r, hessian, scale, floor)
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
        _, vecs, keep = eigen(hessian, scale, support)
        if converged and not keep.all():
            x, y, th = hold_unconstrained(np.array([x, y, th]), initial, scale, vecs[:, ~keep])
        pose = Pose2D(float(x), float(y), wrap(float(th)))
        fitness, rmse, sigma2, inliers = self._fit(pose, src, tgt, sigma)
        converged = converged and inliers >= self.min_points
        cov = covariance(hessian, sigma2, scale, self.covariance_scale, support)
        free = scale[:, None] * vecs[:, ~keep]
        free = free / np.linalg.norm(free, axis=0)
        return MatchResult(pose, cov, fitness, rmse, converged, score, int((~keep).sum()), free)

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
