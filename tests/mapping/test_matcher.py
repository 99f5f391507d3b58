"""Scan registration on synthetic scans: accurate from bad guesses, honest about what it cannot see."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from benchmarks.slam_synthetic import corridor_path, corridor_world, room_path, synthetic_scan

from omnibot.errors import ConfigError
from omnibot.mapping.matcher import ScanMatcher, match
from omnibot.mapping.se2 import between, compose, transform
from omnibot.motion import Pose2D
from omnibot.sim import load_world


@pytest.fixture(scope="module")
def room_pairs() -> list[tuple[Pose2D, Pose2D]]:
    path = room_path(6.0)
    return [(path[k], path[k + 6]) for k in range(0, len(path) - 6, 12)]


def test_scan_to_scan_from_guesses_off_by_20_cm_and_10_degrees(
    room_pairs: list[tuple[Pose2D, Pose2D]],
) -> None:
    rng = np.random.default_rng(3)
    world = load_world("room")
    matcher = ScanMatcher()
    for a, b in room_pairs:
        truth = between(a, b)
        off = rng.choice([-1.0, 1.0], 3) * np.array([0.2, 0.2, math.radians(10.0)])
        guess = compose(truth, Pose2D(*off))
        result = matcher.match(synthetic_scan(world, b, rng), synthetic_scan(world, a, rng), guess)
        err = between(truth, result.pose)
        assert result.converged
        assert result.fitness > 0.9
        assert math.hypot(err.x, err.y) < 0.01
        assert abs(err.theta) < math.radians(0.3)
        assert np.all(np.sqrt(np.diag(result.covariance))[:2] < 0.02)


def test_scan_to_submap() -> None:
    rng = np.random.default_rng(4)
    world = load_world("room")
    path = room_path(3.0)
    matcher = ScanMatcher()
    submap = np.vstack([transform(p, synthetic_scan(world, p, rng).points()) for p in path[:30:5]])
    true = path[40]
    result = match(
        synthetic_scan(world, true, rng), submap, compose(true, Pose2D(-0.15, 0.1, -0.12)), matcher
    )
    assert result.converged
    assert math.hypot(result.pose.x - true.x, result.pose.y - true.y) < 0.01
    assert abs(result.pose.theta - true.theta) < math.radians(0.3)


def test_a_featureless_corridor_is_unconstrained_along_its_axis() -> None:
    rng = np.random.default_rng(5)
    world = corridor_world(40.0)
    a, b = corridor_path(3.0, start=15.0)[0], corridor_path(3.0, start=15.0)[8]
    truth = between(a, b)
    guess = compose(truth, Pose2D(0.12, -0.1, 0.08))
    result = ScanMatcher().match(synthetic_scan(world, b, rng), synthetic_scan(world, a, rng), guess)
    std = np.sqrt(np.linalg.eigvalsh(result.covariance))
    # one direction (the axis) is unconstrained, the other two are known to within a centimetre
    assert std[-1] > 10.0
    assert std[1] < 0.01
    axis = np.linalg.eigh(result.covariance)[1][:, -1]
    assert abs(axis[0]) > 0.99  # the unconstrained direction is x, the corridor's axis (a's frame ~ map)
    # across the axis and in heading the guess is corrected; along it, it is kept, not wandered off
    err = between(truth, result.pose)
    assert abs(err.theta) < math.radians(0.3)
    assert abs(result.pose.x - guess.x) < 0.06
    assert abs(err.y) < 0.02


def test_unrelated_scans_have_a_low_fitness() -> None:
    rng = np.random.default_rng(6)
    room = synthetic_scan(load_world("room"), Pose2D(2.4, 2.0, 0.0), rng)
    corridor = synthetic_scan(corridor_world(), Pose2D(10.0, 0.0, 0.0), rng)
    result = ScanMatcher().match(room, corridor)
    assert result.fitness < 0.5


def test_bad_input_is_one_clear_error() -> None:
    matcher = ScanMatcher()
    with pytest.raises(ConfigError, match="source"):
        matcher.match(np.zeros((5, 3)), np.zeros((5, 2)))
    with pytest.raises(ConfigError, match="target"):
        matcher.match(np.zeros((5, 2)), np.full((5, 2), np.nan))
    with pytest.raises(ConfigError, match="resolution"):
        ScanMatcher(resolution=0.0)
    with pytest.raises(ConfigError, match="initial"):
        matcher.match(np.zeros((5, 2)), np.zeros((5, 2)), Pose2D(math.nan, 0.0, 0.0))


def test_too_few_points_do_not_converge() -> None:
    result = ScanMatcher().match(
        np.array([[1.0, 0.0], [0.0, 1.0]]), np.random.default_rng(0).normal(size=(50, 2))
    )
    assert not result.converged
    assert result.fitness == 0.0
    assert np.all(np.diag(result.covariance) >= 1e3)


def test_the_scanner_mount_is_taken_into_account() -> None:
    """A scanner 0.1 m ahead and turned 30 degrees: matching its scans gives the base's motion."""
    rng = np.random.default_rng(7)
    world = load_world("room")
    mount = Pose2D(0.1, 0.0, math.radians(30.0))
    a, b = Pose2D(2.0, 2.0, 0.3), Pose2D(2.2, 2.1, 0.45)
    sa = replace(synthetic_scan(world, compose(a, mount), rng), mount=mount)
    sb = replace(synthetic_scan(world, compose(b, mount), rng), mount=mount)
    result = ScanMatcher().match(sb, sa)
    err = between(between(a, b), result.pose)
    assert math.hypot(err.x, err.y) < 0.01
    assert abs(err.theta) < math.radians(0.3)


