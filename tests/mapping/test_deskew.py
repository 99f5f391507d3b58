"""Motion-distortion correction: a spinning scanner's rays on a moving base brought to one instant."""

from __future__ import annotations

import math

import numpy as np
from benchmarks.slam_synthetic import synthetic_scan

from omnibot.mapping.deskew import motion, scan_points
from omnibot.mapping.se2 import transform
from omnibot.motion import Pose2D, Twist
from omnibot.sim import World, load_world


def wall_distance(world: World, points: np.ndarray) -> np.ndarray:
    """Distance of each (map-frame) point to the nearest wall or obstacle edge."""
    a = world.segments[:, :2]
    e = world.segments[:, 2:] - a
    p = points[:, None, :] - a[None]
    t = np.clip((p * e[None]).sum(-1) / (e * e).sum(-1)[None], 0.0, 1.0)
    gap = p - t[..., None] * e[None]
    return np.asarray(np.hypot(gap[..., 0], gap[..., 1]).min(axis=1))


def test_deskewed_returns_lie_on_the_walls() -> None:
    world = load_world("room")
    pose = Pose2D(2.0, 2.0, 0.3)
    twist = Twist(0.5, 0.1, 1.0)
    scan = synthetic_scan(
        world, pose, np.random.default_rng(0), noise=0.0, dropout=0.0, twist=twist, time_increment=0.1 / 360
    )
    raw = wall_distance(world, transform(pose, scan.points()))
    fixed = wall_distance(world, transform(pose, scan_points(scan, twist)))
    assert np.median(raw) > 0.01
    assert fixed.max() < 1e-9


def test_nothing_moves_without_motion_or_spin() -> None:
    scan = synthetic_scan(load_world("room"), Pose2D(2.0, 2.0, 0.0), np.random.default_rng(1))
    assert np.array_equal(scan_points(scan, Twist(0.5, 0.0, 1.0)), scan.points())
    assert np.array_equal(scan_points(scan, Twist()), scan.points())


def test_motion_is_the_planar_exponential() -> None:
    # a quarter turn on a circle of radius 1 m, and a straight line
    x, y, th = motion(Twist(1.0, 0.0, 1.0), np.array([math.pi / 2, 0.0]))
    assert np.allclose([x[0], y[0], th[0]], [1.0, 1.0, math.pi / 2])
    assert np.allclose([x[1], y[1], th[1]], 0.0)
    x, y, th = motion(Twist(0.3, -0.2, 0.0), np.array([2.0]))
    assert np.allclose([x[0], y[0], th[0]], [0.6, -0.4, 0.0])
