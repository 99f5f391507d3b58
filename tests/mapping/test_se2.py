"""Planar pose algebra: composition, inverse and relative poses agree with each other and with points."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.mapping.se2 import between, compose, inverse, rotate_covariance, transform, wrap
from omnibot.motion import Pose2D

A = Pose2D(1.0, -2.0, 0.7)
B = Pose2D(-0.3, 0.5, -2.9)


def close(p: Pose2D, q: Pose2D) -> bool:
    return (
        math.isclose(p.x, q.x, abs_tol=1e-12)
        and math.isclose(p.y, q.y, abs_tol=1e-12)
        and abs(wrap(p.theta - q.theta)) < 1e-12
    )


def test_between_undoes_compose() -> None:
    assert close(compose(A, between(A, B)), B)
    assert close(between(A, compose(A, B)), B)
    assert close(compose(A, inverse(A)), Pose2D(0.0, 0.0, 0.0))


def test_transform_follows_compose() -> None:
    pts = np.array([[1.0, 0.0], [0.0, 2.0], [-1.5, 0.3]])
    assert np.allclose(transform(compose(A, B), pts), transform(A, transform(B, pts)))
    assert np.allclose(transform(Pose2D(1.0, 2.0, math.pi / 2), [[1.0, 0.0]]), [[1.0, 3.0]])


def test_wrap_and_rotated_covariance() -> None:
    assert wrap(3 * math.pi) == pytest.approx(-math.pi)
    cov = np.diag([4.0, 1.0, 0.5])
    turned = rotate_covariance(cov, math.pi / 2)
    assert np.allclose(turned, np.diag([1.0, 4.0, 0.5]))
