"""Wall-heading factors: a corridor's straight side walls hold the map's heading over its length."""

from __future__ import annotations

import math

import numpy as np
from benchmarks.slam_synthetic import RATE, a1_scan, corridor_path, corridor_world, drifting_odometry

from omnibot.mapping.slam import Slam
from omnibot.mapping.walls import wall_direction
from omnibot.motion import Pose2D


def test_a_wall_direction_is_the_lines_fitted_to_both_side_walls() -> None:
    """Two parallel walls turned by 0.2 degree, 5 mm noise and a door's jamb off one: their direction
    to a few thousandths of a degree, with a variance that says so; no wall, no direction."""
    rng = np.random.default_rng(3)
    turn = math.radians(0.2)
    along = np.concatenate((rng.uniform(-4.0, 6.0, 400), rng.uniform(-3.0, 8.0, 400)))
    offset = np.concatenate((np.full(400, 1.0), np.full(400, -1.0)))
    offset[:20] += 0.08  # a door's jamb: off the wall's line, within its band
    offset += rng.normal(0.0, 0.005, 800)
    c, s = math.cos(turn), math.sin(turn)
    points = np.column_stack((along * c - offset * s, along * s + offset * c))
    direction = wall_direction(points, 0.0)
    assert direction is not None
    angle, variance = direction
    assert abs(angle - turn) < 4.0 * math.sqrt(variance)
    assert math.degrees(math.sqrt(variance)) < 0.005
    assert wall_direction(points[:25], 0.0) is None  # too few returns for a line
    assert wall_direction(np.column_stack((np.full(100, 3.0), np.linspace(-1, 1, 100))), 0.0) is None


def _heading_errors(wall_heading: bool) -> list[float]:
    world = corridor_world(30.0)
    truth = [Pose2D(p.x, p.y, 0.05 * p.theta) for p in corridor_path(20.0, start=1.5)]
    odom = drifting_odometry(truth, np.random.default_rng(8), heading_bias=math.radians(1.0))
    slam = Slam(wall_heading=wall_heading)
    for k, (pose, odom_pose) in enumerate(zip(truth, odom, strict=True)):
        slam.update(odom_pose, a1_scan(world, pose, np.random.default_rng(300 + k), k / RATE), k / RATE)
    keyframes = [(pose, truth[round(scan.stamp * RATE)]) for pose, scan in slam.keyframes()]
    degenerate = sum(1 for match in slam.matches if match.unconstrained)
    assert degenerate > 50
    assert slam.walled == (degenerate if wall_heading else 0)  # every degenerate keyframe saw the walls
    return [math.degrees(abs(math.remainder(e.theta - t.theta, 2 * math.pi))) for e, t in keyframes]


def test_the_side_walls_hold_the_heading_where_keyframe_matches_random_walk() -> None:
    """20 m down a corridor: each keyframe matched on the last ten takes their heading and adds its
    own match's noise, a random walk; tied through the side walls' direction to the first keyframe,
    the heading stays within two fits' noise."""
    walled, chained = _heading_errors(True), _heading_errors(False)
    # the keyframes' heading error: chained 0.12 degree at worst (rms 0.06: a side wall 20 m on 4 cm
    # off); tied, 0.04 (rms 0.02), a few fits' 0.01-0.015 degree (an A1's noise over 2-8 m of wall)
    assert max(chained) > 0.1
    assert max(walled) < 0.06
    assert math.sqrt(np.mean(np.square(walled))) < 0.5 * math.sqrt(np.mean(np.square(chained)))
