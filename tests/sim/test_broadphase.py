"""A fleet's broad phase: the pairs whose bounding circles meet, swept again only when a body has moved
half a skin, and every footprint placed at once as the world's helpers place one."""

from __future__ import annotations

import itertools
import math

import numpy as np

from omnibot.robot import load_robot
from omnibot.sim.broadphase import SKIN, Footprints, NearPairs
from omnibot.sim.geometry import closed_edges, convex_hull, placed


def every_pair(rows: list[list[float]], reach: list[float]) -> list[tuple[int, int]]:
    """The pairs a test of every pair gives (the bounding circles' test of the fleet's contacts)."""
    return [
        (i, j)
        for i, j in itertools.combinations(range(len(rows)), 2)
        if (rows[j][0] - rows[i][0]) ** 2 + (rows[j][1] - rows[i][1]) ** 2 < (reach[i] + reach[j] + 1e-9) ** 2
    ]


def test_the_pairs_are_every_pair_whose_circles_meet_as_the_bodies_wander() -> None:
    rng = np.random.default_rng(3)
    reach = rng.uniform(0.1, 0.3, 12).tolist()
    xy = rng.uniform(-1.0, 1.0, (12, 2))
    near = NearPairs(reach)
    found = 0
    for _ in range(600):
        xy += rng.normal(0.0, 0.004, xy.shape)  # a few mm a step: most steps reuse the last sweep
        rows = [[x, y, 0.0] for x, y in xy.tolist()]
        pairs = near.pairs(rows)
        assert pairs == every_pair(rows, reach)
        found += len(pairs)
    assert found > 600 and 10 < near.sweeps < 300


def test_a_sweep_comes_when_a_body_has_moved_half_a_skin() -> None:
    near = NearPairs([0.1, 0.1])
    rows = [[0.0, 0.0, 0.0], [0.3, 0.0, 0.0]]
    assert near.pairs(rows) == [] and near.sweeps == 1
    rows[1][0] -= 0.49 * SKIN
    assert near.pairs(rows) == [] and near.sweeps == 1
    rows[1][0] -= 0.02 * SKIN
    assert near.pairs(rows) == [] and near.sweeps == 2
    rows[1][0] = 0.2 + 0.3 * SKIN  # within a skin of touching: kept by a sweep, not touching
    assert near.pairs(rows) == [] and near.sweeps == 3
    rows[1][0] -= 0.4 * SKIN  # touching now, found among the kept pairs without a sweep
    assert near.pairs(rows) == [(0, 1)] and near.sweeps == 3
    assert NearPairs([0.1]).pairs(rows[:1]) == []


def test_a_pair_the_sweep_left_out_cannot_meet_before_the_next_sweep() -> None:
    """Two bodies a hair beyond the skin, closing in by just under half a skin each: still apart."""
    near = NearPairs([0.1, 0.1])
    gap = 0.2 + 1e-9 + SKIN + 1e-12
    assert near.pairs([[0.0, 0.0, 0.0], [gap, 0.0, 0.0]]) == []
    step = 0.5 * SKIN * (1 - 1e-9)
    rows = [[step, 0.0, 0.0], [gap - step, 0.0, 0.0]]
    assert near.pairs(rows) == [] == every_pair(rows, [0.1, 0.1]) and near.sweeps == 1


def test_footprints_are_placed_bit_for_bit_as_one_outline_is() -> None:
    outlines = [
        np.ascontiguousarray(convex_hull(load_robot(name).footprint.outline()), dtype=float)
        for name in ("omni4", "omni3", "mecanum4", "omni4", "omni3")
    ]
    assert len({len(o) for o in outlines}) > 1  # outlines of several sizes, placed by size
    footprints = Footprints(outlines)
    rng = np.random.default_rng(5)
    for _ in range(200):
        rows = [[*rng.uniform(-5.0, 5.0, 2), rng.uniform(-20.0, 20.0)] for _ in outlines]
        edges = footprints.place(rows)
        expected = np.vstack([closed_edges(placed(o, *row)) for o, row in zip(outlines, rows, strict=True)])
        assert edges.tobytes() == expected.tobytes()
    assert footprints.bounds.tolist() == [0, *itertools.accumulate(len(o) for o in outlines)]
    assert Footprints([]).place([]).shape == (0, 4)


def test_each_outline_keeps_its_rows() -> None:
    square = np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]])
    triangle = np.array([[0.2, 0.0], [-0.1, 0.1], [-0.1, -0.1]])
    footprints = Footprints([square, triangle, square])
    edges = footprints.place([[0.0, 0.0, 0.0], [1.0, 2.0, math.pi], [3.0, 0.0, 0.0]])
    lo, hi = footprints.bounds[1], footprints.bounds[2]
    np.testing.assert_allclose(edges[lo:hi, :2], [[0.8, 2.0], [1.1, 1.9], [1.1, 2.1]], atol=1e-12)
    np.testing.assert_allclose(edges[hi:, 0], [2.9, 3.1, 3.1, 2.9])
