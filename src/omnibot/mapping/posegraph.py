"""The SLAM's back end: a pose graph of the keyframes (gtsam ``Pose2`` nodes) and its optimiser.

Factors: a prior holding the first keyframe, odometry between consecutive keyframes (diagonal
sigmas), scan matches (their own covariance, so a direction the scans leave unconstrained is
carried by the odometry alone) and loop closures (through a Cauchy robust kernel, so one false
closure is down-weighted, not obeyed). ``optimizer="isam2"`` updates the graph incrementally on
every keyframe (with extra iterations after a closure); ``"lm"`` runs a batch Levenberg-Marquardt
after each closure and otherwise leaves the estimates as they are.
"""

from __future__ import annotations

import gtsam
import numpy as np
from numpy.typing import NDArray

from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]

OPTIMIZERS = ("isam2", "lm")
PRIOR_SIGMA = 1e-4
"""Sigma of the prior that holds the first keyframe where it is (m and rad)."""


def _pose2(p: Pose2D) -> gtsam.Pose2:
    return gtsam.Pose2(p.x, p.y, p.theta)


def _pose(p: gtsam.Pose2) -> Pose2D:
    return Pose2D(float(p.x()), float(p.y()), float(p.theta()))


class PoseGraph:
    """The keyframes' factor graph, its values and the optimiser (see the module docstring)."""

    def __init__(self, optimizer: str = "isam2") -> None:
        self.optimizer = optimizer
        self._graph = gtsam.NonlinearFactorGraph()  # every factor (batch optimiser)
        self._values = gtsam.Values()
        self._new_factors = gtsam.NonlinearFactorGraph()  # not yet given to iSAM2
        self._new_values = gtsam.Values()
        params = gtsam.ISAM2Params()
        params.setRelinearizeThreshold(0.01)
        params.relinearizeSkip = 1
        self._isam = gtsam.ISAM2(params)

    def add_node(self, key: int, pose: Pose2D) -> None:
        """Keyframe ``key`` with its first estimate."""
        self._values.insert(key, _pose2(pose))
        self._new_values.insert(key, _pose2(pose))

    def add_prior(self, key: int, pose: Pose2D) -> None:
        """Hold keyframe ``key`` at ``pose`` (:data:`PRIOR_SIGMA`)."""
        noise = gtsam.noiseModel.Isotropic.Sigma(3, PRIOR_SIGMA)
        self._add(gtsam.PriorFactorPose2(key, _pose2(pose), noise))

    def add_odometry(self, older: int, newer: int, relative: Pose2D, sigmas: FloatArray) -> None:
        """Keyframe ``newer`` seen from ``older`` by the odometry: independent (x, y, theta) ``sigmas``."""
        noise = gtsam.noiseModel.Diagonal.Sigmas(sigmas)
        self._add(gtsam.BetweenFactorPose2(older, newer, _pose2(relative), noise))

    def add_match(self, older: int, newer: int, relative: Pose2D, covariance: FloatArray) -> None:
        """Keyframe ``newer`` seen from ``older`` by a scan match, with the match's covariance."""
        noise = gtsam.noiseModel.Gaussian.Covariance(covariance)
        self._add(gtsam.BetweenFactorPose2(older, newer, _pose2(relative), noise))

    def add_robust(
        self, older: int, newer: int, relative: Pose2D, covariance: FloatArray, kernel_width: float
    ) -> None:
        """Keyframe ``newer`` seen from ``older`` by a loop closure: ``covariance`` through a Cauchy
        kernel of ``kernel_width``."""
        kernel = gtsam.noiseModel.mEstimator.Cauchy.Create(kernel_width)
        noise = gtsam.noiseModel.Robust.Create(kernel, gtsam.noiseModel.Gaussian.Covariance(covariance))
        self._add(gtsam.BetweenFactorPose2(older, newer, _pose2(relative), noise))

    def optimise(self, closed: bool, count: int) -> list[Pose2D] | None:
        """The estimates of keyframes ``0 .. count - 1`` after the factors and nodes added since the
        last call (``closed``: a loop closure among them); None where the optimiser has not run
        (``"lm"`` without a closure)."""
        if self.optimizer == "isam2":
            self._isam.update(self._new_factors, self._new_values)
            for _ in range(3 if closed else 0):
                self._isam.update()
            result = self._isam.calculateEstimate()
        elif closed:
            params = gtsam.LevenbergMarquardtParams()
            result = gtsam.LevenbergMarquardtOptimizer(self._graph, self._values, params).optimize()
        else:
            result = None
        self._new_factors = gtsam.NonlinearFactorGraph()
        self._new_values = gtsam.Values()
        if result is None:
            return None
        self._values = result
        return [_pose(result.atPose2(k)) for k in range(count)]

    def _add(self, factor: gtsam.NonlinearFactor) -> None:
        self._graph.add(factor)
        self._new_factors.add(factor)