def test_an_end_wall_in_range_constrains_the_axis() -> None:
    """Near the corridor's end the same matcher pins the axis down: degeneracy is not over-reported."""
    rng = np.random.default_rng(8)
    world = corridor_world(40.0)
    path = corridor_path(3.0, start=34.0)  # the end wall at x = 40 is 3-6 m ahead
    a, b = path[0], path[8]
    truth = between(a, b)
    result = ScanMatcher().match(
        synthetic_scan(world, b, rng), synthetic_scan(world, a, rng), compose(truth, Pose2D(0.12, -0.1, 0.08))
    )
    err = between(truth, result.pose)
    assert np.sqrt(np.linalg.eigvalsh(result.covariance)).max() < 0.02
    assert math.hypot(err.x, err.y) < 0.01


def _sharp_corridor(world_length: float, upto: float, rng: np.random.Generator) -> np.ndarray:
    """The corridor's returns within 2 m of poses every 0.25 m from x = 1 to ``upto`` (map frame): what
    an anchor submap holds, the end wall at x = 0 seen from 1 m."""
    world = corridor_world(world_length)
    clouds = []
    for x in np.arange(1.0, upto, 0.25):
        pose = Pose2D(float(x), 0.0, 0.0)
        pts = synthetic_scan(world, pose, rng, range_max=12.0, noise=0.0, noise_fraction=0.01).points()
        clouds.append(transform(pose, pts[np.hypot(pts[:, 0], pts[:, 1]) <= 2.0]))
    return np.vstack(clouds)


def test_a_far_end_wall_constrains_the_axis_as_far_as_its_noise_allows() -> None:
    """An A1 (1 % range noise) 10 m from the end wall it saw up close: the wall's dozen returns fix the
    axis to a few centimetres. One spread for all (the sharp side walls') claims about a centimetre;
    weighing each return by its own noise gives a standard deviation the errors stay within."""
    world = corridor_world(30.0)
    true = Pose2D(10.0, 0.1, 0.05)
    guess = compose(true, Pose2D(0.08, -0.05, 0.02))
    errors: dict[bool, list[float]] = {False: [], True: []}
    claimed: dict[bool, list[float]] = {False: [], True: []}
    for seed in range(8):
        rng = np.random.default_rng(seed)
        target = ScanMatcher().target(_sharp_corridor(30.0, 11.0, rng))
        source = synthetic_scan(world, true, rng, range_max=12.0, noise=0.0, noise_fraction=0.01)
        for weighted in (False, True):
            result = ScanMatcher().match(source, target, guess, weighted=weighted)
            assert result.unconstrained == 0
            assert result.converged or not weighted  # the unweighted one may wobble on the far returns
            assert abs(result.pose.y - true.y) < 0.01
            assert abs(result.pose.theta - true.theta) < math.radians(0.3)
            errors[weighted].append(result.pose.x - true.x)
            claimed[weighted].append(math.sqrt(result.covariance[0, 0]))
    spread = {w: math.sqrt(float(np.mean(np.square(e)))) for w, e in errors.items()}
    assert 0.02 < spread[True] < 0.08  # a few centimetres: the wall constrains the axis
    assert float(np.median(claimed[False])) < spread[False] / 2  # overconfident
    assert spread[True] <= float(np.median(claimed[True])) < 0.15  # honest


