"""Planar rigid motions on :class:`~omnibot.motion.Pose2D`: compose, invert, relate, move points.

A pose ``a`` read as a transform maps points of its own frame into its parent's frame:
``transform(a, p) = R(a.theta) p + (a.x, a.y)``. :func:`compose` chains two (``a`` then ``b`` in
``a``'s frame), :func:`between` is the pose of ``b`` seen from ``a`` (``compose(a, between(a, b)) == b``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]


def wrap(angle: float) -> float:
    """The angle in [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """``a * b``: the pose ``b`` (given in ``a``'s frame) in ``a``'s parent frame."""
    c, s = math.cos(a.theta), math.sin(a.theta)
    return Pose2D(a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrap(a.theta + b.theta))


def inverse(a: Pose2D) -> Pose2D:
    """``a^-1``: the parent frame's pose seen from ``a``."""
    c, s = math.cos(a.theta), math.sin(a.theta)
    return Pose2D(-c * a.x - s * a.y, s * a.x - c * a.y, wrap(-a.theta))


def between(a: Pose2D, b: Pose2D) -> Pose2D:
    """``a^-1 * b``: the pose ``b`` seen from ``a`` (both in the same parent frame)."""
    return compose(inverse(a), b)


def transform(pose: Pose2D, points: ArrayLike) -> FloatArray:
    """(n, 2) points of ``pose``'s frame in its parent's frame."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    out: FloatArray = p @ np.array([[c, s], [-s, c]]) + np.array([pose.x, pose.y])
    return out


def distance(a: Pose2D, b: Pose2D) -> float:
    """Distance between the two poses' positions, m."""
    return math.hypot(b.x - a.x, b.y - a.y)


def rotate_covariance(covariance: ArrayLike, theta: float) -> FloatArray:
    """A 3x3 (x, y, theta) covariance rotated by ``theta`` (its x, y block turned into another frame)."""
    c, s = math.cos(theta), math.sin(theta)
    r = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    out: FloatArray = r @ np.asarray(covariance, dtype=np.float64) @ r.T
    return out
