"""The world's plane geometry: points in a polygon, convexity, hulls."""

from __future__ import annotations

import numpy as np

from omnibot.sim.geometry import convex_hull, is_convex, points_in_polygon
from tests.sim.test_world import square


def test_point_in_polygon_and_hulls() -> None:
    l_shape = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
    inside = points_in_polygon(np.array([[0.5, 0.5], [1.5, 1.5], [0.5, 1.5], [3.0, 3.0]]), l_shape)
    assert inside.tolist() == [True, False, True, False]
    assert not is_convex(l_shape) and is_convex(square(0, 0, 1))
    hull = convex_hull(l_shape)
    assert len(hull) == 5 and is_convex(hull)
