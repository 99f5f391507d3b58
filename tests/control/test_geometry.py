"""Path geometry: Douglas-Peucker, arc-length resampling, curvature, heading rate, projection."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control.paths import Path, curvature, douglas_peucker, heading_rate, resample, standard_path


def circle(r: float = 0.5, n: int = 721) -> Path:
    a = np.linspace(-math.pi / 2, 1.5 * math.pi, n)
    return Path.from_points(np.column_stack((r * np.cos(a), r + r * np.sin(a))), theta=0.0)


def test_douglas_peucker_keeps_corners_and_respects_the_tolerance() -> None:
    square = standard_path("square", size=1.0, spacing=0.01)
    simple = douglas_peucker(square, 0.001)
    assert len(simple) == 5
    np.testing.assert_allclose(simple.points, [[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], atol=1e-9)
    ring = circle()
    coarse = douglas_peucker(ring, 0.005)
    assert 10 < len(coarse) < 60
    assert ring.distances(coarse.points).max() < 1e-9  # kept points are on the original
    assert coarse.distances(ring.points).max() <= 0.005 + 1e-9  # and the original is near the chords


def test_douglas_peucker_keeps_heading_turns_when_asked() -> None:
    line = Path.from_points([(x, 0.0) for x in np.linspace(0, 1, 101)], theta=np.linspace(0, 1, 101) ** 2)
    assert len(douglas_peucker(line, 0.01)) == 2
    assert len(douglas_peucker(line, 0.01, heading_tolerance=0.01)) > 4


def test_resample_by_arc_length_interpolates_every_column() -> None:
    p = Path(
        np.array([0.0, 1.0, 1.0]),
        np.array([0.0, 0.0, 1.0]),
        np.array([0.0, 1.0, 2.0]),
        np.array([0, 1, 3.0]),
        np.array([0, 1, 0.0]),
    )
    r = resample(p, 0.3)
    steps = np.diff(r.s)
    assert steps.max() <= 0.3 + 1e-9 and r.length == pytest.approx(2.0)
    assert (r.x[-1], r.y[-1]) == (1.0, 1.0)
    k = int(np.argmin(np.abs(r.s - 0.6)))
    assert r.theta[k] == pytest.approx(0.6) and r.t[k] == pytest.approx(0.6) and r.v[k] == pytest.approx(0.6)  # type: ignore[index]
    with pytest.raises(ValueError, match="spacing"):
        resample(p, 0.0)


def test_resample_keeps_a_turn_in_place() -> None:
    p = Path(np.array([0.0, 1.0, 1.0, 2.0]), np.zeros(4), np.array([0.0, 0.0, 1.5, 1.5]))
    r = resample(p, 0.25)
    at_corner = np.flatnonzero(np.isclose(r.x, 1.0))
    assert len(at_corner) == 2
    assert r.theta[at_corner].tolist() == pytest.approx([0.0, 1.5])


def test_curvature_and_heading_rate() -> None:
    ring = circle(0.5)
    k = curvature(ring)
    assert np.median(k[1:-1]) == pytest.approx(2.0, rel=1e-3)  # 1/r, left turn positive
    mirrored = Path.from_points(np.column_stack((ring.x, -ring.y)), theta=0.0)
    assert np.median(curvature(mirrored)[1:-1]) == pytest.approx(-2.0, rel=1e-3)
    tangent = Path.from_points(ring.points)
    assert np.median(heading_rate(tangent)) == pytest.approx(2.0, rel=1e-2)
    assert np.all(heading_rate(ring) == 0.0)


def test_projection_signed_cross_track_and_nearest() -> None:
    line = Path.from_points([(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)], theta=0.0)
    left = line.project(1.5, 0.2)
    assert (left.s, left.cross) == pytest.approx((1.5, 0.2)) and left.index == 1
    assert line.project(0.5, -0.1).cross == pytest.approx(-0.1)
    d, s = line.nearest(np.array([[0.5, 0.3], [3.0, 0.0]]))
    np.testing.assert_allclose(d, [0.3, 1.0])
    np.testing.assert_allclose(s, [0.5, 2.0])
    near = line.project_near(1.9, 0.0, s=1.8, behind=0.1, ahead=0.5)
    assert near.s == pytest.approx(1.9)
