"""The 2D SLAM on synthetic scans from World.raycast, with odometry drifting as a bad floor makes it."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from benchmarks.slam_synthetic import (
    RATE,
    corridor_path,
    corridor_world,
    drifting_odometry,
    position_errors,
    rmse,
    synthetic_scan,
)

from omnibot.errors import ConfigError
from omnibot.mapping.se2 import between, compose, inverse
from omnibot.mapping.slam import Slam
from omnibot.motion import Pose2D, Twist
from omnibot.sim import load_world
from tests.mapping.laps import drive


@pytest.mark.parametrize("optimizer", ["isam2", "lm"])
def test_slam_is_several_times_better_than_odometry_and_within_centimetres(
    room_loop: tuple[list[Pose2D], list[Pose2D]], optimizer: str
) -> None:
    truth, odom = room_loop
    slam = Slam(optimizer=optimizer)
    estimate = drive(slam, load_world("room"), truth, odom, seed=12)
    odom_ape = rmse(position_errors(odom, truth))
    slam_ape = rmse(position_errors(estimate, truth))
    assert odom_ape > 0.15
    assert slam_ape < 0.02
    assert slam_ape * 5 < odom_ape
    assert slam.closures >= 1
    # the map -> odom transform carries the odometry's pose onto the SLAM's
    assert np.allclose(
        [*compose(slam.map_to_odom, odom[-1]).__dict__.values()], [*slam.pose.__dict__.values()], atol=1e-9
    )
    # keyframes: corrected poses with their scans, for a mapper
    frames = slam.keyframes()
    assert len(frames) == len(slam.matches) + 1
    kf_truth = [truth[round(scan.stamp * RATE)] for _, scan in frames]
    assert max(position_errors([pose for pose, _ in frames], kf_truth)) < 0.03


def test_the_corridor_falls_back_on_odometry_along_its_axis() -> None:
    """Mid-corridor the ends are out of range: scans fix heading and side, odometry the axis."""
    world = corridor_world(40.0)
    truth = corridor_path(8.0, start=14.0)
    odom = drifting_odometry(truth, np.random.default_rng(21))
    slam = Slam()
    estimate = drive(slam, world, truth, odom, seed=22)
    along_slam = max(abs(e.x - t.x) for e, t in zip(estimate, truth, strict=True))
    along_odom = max(abs(o.x - t.x) for o, t in zip(odom, truth, strict=True))
    across_slam = max(abs(e.y - t.y) for e, t in zip(estimate, truth, strict=True))
    across_odom = max(abs(o.y - t.y) for o, t in zip(odom, truth, strict=True))
    heading = max(
        abs(math.remainder(e.theta - t.theta, 2 * math.pi)) for e, t in zip(estimate, truth, strict=True)
    )
    heading_odom = max(
        abs(math.remainder(o.theta - t.theta, 2 * math.pi)) for o, t in zip(odom, truth, strict=True)
    )
    assert along_odom > 0.1  # the odometry's scale error, which nothing in the scans can see
    assert along_slam <= along_odom * 1.1 + 0.02
    assert across_odom > 0.3
    assert across_slam < 0.03
    # between keyframes (every 0.25 m) the heading is the odometry's since the last one: 2 deg/m bias
    assert heading < math.radians(1.5)
    assert heading * 10 < heading_odom
    # every front-end match reported the axis as unconstrained
    assert all(np.sqrt(m.covariance[0, 0]) > 10.0 for m in slam.matches)


def test_bad_input_is_one_clear_error() -> None:
    with pytest.raises(ConfigError, match="keyframe_distance"):
        Slam(keyframe_distance=0.0)
    with pytest.raises(ConfigError, match="optimizer"):
        Slam(optimizer="gauss")
    with pytest.raises(ConfigError, match="loop_min_fitness"):
        Slam(loop_min_fitness=1.5)
    slam = Slam()
    scan = synthetic_scan(load_world("room"), Pose2D(2.0, 2.0, 0.0), np.random.default_rng(0))
    slam.update(Pose2D(0.0, 0.0, 0.0), scan, 1.0)
    with pytest.raises(ConfigError, match="stamp"):
        slam.update(Pose2D(0.0, 0.0, 0.0), scan, 0.5)
    with pytest.raises(ConfigError, match="odom_pose"):
        slam.update(Pose2D(math.inf, 0.0, 0.0), scan, 2.0)
    with pytest.raises(ConfigError, match="scan"):
        slam.update(Pose2D(0.0, 0.0, 0.0), "scan", 2.0)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="twist"):
        slam.update(Pose2D(0.0, 0.0, 0.0), scan, 2.0, Twist(0.0, math.nan, 0.0))
    with pytest.raises(ConfigError, match="older"):
        slam.try_loop_closure(5, 0)
    assert slam.map_to_odom == compose(slam.pose, inverse(Pose2D(0.0, 0.0, 0.0)))


def test_scans_without_returns_fall_back_on_odometry(room_loop: tuple[list[Pose2D], list[Pose2D]]) -> None:
    """A blinded scanner (every ray inf) for a stretch: the SLAM carries on with odometry, then recovers."""
    truth, odom = room_loop
    world = load_world("room")
    rng = np.random.default_rng(17)
    slam = Slam()
    blind = range(40, 60)
    for k, (true_pose, odom_pose) in enumerate(zip(truth, odom, strict=True)):
        scan = synthetic_scan(world, true_pose, rng, k / RATE)
        if k in blind:
            scan = replace(scan, ranges=np.full(len(scan), math.inf))
        slam.update(odom_pose, scan, k / RATE)
    assert any(not m.converged for m in slam.matches)
    estimate = [pose for _, pose in slam.trajectory()]
    assert rmse(position_errors(estimate, truth)) < 0.03


def test_a_spinning_scanners_motion_distortion_is_undone(
    room_loop: tuple[list[Pose2D], list[Pose2D]],
) -> None:
    """Rays cast along the true motion over each 0.1 s scan: deskewed with the odometry's twist."""
    truth, odom = room_loop
    world = load_world("room")
    apes = {}
    for deskew in (True, False):
        rng = np.random.default_rng(18)
        slam = Slam(deskew=deskew)
        for k in range(len(truth) - 1):
            step = between(truth[k], truth[k + 1])
            twist = Twist(step.x * RATE, step.y * RATE, step.theta * RATE)
            scan = synthetic_scan(
                world, truth[k], rng, k / RATE, twist=twist, time_increment=1 / (RATE * 360)
            )
            slam.update(odom[k], scan, k / RATE)
        apes[deskew] = rmse(position_errors([p for _, p in slam.trajectory()], truth[:-1]))
    assert apes[True] < 0.02
    assert apes[True] * 3 < apes[False]


