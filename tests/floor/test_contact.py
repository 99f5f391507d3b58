"""The floor's contact model: static normal loads."""

from __future__ import annotations

import numpy as np

from omnibot.floor.contact import GRAVITY, static_loads


def test_static_loads_clip_tipping_solutions() -> None:
    x = np.array([[0.1, -0.1, 0.0]])
    y = np.array([[0.0, 0.1, -0.1]])
    loads = static_loads(x, y, np.array([2.0]), np.array([[False, False, True]]))
    assert (loads >= 0).all()
    np.testing.assert_allclose(loads.sum(), 2.0 * GRAVITY)
