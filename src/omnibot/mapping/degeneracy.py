"""Which directions a match's geometry constrains, and its covariance (degeneracy, localisability).

The normal matrix of the point-to-line problem, its rotation scaled by the points' spread to a
length, is decomposed: a direction is unconstrained when its eigenvalue lies far below the largest
(:data:`DEGENERATE_RATIO`), or, for a weighted match, when the correspondences aligned with it
fix it no better than :data:`DEGENERATE_SIGMA` (:class:`Support`, X-ICP's localisability). The
covariance is ``covariance_scale * sigma^2 H^-1`` with :data:`UNCONSTRAINED_VARIANCE` along the
unconstrained directions, and a match's move along them is taken back to the caller's guess.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]

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


@dataclass(frozen=True)
class Support:
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
    ) -> Support:
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


def eigen(
    hessian: FloatArray, scale: FloatArray, support: Support | None = None
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Eigen-decomposition of the normal matrix in scaled units, and which directions are constrained.

    Without ``support``: eigenvalues above :data:`DEGENERATE_RATIO` of the largest. With it: the
    supported information of each direction, above the weighted match's floor (:class:`Support`)."""
    if support is not None:
        return support.info, support.vecs, support.keep
    vals, vecs = np.linalg.eigh(hessian * np.outer(scale, scale))
    keep = vals > DEGENERATE_RATIO * max(float(vals[-1]), 1e-12)
    return vals, vecs, keep


def solve(hessian: FloatArray, grad: FloatArray, scale: FloatArray) -> FloatArray:
    """The Gauss-Newton step ``H^-1 g`` restricted to the constrained directions."""
    vals, vecs, keep = eigen(hessian, scale)
    inv = np.where(keep, 1.0 / np.where(keep, vals, 1.0), 0.0)
    step: FloatArray = scale * (vecs @ (inv * (vecs.T @ (scale * grad))))
    return step


def hold_unconstrained(pose: FloatArray, initial: Pose2D, scale: FloatArray, free: FloatArray) -> FloatArray:
    """``pose`` (x, y, theta) with its move from ``initial`` along the ``free`` directions (in
    ``scale``d units) taken back: what the geometry leaves unconstrained stays at the caller's guess."""
    moved = (
        np.array(
            [pose[0] - initial.x, pose[1] - initial.y, math.remainder(pose[2] - initial.theta, 2 * math.pi)]
        )
        / scale
    )
    return pose - scale * (free @ (free.T @ moved))


def covariance(
    hessian: FloatArray,
    sigma2: float,
    scale: FloatArray,
    covariance_scale: float,
    support: Support | None = None,
) -> FloatArray:
    """``covariance_scale * sigma2 * H^-1``, unconstrained directions at :data:`UNCONSTRAINED_VARIANCE`."""
    vals, vecs, keep = eigen(hessian, scale, support)
    var = np.where(keep, covariance_scale * sigma2 / np.where(keep, vals, 1.0), UNCONSTRAINED_VARIANCE)
    scaled = (vecs * var) @ vecs.T  # in the scaled coordinates (x, y, theta * length)
    cov: FloatArray = scaled * np.outer(scale, scale)
    return 0.5 * (cov + cov.T)
