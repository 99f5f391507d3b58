"""The SLAM's loop closures: one that fixes the end point, a wrong candidate refused, a false one survived."""

from __future__ import annotations

import math

import numpy as np
import pytest
from benchmarks.slam_synthetic import RATE, position_errors, rmse, synthetic_scan

from omnibot.mapping.se2 import between, compose
from omnibot.mapping.slam import Slam
from omnibot.motion import Pose2D
from omnibot.sim import load_world
from tests.mapping.laps import drive


def test_a_loop_closure_fixes_the_end_point(room_loop: tuple[list[Pose2D], list[Pose2D]]) -> None:
    """Odometry and loop closures alone (no scan-to-submap front end): the closure pulls the end back."""
    truth, odom = room_loop
    world = load_world("room")
    options = {"scan_to_submap": False, "loop_search_window": (0.8, math.radians(20.0))}
    open_loop = Slam(**options, loop_min_separation=10_000)  # type: ignore[arg-type]
    closed = Slam(**options)  # type: ignore[arg-type]
    end_open = position_errors(drive(open_loop, world, truth, odom, seed=13), truth)[-1]
    end_closed = position_errors(drive(closed, world, truth, odom, seed=13), truth)[-1]
    end_odom = position_errors(odom, truth)[-1]
    assert open_loop.closures == 0
    assert end_open == pytest.approx(end_odom, rel=0.05)
    assert closed.closures >= 1
    assert end_closed < 0.08
    assert end_closed * 3 < end_open


def test_a_wrong_loop_closure_candidate_is_rejected(room_loop: tuple[list[Pose2D], list[Pose2D]]) -> None:
    truth, odom = room_loop
    slam = Slam()
    drive(slam, load_world("room"), truth, odom, seed=14)
    before = [pose for pose, _ in slam.keyframes()]
    newer = len(before) - 1
    # the right place, but a guess turned by 90 degrees: beyond the search window, nothing fits
    wrong = compose(before[newer], Pose2D(0.0, 0.0, math.pi / 2))
    loop = slam.try_loop_closure(0, newer, wrong)
    assert not loop.accepted
    assert loop.match is not None
    assert loop.match.fitness < slam.loop_min_fitness or not loop.match.converged
    assert [pose for pose, _ in slam.keyframes()] == before
    # the right guess is accepted
    assert slam.try_loop_closure(0, newer).accepted


def test_a_false_closure_that_got_through_does_not_wreck_the_map(
    room_loop: tuple[list[Pose2D], list[Pose2D]],
) -> None:
    truth, odom = room_loop
    world = load_world("room")
    slam = Slam()
    half = len(truth) // 2
    drive(slam, world, truth[:half], odom[:half], seed=15)
    frames = slam.keyframes()
    # claim keyframe 0 and the latest are 0.5 m and 20 degrees apart from what they are, confidently
    true_rel = between(frames[0][0], frames[-1][0])
    lie = compose(true_rel, Pose2D(0.5, -0.3, math.radians(20.0)))
    slam.add_loop_closure(0, len(frames) - 1, lie, np.diag([1e-4, 1e-4, 1e-4]))
    rng = np.random.default_rng(16)
    for k in range(half, len(truth)):
        slam.update(odom[k], synthetic_scan(world, truth[k], rng, k / RATE), k / RATE)
    estimate = [pose for _, pose in slam.trajectory()]
    assert rmse(position_errors(estimate, truth)) < 0.03
