"""Estimators registered by name (:data:`ESTIMATORS`, :func:`make_estimator`), so that a benchmark can
run several on the same telemetry, and replaying one over recorded samples."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from omnibot.errors import ConfigError
from omnibot.estimation.creep import SlipParameters
from omnibot.estimation.estimator import Estimator, PoseEstimator, SensorSample
from omnibot.estimation.seed002 import Seed002Estimator
from omnibot.motion import Estimate, Pose2D
from omnibot.robot import RobotDescription

EstimatorFactory = Callable[[RobotDescription, Pose2D | None, SlipParameters | None], Estimator]


def _pose_estimator(name: str, translation: str = "auto", heading: str = "fused") -> EstimatorFactory:
    def make(robot: RobotDescription, start: Pose2D | None, slip: SlipParameters | None) -> Estimator:
        return PoseEstimator(
            robot, translation=translation, heading=heading, start=start, name=name, slip=slip
        )

    return make


ESTIMATORS: dict[str, EstimatorFactory] = {
    "fused": _pose_estimator("fused", "auto", "auto"),
    "tracking+gyro": _pose_estimator("tracking+gyro", "tracking"),
    "tracking+raw-gyro": _pose_estimator("tracking+raw-gyro", "tracking", "gyro"),
    "encoders+gyro": _pose_estimator("encoders+gyro", "encoders"),
    "encoders+raw-gyro": _pose_estimator("encoders+raw-gyro", "encoders", "gyro"),
    "encoders": _pose_estimator("encoders", "encoders", "encoders"),
    "seed002": lambda r, s, _slip: Seed002Estimator(r, s),
}
"""Estimators by name: ``fused`` is the best the robot's sensors allow (tracking wheels if any, gyro
fused with the encoders if any, else the encoders' rotation); the others isolate one source each, for comparison. Every one but
``seed002`` (as written) takes the floor's slip coefficients for its driven-wheel encoders."""


def make_estimator(
    name: str, robot: RobotDescription, start: Pose2D | None = None, slip: SlipParameters | None = None
) -> Estimator:
    """The estimator registered as ``name`` for ``robot``, starting at ``start``, with the floor's
    wheel slip ``slip`` (None: uncorrected encoders)."""
    try:
        factory = ESTIMATORS[name]
    except KeyError:
        raise ConfigError(f"unknown estimator {name!r}; expected one of: {', '.join(ESTIMATORS)}") from None
    return factory(robot, start, slip)


def estimator_names(robot: RobotDescription | None = None) -> list[str]:
    """Registered names (those ``robot``'s sensors support, when given)."""
    if robot is None:
        return list(ESTIMATORS)
    out = []
    for name, factory in ESTIMATORS.items():
        try:
            factory(robot, None, None)
        except ConfigError:
            continue
        out.append(name)
    return out


def replay(estimator: Estimator, samples: Sequence[SensorSample]) -> list[Estimate]:
    """Run an estimator over recorded samples; the estimate after each."""
    return [estimator.update(s) for s in samples]
