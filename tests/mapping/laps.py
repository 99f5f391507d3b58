"""The SLAM driven on synthetic scans: a route's odometry and the scans at its true poses."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from benchmarks.slam_synthetic import RATE, synthetic_scan

from omnibot.mapping.slam import Slam
from omnibot.motion import Pose2D
from omnibot.sim import World


def drive(
    slam: Slam, world: World, truth: Sequence[Pose2D], odom: Sequence[Pose2D], seed: int
) -> list[Pose2D]:
    rng = np.random.default_rng(seed)
    for k, (true_pose, odom_pose) in enumerate(zip(truth, odom, strict=True)):
        slam.update(odom_pose, synthetic_scan(world, true_pose, rng, k / RATE), k / RATE)
    return [pose for _, pose in slam.trajectory()]
