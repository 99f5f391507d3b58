"""The pose graph on its own: odometry chained from the prior, iSAM2 at once, batch LM after a closure."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.mapping.posegraph import PoseGraph
from omnibot.mapping.se2 import compose
from omnibot.motion import Pose2D

START = Pose2D(1.0, 2.0, 0.3)
STEP = Pose2D(0.5, 0.1, math.pi / 6)
SIGMAS = np.array([0.01, 0.01, 0.01])


def chain(graph: PoseGraph) -> None:
    """Three keyframes: the first held, two odometry steps, each node's first guess off by cm."""
    graph.add_prior(0, START)
    graph.add_node(0, START)
    for k in (1, 2):
        graph.add_odometry(k - 1, k, STEP, SIGMAS)
        guess = compose(START, STEP) if k == 1 else compose(compose(START, STEP), STEP)
        graph.add_node(k, Pose2D(guess.x + 0.03, guess.y - 0.02, guess.theta + 0.01))


def assert_chained(estimates: list[Pose2D], tolerance: float) -> None:
    want = [START, compose(START, STEP), compose(compose(START, STEP), STEP)]
    for got, pose in zip(estimates, want, strict=True):
        assert (got.x, got.y, got.theta) == pytest.approx((pose.x, pose.y, pose.theta), abs=tolerance)


def test_isam2_places_every_keyframe_on_the_odometry_chain() -> None:
    """One iSAM2 update is one Gauss-Newton step: from guesses 3 cm off, within 0.1 mm (2e-5 m seen)."""
    graph = PoseGraph("isam2")
    chain(graph)
    estimates = graph.optimise(closed=False, count=3)
    assert estimates is not None
    assert_chained(estimates, 1e-4)


def test_batch_lm_runs_only_after_a_closure() -> None:
    graph = PoseGraph("lm")
    chain(graph)
    assert graph.optimise(closed=False, count=3) is None
    estimates = graph.optimise(closed=True, count=3)
    assert estimates is not None
    assert_chained(estimates, 1e-6)  # iterated to convergence


def test_a_robust_closure_that_contradicts_the_odometry_is_down_weighted() -> None:
    """Keyframe 2 claimed 0.5 m off where the odometry puts it, as confidently as each odometry step:
    a plain Gaussian factor would pull it 33 cm, the Cauchy kernel leaves it within 5 mm (3.7 seen)."""
    graph = PoseGraph("lm")
    chain(graph)
    truth = compose(compose(START, STEP), STEP)
    claim = compose(compose(STEP, STEP), Pose2D(0.5, 0.0, 0.0))
    graph.add_robust(0, 2, claim, np.diag(SIGMAS**2), kernel_width=3.0)
    estimates = graph.optimise(closed=True, count=3)
    assert estimates is not None
    off = math.hypot(estimates[2].x - truth.x, estimates[2].y - truth.y)
    assert off < 0.005