def test_a_turn_starting_or_stopping_during_a_scan_is_deskewed_with_the_scans_own_twist() -> None:
    """Turns in bursts (1.5 rad/s on and off, as goto's legs turn the base) while creeping along x:
    the previous revolution's motion leaves a scan whose turn rate changed distorted by the change,
    which the match turns into a heading error; the scan's own twist does not."""
    world = load_world("room")
    truth = [Pose2D(1.0, 1.5, 0.0)]
    for k in range(200):
        w = (1.5, 0.0, -1.5, 0.0)[(k // 5) % 4]
        vx = 0.15 if (k // 40) % 2 == 0 else -0.15
        p = truth[-1]
        truth.append(
            compose(p, Pose2D(vx / RATE * math.cos(p.theta), -vx / RATE * math.sin(p.theta), w / RATE))
        )
    worst = {}
    for own in (True, False):
        rng = np.random.default_rng(3)
        slam = Slam()
        for k in range(len(truth) - 1):
            step = between(truth[k], truth[k + 1])
            twist = Twist(step.x * RATE, step.y * RATE, step.theta * RATE)
            scan = synthetic_scan(
                world, truth[k], rng, k / RATE, twist=twist, time_increment=1 / (RATE * 360)
            )
            slam.update(truth[k], scan, k / RATE, twist if own else None)
        worst[own] = max(
            abs(math.remainder(p.theta - t.theta, 2 * math.pi))
            for (_, p), t in zip(slam.trajectory(), truth, strict=False)
        )
    assert worst[True] < math.radians(0.2)
    assert worst[False] > math.radians(1.0)
