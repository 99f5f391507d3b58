"""Seed 000's Fig. 6 statement on the simulated robot: rotation in place needs more power than a turn
added to a robot already moving (``benchmarks.seed000_figures.turn_against_rotation``)."""

from __future__ import annotations

import pytest
from benchmarks.seed000_figures import STILL, turn_against_rotation


@pytest.mark.parametrize("surface", ["wood", "carpet"])
def test_a_turn_added_to_a_motion_needs_less_power_than_rotation_in_place(surface: str) -> None:
    """Seed 000: "rotation without movement requires more power than turning adjustment" (its K_r above
    its K_t at every power). Added to a robot moving at 100 counts, each of K_t's powers of the default
    calibration (up to 85 counts) turns it faster than it turns the robot at rest: below the wheels'
    start (30 counts) the robot at rest does not turn at all; at 85 counts 1.06x on the axis and 1.32x
    at 45 degrees on wood (1.05x, 1.25x on carpet). A turn larger than the motion itself (120 counts)
    stops some wheels and reverses them, and gets 0.84x / 0.90x: the seed's statement is about
    adjusting a motion."""
    turns = turn_against_rotation(surface, powers=(30, 45, 60, 85))
    rotation = turns["rotation"]
    assert rotation[30] < STILL < rotation[45]
    for course in ("course 0", "course 45"):
        added = turns[course]
        assert all(added[p] > rotation[p] for p in rotation), (course, added, rotation)
    assert turns["course 45"][85] > 1.2 * rotation[85]
