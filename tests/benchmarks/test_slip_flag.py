"""The slip-flag benchmark's truth and scoring (no simulation: the runs are the benchmark's)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks import slip_flag
from omnibot.robot import load_robot


def test_the_truth_is_one_wheels_nonrigid_slip_and_the_old_rule_needs_twelve_counts() -> None:
    robot = load_robot("omni4")
    J = np.asarray(robot.wheel_matrix, dtype=float)
    rim = robot.wheels[0].radius
    rigid = (J @ np.array([0.2, -0.1, 0.5])) * rim  # m/s of slip that a rigid motion explains
    one = np.array([0.0, 0.05, 0.0, 0.0])
    assert slip_flag.nonrigid_slip(robot, np.array([rigid, rigid + one])) == pytest.approx([0.0, 0.05])
    count = 2.0 * math.pi / robot.encoders.motors[0].counts_per_rev
    assert not slip_flag.old_rule(robot, np.array([0.0, 11.5, 0.0, 0.0]) * count)
    assert slip_flag.old_rule(robot, np.array([0.0, 12.5, 0.0, 0.0]) * count)
    assert slippery_grip(slip_flag.slippery("omni4", 1, 0.2)) == [1.0, 0.2, 1.0, 1.0]


def slippery_grip(robot: object) -> list[float]:
    return [w.rollers.grip for w in robot.wheels]  # type: ignore[attr-defined]


def test_score_counts_episodes_delays_and_quiet_false_alarms() -> None:
    t = np.arange(100) * 0.01
    truth = np.zeros(100)
    truth[20:30] = truth[60:65] = 0.1  # two episodes
    moving = truth.copy()
    flag = np.zeros(100, dtype=bool)
    flag[23:32] = True  # the first found 30 ms in; the second missed
    flag[90] = True  # a quiet sample flagged
    s = slip_flag.score(t, flag, truth, moving, hold=0.0)
    assert (s.episodes, s.found) == (2, 1)
    assert s.delay == pytest.approx(0.03)
    quiet = 100 - len(set(range(10, 40)) | set(range(50, 75)))
    assert s.false_alarms == pytest.approx(1 / quiet, rel=0.1)
    assert s.flagged == pytest.approx(0.10)
