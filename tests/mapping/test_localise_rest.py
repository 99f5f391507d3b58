"""A robot at rest in a mapped room: the localiser's pose stays on the truth, scan after scan.

The scanner is the presets' RPLIDAR A1 (360 rays, range noise 1 % of the distance, 1 % dropouts),
the map the room rasterised at 2.5 cm (goto's benchmark's) and at 5 cm (``omnibot map``'s cells).
The bounds, 1 cm and 0.5 degrees after the first second (ten scans), from the errors' sources:

* noise: about 340 returns per scan, a quarter on each of the room's four walls 1-4 m away (sigma
  1-4 cm): the least-squares position across a wall is good to about 3 cm / sqrt(85), 0.3 cm,
  1 cm at three sigma; the heading, with the returns 1-4 m from the robot, to a tenth of a degree;
* the map: a wall is a band of cells one or two thick; matched to the band's middle line, the
  rasterisation's error is a fraction of a cell, well under the noise's. A matcher that lets the
  returns sit anywhere in the bands (main's, on the distance to the cells' centres) is free to
  wander 1.25 cm across each wall of a 2.5 cm map and 2.5 cm of a 5 cm one: 1.1-3.9 cm and up to
  0.7 degrees measured on these poses (issue 25's "up to 4 cm at rest").
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from benchmarks.planner import rasterise
from benchmarks.slam_synthetic import synthetic_scan

from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.localise import Localiser
from omnibot.motion import Pose2D
from omnibot.sim import World, load_world

SCANS, SETTLE = 60, 10
"""Six seconds of a 10 Hz scanner; the first second's scans are the filter settling."""
BOUND = 0.01
"""m: the localiser's error at rest (the module docstring's derivation)."""


def at_rest(world: World, grid: OccupancyGrid, pose: Pose2D, seed: int) -> tuple[float, float]:
    """The localiser's worst position and heading errors over a robot's scans at rest, after the first
    second; started 5 cm off its true pose, the odometry still."""
    rng = np.random.default_rng(seed)
    loc = Localiser(grid, seed=seed)
    loc.reset(Pose2D(pose.x + 0.03, pose.y - 0.04, pose.theta + 0.02), spread=(0.05, 0.05))
    worst, heading = 0.0, 0.0
    for k in range(SCANS):
        scan = synthetic_scan(world, pose, rng, 0.1 * k, noise=0.0, noise_fraction=0.01, dropout=0.01)
        found = loc.update(Pose2D(0.0, 0.0, 0.0), scan).pose
        if k >= SETTLE:
            worst = max(worst, math.hypot(found.x - pose.x, found.y - pose.y))
            heading = max(heading, abs((found.theta - pose.theta + math.pi) % (2 * math.pi) - math.pi))
    return worst, heading


@pytest.mark.parametrize("resolution", [0.025, 0.05])
@pytest.mark.parametrize(
    ("pose", "seed"),
    [
        (Pose2D(1.0, 1.0, 0.0), 1),
        (Pose2D(2.6, 2.1, 2.0), 2),
        (Pose2D(4.2, 2.8, -1.0), 3),
        (Pose2D(1.7, 2.4, 0.7), 4),
    ],
)
def test_a_robot_at_rest_is_localised_within_a_centimetre_and_does_not_wander(
    pose: Pose2D, seed: int, resolution: float
) -> None:
    world = load_world("room")
    worst, heading = at_rest(world, rasterise(world, resolution), pose, seed)
    assert worst < BOUND and heading < math.radians(0.5)
