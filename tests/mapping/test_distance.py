"""The distance transform: exact squared distances to the nearest wall cell."""

from __future__ import annotations

import numpy as np

from omnibot.mapping.distance import distance_squared


def test_distance_transform_is_exact() -> None:
    walls = np.zeros((30, 40), dtype=bool)
    walls[[3, 17, 25], [5, 30, 12]] = True
    got = distance_squared(walls)
    r, c = np.mgrid[0:30, 0:40]
    want = np.min([(r - a) ** 2 + (c - b) ** 2 for a, b in zip(*np.nonzero(walls), strict=True)], axis=0)
    assert np.array_equal(got, want)