def test_a_weighted_match_takes_the_axis_from_the_end_wall_alone() -> None:
    """An anchor submap's side walls are many keyframes' returns at slightly wrong poses: their local
    lines tilt a little, and in the full normal equations their metres of returns pulled the axis
    (along which their normals barely lean) harder than the far end wall's dozen that measure it.
    Side walls zigzagging by 1.5 cm every 0.3 m leave the axis where straight ones put it."""
    world = corridor_world(30.0)
    true = Pose2D(10.0, 0.1, 0.05)
    guess = compose(true, Pose2D(0.08, -0.05, 0.02))
    moved = []
    for seed in range(8):
        rng = np.random.default_rng(seed)
        straight = _sharp_corridor(30.0, 11.0, rng)
        zigzag = straight.copy()
        side = np.abs(zigzag[:, 1]) > 0.8
        tooth = np.abs((zigzag[side, 0] + 0.1) % 0.6 - 0.3) / 0.3  # 0..1 and back every 0.6 m
        zigzag[side, 1] += 0.015 * tooth * np.sign(zigzag[side, 1])
        source = synthetic_scan(world, true, rng, range_max=12.0, noise=0.0, noise_fraction=0.01)
        flat = ScanMatcher().match(source, straight, guess, weighted=True)
        toothed = ScanMatcher().match(source, zigzag, guess, weighted=True)
        assert flat.unconstrained == toothed.unconstrained == 0
        moved.append(toothed.pose.x - flat.pose.x)
    assert math.sqrt(float(np.mean(np.square(moved)))) < 0.01  # before: 5.0 cm, up to 11.7


def test_a_weighted_match_mid_corridor_still_leaves_the_axis_free() -> None:
    """No end wall in range: the lines' slightly tilted normals add up to information along the axis
    that no return measured; the localisability check does not count it."""
    rng = np.random.default_rng(10)
    world = corridor_world(60.0)
    target = _sharp_corridor(60.0, 40.0, rng)
    true = Pose2D(26.0, -0.1, -0.03)
    guess = compose(true, Pose2D(0.1, 0.04, 0.02))
    source = synthetic_scan(world, true, rng, range_max=12.0, noise=0.0, noise_fraction=0.01)
    result = ScanMatcher().match(source, target, guess, weighted=True)
    assert result.converged
    assert result.unconstrained == 1
    axis = np.linalg.eigh(result.covariance)[1][:, -1]
    assert abs(axis[0]) > 0.99
    assert abs(result.pose.x - guess.x) < 0.01  # kept, not wandered off
    assert abs(result.pose.y - true.y) < 0.01


def test_a_wall_at_the_scanners_cut_off_is_left_out_of_a_weighted_match() -> None:
    """The scanner drops returns beyond its range_max: of a wall 11.8 m away (1 % noise, a 12 m
    cut-off) only the returns whose noise fell short are left, biased short. Given range_max, the
    weighted match leaves such pairs out, and with them the axis they alone constrained."""
    world = corridor_world(30.0)
    true = Pose2D(11.8, 0.1, 0.02)
    guess = compose(true, Pose2D(0.05, -0.03, 0.01))
    rng = np.random.default_rng(3)
    target = ScanMatcher().target(_sharp_corridor(30.0, 14.0, rng))
    source = synthetic_scan(world, true, rng, range_max=12.0, noise=0.0, noise_fraction=0.01)
    kept = ScanMatcher().match(source, target, guess, weighted=True)
    cut = ScanMatcher().match(source, target, guess, weighted=True, range_max=12.0)
    assert kept.unconstrained == 0
    assert cut.converged and cut.unconstrained == 1
    assert abs(cut.pose.x - guess.x) < 0.002  # kept where the guess put it (the free direction: x, nearly)
    assert abs(cut.pose.y - true.y) < 0.01
