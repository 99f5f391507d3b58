"""The wheel-slip step of ``omnibot calibrate``: the slip runs of :mod:`omnibot.navigation.slipcal`
measured by the session's truth source, one fit per floor.

Driven-wheel encoders over-read by the creep of the wheels that push (on carpet 5-13 % on omni4);
the fitted coefficients go to the calibration file (``surfaces.<floor>.odometry.slip``), where
``omnibot follow --calibration`` and the estimators take them. The runs use the wheel-speed loop and
the binary protocol (as following does); the session puts the controller back in open loop after.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from omnibot.calibration.runs import STRAIGHT, RunInfo
from omnibot.calibration.truth import TruthSource
from omnibot.client import RobotClient
from omnibot.navigation import Navigator, SlipCalibration, calibrate_slip
from omnibot.robot import RobotDescription
from omnibot.runtime import RuntimeRecording

SLIP_SPEED_MAX = 0.8
"""m/s: the slip runs' speed cap (creep hardly depends on speed; the runs must fit a room)."""


class SourceRuns:
    """A calibration :class:`TruthSource` as the slip runs' :class:`~omnibot.navigation.slipcal.RunTruth`."""

    def __init__(self, source: TruthSource) -> None:
        self.source = source
        self.live = source.live

    def start(self) -> object:
        """Mark the start of a slip run with the truth source."""
        return self.source.mark()

    def displacement(self, mark: object, course: float) -> tuple[float, float] | None:
        """The measured displacement of a slip run on ``course`` (rad) in the start's body frame, m; None
        when the source cannot measure it."""
        run = RunInfo(STRAIGHT, f"slip run on course {math.degrees(course):.0f} deg", course)
        if not self.source.can(run):
            return None
        motion = self.source.measure(mark, run)
        if motion is None:
            return None
        if motion.x is not None and motion.y is not None:
            return (motion.x, motion.y)
        if motion.along is not None:  # only the distance: along the commanded course
            return (motion.along * math.cos(course), motion.along * math.sin(course))
        return None


def slip_speed(robot: RobotDescription) -> float:
    """The slip runs' speed: the middle of the robot's speed range, at most :data:`SLIP_SPEED_MAX`."""
    lim = robot.limits
    return min(SLIP_SPEED_MAX, 0.5 * (lim.speed_min + lim.speed_max))


def slip_step(
    client: RobotClient,
    robot: RobotDescription,
    source: TruthSource,
    bar: Any = None,
    recording: RuntimeRecording | None = None,
) -> SlipCalibration:
    """Drive the slip runs on the floor the robot stands on and fit its wheel slip (the runs'
    runtime recorded in ``recording``, the command's ``--log``)."""
    nav = Navigator(client, robot, recording=recording)
    update: Callable[[int, int], object] | None = None
    if bar is not None:
        update = lambda done, total: bar.update(1)  # noqa: E731
    try:
        nav.prepare()
        return calibrate_slip(nav, SourceRuns(source), speed=slip_speed(robot), progress=update)
    finally:
        nav.close()
